#include "sdlighting/gauss_quadrature.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sd {
namespace {

// ∫_0^1 s^j (1−s)^σ ds = B(j+1, σ+1), in long double: log-gammas near 10⁵ would cost double
// its last digits.
double beta_moment(int j, double sigma) {
  const long double s = sigma;
  return static_cast<double>(std::exp(std::lgamma(j + 1.0L) + std::lgamma(s + 1.0L) - std::lgamma(j + s + 2.0L)));
}

TEST(GaussQuadrature, JacobiRuleIsExactToDegree2nMinus1) {
  for (double sigma : {0.0, 1.0, 8.0, 1000.0, 1e4}) {
    for (int n : {1, 3, 8}) {
      const Rule1D rule = gauss_rule(jacobi_recurrence_unit_interval(sigma, n), n);
      for (int j = 0; j <= 2 * n - 1; ++j) {
        double sum = 0.0;
        for (int i = 0; i < n; ++i) sum += rule.weights[i] * std::pow(rule.nodes[i], j);
        EXPECT_NEAR(sum / beta_moment(j, sigma), 1.0, 1e-12) << "sigma=" << sigma << " n=" << n << " j=" << j;
      }
      for (int i = 0; i < n; ++i) EXPECT_GT(rule.weights[i], 0.0);
    }
  }
}

TEST(GaussQuadrature, RadauRuleKeepsTheFixedNodeAndIsExactTo2nMinus2) {
  for (double sigma : {0.0, 1.0, 32.0, 1000.0}) {
    const int n = 5;
    const Rule1D rule = gauss_radau_rule(jacobi_recurrence_unit_interval(sigma, n), n, 0.0);
    int fixed = 0;
    for (int i = 0; i < n; ++i) {
      fixed += rule.nodes[i] == 0.0;
      EXPECT_GT(rule.weights[i], 0.0);
    }
    EXPECT_EQ(fixed, 1);
    for (int j = 0; j <= 2 * n - 2; ++j) {
      double sum = 0.0;
      for (int i = 0; i < n; ++i) sum += rule.weights[i] * std::pow(rule.nodes[i], j);
      EXPECT_NEAR(sum / beta_moment(j, sigma), 1.0, 1e-11) << sigma << " " << j;
    }
  }
}

TEST(GaussQuadrature, DiscreteRecurrenceReproducesTheClosedForm) {
  // Small σ only: for large σ the rule's tail weights (below 1e-20) carry only absolute accuracy,
  // and high-degree recurrence coefficients amplify that, whatever the algorithm.
  for (double sigma : {0.0, 1.0, 3.0}) {
    const Recurrence exact = jacobi_recurrence_unit_interval(sigma, 30);
    const Rule1D rule = gauss_rule(exact, 30);
    const Recurrence lanczos = discrete_recurrence(rule.nodes, rule.weights, 20);
    for (int k = 0; k < 20; ++k) {
      EXPECT_NEAR(lanczos.alpha[k], exact.alpha[k], 1e-13 * (1.0 + exact.alpha[k])) << sigma << " " << k;
      EXPECT_NEAR(lanczos.beta[k] / exact.beta[k], 1.0, 1e-11) << sigma << " " << k;
    }
  }
}

TEST(GaussQuadrature, OrthonormalPolynomialsAndDerivatives) {
  const Recurrence rec = jacobi_recurrence_unit_interval(3.0, 12);
  const Rule1D rule = gauss_rule(rec, 12);
  const int n = 10;
  std::vector<double> p(n), dp(n), plus(n), minus(n);
  std::vector<double> gram(n * n, 0.0);
  for (size_t i = 0; i < rule.nodes.size(); ++i) {
    orthonormal_polynomials(rec, n, rule.nodes[i], p.data(), nullptr);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) gram[a * n + b] += rule.weights[i] * p[a] * p[b];
  }
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) EXPECT_NEAR(gram[a * n + b], a == b ? 1.0 : 0.0, 1e-12);
  const double x = 0.3, h = 1e-6;
  orthonormal_polynomials(rec, n, x, p.data(), dp.data());
  orthonormal_polynomials(rec, n, x + h, plus.data(), nullptr);
  orthonormal_polynomials(rec, n, x - h, minus.data(), nullptr);
  for (int k = 0; k < n; ++k) EXPECT_NEAR(dp[k], (plus[k] - minus[k]) / (2 * h), 1e-5 * (1.0 + std::abs(dp[k])));
}

TEST(GaussQuadrature, RejectsTooFewCoefficientsOrPoints) {
  const Recurrence rec = jacobi_recurrence_unit_interval(1.0, 3);
  EXPECT_THROW(gauss_rule(rec, 4), std::invalid_argument);
  EXPECT_THROW(discrete_recurrence({0.1, 0.2}, {1.0, 0.0}, 2), std::invalid_argument);
  EXPECT_THROW(jacobi_recurrence_unit_interval(-1.0, 3), std::invalid_argument);
}

}  // namespace
}  // namespace sd
