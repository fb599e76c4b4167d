// Real Gaunt coefficients: integrals of triple products of real SH (spherical_harmonics.h).
#pragma once

#include <vector>

namespace sd {

/// One non-zero coefficient G = ∫ y_a y_b y_c dμ, with flat SH indices a, b, c.
struct GauntEntry {
  int a;
  int b;
  int c;
  double value;
};

/// Every non-zero real Gaunt coefficient with l_a <= order_a, l_b <= order_b, l_c <= order_c,
/// sorted by (a, b, c). These are the coupling coefficients C of PRT formula (10) (the seed's
/// Lemma 1.2): y_a y_b = Σ_c G_abc y_c. Computed by an exact product quadrature, restricted to the
/// selection rules (|l_a - l_b| <= l_c <= l_a + l_b, l_a + l_b + l_c even, and the rule on m),
/// so exact to rounding. Throws std::invalid_argument for negative orders, or for orders whose
/// table would exceed kMaxCallBytes (counted before it is built: (64, 64, 64) would need ~20 GB).
std::vector<GauntEntry> gaunt_coefficients(int order_a, int order_b, int order_c);

}  // namespace sd
