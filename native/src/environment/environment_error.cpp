// The error measures that choose the order s (environment_error.h), from the band energies of the
// map's reference projection (projection.cpp).
#include "sdlighting/environment_error.h"

#include "environment/environment_detail.h"
#include "sdlighting/limits.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace sd {

double low_frequency_error(const Environment& environment, int order, int channel) {
  check_order("Environment::low_frequency_error: order", order, kMaxEnergyOrder);
  check_channel("Environment::low_frequency_error", channel);
  const ReferenceProjection& reference = reference_projection(environment);
  const double norm2 = reference.norm_squared[channel];
  if (!(norm2 > 0.0)) return 0.0;
  double kept = 0.0;
  for (int l = 0; l <= order; ++l) kept += reference.energies[4 * l + channel];
  return std::sqrt(std::max(0.0, norm2 - kept) / norm2);
}

double lobe_filtered_error(const Environment& environment, const ZonalLobe& lobe, int order) {
  check_order("Environment::lobe_filtered_error: order", order, kMaxEnergyOrder);
  const std::vector<double> w = lobe.coefficients(kMaxEnergyOrder);
  const auto& energies = reference_projection(environment).energies;
  double missed = 0.0, total = 0.0;  // summed separately: no cancellation
  for (int l = 0; l <= kMaxEnergyOrder; ++l) {
    const double term = w[l] * w[l] * energies[4 * l + kLuminance];
    total += term;
    if (l > order) missed += term;
  }
  if (!(total > 0.0)) return 0.0;
  return std::sqrt(missed / total);
}

int smallest_order(const Environment& environment, const ZonalLobe& lobe, double target_error, int max_order) {
  check_order("Environment::smallest_order: max_order", max_order, kMaxEnergyOrder);
  if (!(target_error >= 0.0) || !std::isfinite(target_error)) {
    throw std::invalid_argument("Environment::smallest_order: target_error must be finite and >= 0");
  }
  for (int s = 0; s <= max_order; ++s) {
    if (lobe_filtered_error(environment, lobe, s) <= target_error) return s;
  }
  return -1;
}

}  // namespace sd
