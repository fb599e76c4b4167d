// The Funk–Hecke factors of the Phong lobe in closed form, the reference of the zonal-lobe tests
// (test_zonal_lobe.cpp, the randomized test_sh_properties.cpp).
#pragma once

#include <cmath>

namespace sd::test {

// ŵ_l = (σ+1) ∫_0^1 t^σ P_l(t) dt = (σ+1) √π 2^(−σ−1) Γ(1+σ) / (Γ(1+σ/2−l/2) Γ(3/2+σ/2+l/2))
// (Gradshteyn–Ryzhik 7.126.2), in long double through log-gamma so that σ = 10⁴ neither
// overflows nor loses digits.
inline double closed_form_factor(double sigma, int l) {
  const long double s = sigma;
  const long double x1 = 1.0L + s / 2 - l / 2.0L;
  if (x1 <= 0.0L && x1 == std::floor(x1)) return 0.0;  // 1/Γ vanishes at poles
  const long double x2 = 1.5L + s / 2 + l / 2.0L;
  const long double log_value = std::log(s + 1) + 0.5L * std::log(static_cast<long double>(M_PI)) -
                                (s + 1) * std::log(2.0L) + std::lgamma(1 + s) - std::lgamma(x1) - std::lgamma(x2);
  const long double sign = (x1 < 0.0L && static_cast<long long>(std::floor(x1)) % 2 != 0) ? -1.0L : 1.0L;
  return static_cast<double>(sign * std::exp(log_value));
}

}  // namespace sd::test
