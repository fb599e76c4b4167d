#include "sdlighting/zonal_lobe.h"

#include "util/number_string.h"

#include <cmath>
#include <stdexcept>

namespace sd {

ZonalLobe ZonalLobe::phong(double exponent) {
  if (!(exponent >= 0.0 && exponent <= kMaxPhongExponent)) {
    throw std::invalid_argument("Phong exponent must be in [0, " +
                                std::to_string(static_cast<long long>(kMaxPhongExponent)) + "], got " +
                                number_string(exponent));
  }
  return ZonalLobe{exponent};
}

ZonalLobe ZonalLobe::from_name(const std::string& name, double exponent) {
  if (name == "lambert") return lambert();
  if (name == "phong") return phong(exponent);
  throw std::invalid_argument("unknown lobe '" + name + "' (expected 'lambert' or 'phong')");
}

double ZonalLobe::value(double t) const {
  if (t < 0.0) return 0.0;
  return (2.0 * exponent + 2.0) * std::pow(t, exponent);
}

std::vector<double> ZonalLobe::coefficients(int lmax) const {
  if (lmax < 0) throw std::invalid_argument("lmax must be >= 0");
  const double s = exponent;
  std::vector<double> w(lmax + 1);
  w[0] = 1.0;
  if (lmax >= 1) w[1] = (s + 1.0) / (s + 2.0);
  for (int l = 0; l + 2 <= lmax; ++l) w[l + 2] = w[l] * (s - l) / (s + l + 3.0);
  return w;
}

double truncated_lobe(const std::vector<double>& coefficients, int order, double t) {
  double p_prev = 0.0, p = 1.0, sum = 0.0;
  for (int l = 0; l <= order; ++l) {
    sum += (2.0 * l + 1.0) * coefficients[l] * p;
    const double next = ((2.0 * l + 1.0) * t * p - l * p_prev) / (l + 1.0);
    p_prev = p;
    p = next;
  }
  return sum;
}

}  // namespace sd
