#include "sdlighting/gauss_quadrature.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/zonal_lobe.h"
#include "zonal_lobe_closed_form.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace sd {
namespace {

constexpr double kExact = 1e-12;

using test::closed_form_factor;

TEST(ZonalLobe, LambertFactors) {
  const auto w = ZonalLobe::lambert().coefficients(6);
  const double expected[] = {1.0, 2.0 / 3.0, 0.25, 0.0, -1.0 / 24.0, 0.0, 1.0 / 64.0};
  for (int l = 0; l <= 6; ++l) EXPECT_NEAR(w[l], expected[l], kExact) << "l=" << l;
}

TEST(ZonalLobe, PhongFactorsMatchClosedFormUpToSigma1e4) {
  for (double sigma : {0.0, 0.5, 1.0, 7.3, 8.0, 32.0, 1000.0, 1e4}) {
    const auto w = ZonalLobe::phong(sigma).coefficients(64);
    for (int l = 0; l <= 64; ++l) {
      EXPECT_NEAR(w[l], closed_form_factor(sigma, l), kExact) << "sigma=" << sigma << " l=" << l;
    }
  }
}

TEST(ZonalLobe, FactorsMatchQuadratureOfTheLobe) {
  // Gauss–Jacobi in s = 1 − t integrates t^σ P_l(t) exactly: an independent path.
  for (double sigma : {1.0, 8.0, 100.0}) {
    const int n = 20;
    const Rule1D rule = gauss_rule(jacobi_recurrence_unit_interval(sigma, n), n);
    const auto w = ZonalLobe::phong(sigma).coefficients(30);
    for (int l = 0; l <= 30; ++l) {
      double integral = 0.0;
      for (int i = 0; i < n; ++i) integral += rule.weights[i] * legendre(l, 1.0 - rule.nodes[i]);
      EXPECT_NEAR((sigma + 1.0) * integral, w[l], kExact);
    }
  }
}

TEST(ZonalLobe, ValueIsNormalised) {
  const int n = 40;
  const Rule1D rule = gauss_rule(jacobi_recurrence_unit_interval(0.0, n), n);  // Legendre on [0, 1]
  for (double sigma : {0.0, 1.0, 3.5, 20.0}) {
    const ZonalLobe lobe = ZonalLobe::phong(sigma);
    double mass = 0.0;  // ½ ∫_{-1}^{1} w dt, w = 0 below t = 0
    for (int i = 0; i < n; ++i) mass += 0.5 * rule.weights[i] * lobe.value(rule.nodes[i]);
    EXPECT_NEAR(mass, 1.0, 1e-9) << sigma;  // σ = 3.5 is not a polynomial: quadrature error
  }
  EXPECT_EQ(ZonalLobe::lambert().value(-0.5), 0.0);
  EXPECT_NEAR(ZonalLobe::lambert().value(0.5), 2.0, kExact);
}

TEST(ZonalLobe, TruncatedLobeKeepsOnlyLowBands) {
  const auto w = ZonalLobe::phong(8.0).coefficients(6);
  const int n = 12;
  const Rule1D rule = gauss_rule(jacobi_recurrence_unit_interval(0.0, n), n);
  for (int l = 0; l <= 8; ++l) {
    double projection = 0.0;  // ½ ∫_{-1}^{1} w̃ P_l dt
    for (int i = 0; i < n; ++i) {
      const double t = 2.0 * rule.nodes[i] - 1.0;
      projection += rule.weights[i] * truncated_lobe(w, 4, t) * legendre(l, t);
    }
    EXPECT_NEAR(projection, l <= 4 ? w[l] : 0.0, kExact) << l;
  }
}

TEST(ZonalLobe, RejectsBadInput) {
  EXPECT_THROW(ZonalLobe::phong(-1.0), std::invalid_argument);
  EXPECT_THROW(ZonalLobe::phong(2e4), std::invalid_argument);
  EXPECT_THROW(ZonalLobe::phong(std::nan("")), std::invalid_argument);
  EXPECT_THROW(ZonalLobe::from_name("ggx", 1.0), std::invalid_argument);
  EXPECT_THROW(ZonalLobe::lambert().coefficients(-1), std::invalid_argument);
}

}  // namespace
}  // namespace sd
