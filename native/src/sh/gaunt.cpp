#include "sdlighting/gaunt.h"

#include "sdlighting/gauss_quadrature.h"
#include "sdlighting/limits.h"
#include "sdlighting/spherical_harmonics.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace sd {
namespace {

constexpr double kKeepThreshold = 1e-13;

// (1/2π) ∫ Φ_ma Φ_mb Φ_mc dφ with Φ_m = cos(mφ) (m > 0), 1 (m = 0), sin(|m|φ) (m < 0), the φ
// factors of the convention's y_lm. Expanding each factor into e^{±i|m|φ} leaves a sum of dyadic
// rationals, so the φ part of the product rule is taken exactly rather than sampled.
double azimuthal_integral(int ma, int mb, int mc) {
  const int ms[3] = {ma, mb, mc};
  int sines = 0;
  for (int m : ms) sines += m < 0;
  // An odd number of sines is odd in φ.
  if (sines % 2 == 1) return 0.0;
  double total = 0.0;
  for (int signs = 0; signs < 8; ++signs) {
    int frequency = 0;
    double coefficient = 1.0;
    bool duplicate = false;
    for (int k = 0; k < 3; ++k) {
      const int s = (signs >> k) & 1 ? -1 : 1;
      if (ms[k] == 0) {
        // The constant has a single exponential; count it under s = +1 only.
        if (s < 0) duplicate = true;
        continue;
      }
      frequency += s * std::abs(ms[k]);
      // cos = (e⁺ + e⁻)/2, sin = (e⁺ − e⁻)/(2i); the i's of two sines give the overall −1 below.
      coefficient *= ms[k] > 0 ? 0.5 : 0.5 * s;
    }
    if (!duplicate && frequency == 0) total += coefficient;
  }
  return sines == 2 ? -total : total;
}

}  // namespace

std::vector<GauntEntry> gaunt_coefficients(int order_a, int order_b, int order_c) {
  if (order_a < 0 || order_b < 0 || order_c < 0) {
    throw std::invalid_argument("gaunt_coefficients: orders must be non-negative");
  }
  // At most two m_c per (a, b, l_c) pass the m rule below (the parity of the sines fixes the sign).
  double most_entries = 0.0;
  for (int la = 0; la <= order_a; ++la) {
    for (int lb = 0; lb <= order_b; ++lb) {
      const int lc_end = std::min(la + lb, order_c);
      if (lc_end >= std::abs(la - lb)) most_entries += 2.0 * (2 * la + 1) * (2 * lb + 1) * ((lc_end - std::abs(la - lb)) / 2 + 1);
    }
  }
  check_allocation("gaunt_coefficients(" + std::to_string(order_a) + ", " + std::to_string(order_b) + ", " +
                       std::to_string(order_c) + ")",
                   most_entries * sizeof(GauntEntry));
  // y_lm = Θ_l|m|(z) Φ_m(φ), so the product rule (Gauss–Legendre in z × any exact rule in φ)
  // factorises: each coefficient is an exact z-sum times the azimuthal_integral. For a triple
  // allowed by the m rule, |ma| + |mb| + |mc| is even, so Θ_a Θ_b Θ_c is a polynomial in z of
  // degree l_a + l_b + l_c and n Gauss points with 2n − 1 >= that degree integrate it exactly.
  const int max_lc = std::min(order_c, order_a + order_b);
  const int degree = order_a + order_b + max_lc;
  const int n = degree / 2 + 1;
  const Rule1D rule = gauss_rule(jacobi_recurrence_unit_interval(0.0, n), n);

  // Θ_l|m| at every z node, from sh_basis at φ = 0 where Φ_m = 1 for m >= 0. Stored node-minor
  // so that each triple is one contiguous dot product over the nodes.
  const int basis_order = std::max({order_a, order_b, max_lc});
  std::vector<double> theta(size_t(sh_count(basis_order)) * n);
  std::vector<double> y(sh_count(basis_order));
  for (int q = 0; q < n; ++q) {
    const double s = rule.nodes[q];
    // 1 − z² = 4 s (1 − s) keeps sin θ accurate for the nodes crowding the poles.
    const double z = 1.0 - 2.0 * s, r = 2.0 * std::sqrt(std::max(0.0, s * (1.0 - s)));
    sh_basis(basis_order, glm::dvec3(r, 0.0, z), y.data());
    for (int l = 0; l <= basis_order; ++l) {
      for (int m = -l; m <= l; ++m) {
        theta[size_t(sh_index(l, m)) * n + q] = y[sh_index(l, std::abs(m))];
      }
    }
  }
  // w_q Θ_a Θ_b, formed once per (a, b) and reused for every c.
  std::vector<double> weighted_ab(n);

  std::vector<GauntEntry> entries;
  for (int la = 0; la <= order_a; ++la) {
    for (int ma = -la; ma <= la; ++ma) {
      const int a = sh_index(la, ma);
      const double* theta_a = &theta[size_t(a) * n];
      for (int lb = 0; lb <= order_b; ++lb) {
        for (int mb = -lb; mb <= lb; ++mb) {
          const int b = sh_index(lb, mb);
          const double* theta_b = &theta[size_t(b) * n];
          for (int q = 0; q < n; ++q) weighted_ab[q] = rule.weights[q] * theta_a[q] * theta_b[q];

          // |mc| ∈ {|ma| + |mb|, ||ma| − |mb||}, each with both signs, in increasing order so
          // that entries come out sorted by c.
          const int sum = std::abs(ma) + std::abs(mb), diff = std::abs(std::abs(ma) - std::abs(mb));
          int candidates[4] = {-sum, -diff, diff, sum};
          int count = 4;
          count = int(std::unique(candidates, candidates + count) - candidates);
          double phi_factor[4];
          for (int k = 0; k < count; ++k) phi_factor[k] = azimuthal_integral(ma, mb, candidates[k]);

          const int lc_begin = std::abs(la - lb), lc_end = std::min(la + lb, order_c);
          for (int lc = lc_begin; lc <= lc_end; lc += 2) {
            for (int k = 0; k < count; ++k) {
              const int mc = candidates[k];
              if (std::abs(mc) > lc || phi_factor[k] == 0.0) continue;
              const int c = sh_index(lc, mc);
              const double* theta_c = &theta[size_t(c) * n];
              double z_integral = 0.0;
              for (int q = 0; q < n; ++q) z_integral += weighted_ab[q] * theta_c[q];
              const double value = z_integral * phi_factor[k];
              if (std::abs(value) > kKeepThreshold) entries.push_back({a, b, c, value});
            }
          }
        }
      }
    }
  }
  return entries;
}

}  // namespace sd
