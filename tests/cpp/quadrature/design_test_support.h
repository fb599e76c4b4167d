// Checks shared by the design tests (test_spherical_designs.cpp, the randomized
// test_design_properties.cpp).
#pragma once

#include "sdlighting/spherical_design.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/zonal_lobe.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sd::test {

// Checks a design of a lobe independently of the builder's own certificate: its SH moments must
// be the Funk–Hecke values ŵ_l sqrt(2l+1) δ_m0 from the factor recurrence.
inline void expect_lobe_design(const SphericalDesign& design, const ZonalLobe& lobe, int degree) {
  ASSERT_GT(design.size(), 0);
  EXPECT_EQ(design.degree, degree);
  EXPECT_LE(design.residual, kDesignTolerance);
  for (double w : design.weights) EXPECT_GT(w, 0.0);
  EXPECT_NEAR(std::accumulate(design.weights.begin(), design.weights.end(), 0.0), 1.0, 1e-12);
  const auto w_hat = lobe.coefficients(degree);
  const auto moments = design_moments(design.nodes, design.weights, degree);
  double error = 0.0;
  for (int l = 0; l <= degree; ++l)
    for (int m = -l; m <= l; ++m) {
      const double expected = m == 0 ? w_hat[l] * std::sqrt(2.0 * l + 1.0) : 0.0;
      error = std::max(error, std::abs(moments[sh_index(l, m)] - expected));
    }
  EXPECT_LT(error, kDesignTolerance) << "sigma=" << lobe.exponent << " degree=" << degree;
  for (const auto& x : design.nodes) {
    EXPECT_NEAR(glm::length(x), 1.0, 1e-14);
    EXPECT_GE(x.z, -1e-15) << "node below the lobe's horizon";
  }
}

}  // namespace sd::test
