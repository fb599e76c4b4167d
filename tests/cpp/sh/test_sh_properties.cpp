// Randomized properties of the SH rotation and the zonal lobes (issue 12, item 8): fixed seeds,
// each case's seed in the failure message (SCOPED_TRACE), random orders, rotations (also rounded
// to float32, as the add-on's matrices arrive) and non-integer Phong exponents in [0, 10⁴].
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/zonal_lobe.h"
#include "sdtesting/sphere.h"
#include "zonal_lobe_closed_form.h"

#include <gtest/gtest.h>
#include <glm/mat3x3.hpp>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace sd {
namespace {

constexpr double kExact = 1e-11;  // relative to the coefficients' norm: exact up to rounding
constexpr int kCases = 40;

using test::random_direction;
using test::random_rotation;

std::vector<double> random_coefficients(int count, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::vector<double> c(count);
  for (double& v : c) v = normal(rng);
  return c;
}

double norm(const std::vector<double>& c) {
  double sum = 0.0;
  for (double v : c) sum += v * v;
  return std::sqrt(sum);
}

// A random rotation, half the time rounded to float32 entries (not exactly orthogonal).
glm::dmat3 random_test_rotation(std::mt19937_64& rng) {
  glm::dmat3 r = random_rotation(rng);
  if (rng() % 2) {
    for (int col = 0; col < 3; ++col)
      for (int row = 0; row < 3; ++row) r[col][row] = static_cast<float>(r[col][row]);
  }
  return r;
}

// Channel c of RGB coefficients evaluated at x.
double evaluate(const std::vector<double>& c, int order, int channels, int channel, const glm::dvec3& x) {
  const std::vector<double> y = sh_basis(order, x);
  double sum = 0.0;
  for (int i = 0; i < sh_count(order); ++i) sum += c[channels * i + channel] * y[i];
  return sum;
}

TEST(ShProperties, RotatedShIsTheFunctionAtRotatedPoints) {  // L(g x) = Σ rotated_sh(L, g)_i y_i(x)
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(seed);
    const int order = static_cast<int>(rng() % 17), channels = 1 + static_cast<int>(rng() % 3);
    const glm::dmat3 g = random_test_rotation(rng);
    const std::vector<double> c = random_coefficients(sh_count(order) * channels, rng);
    const std::vector<double> rotated = rotated_sh(c, order, g, channels);
    // A float32 g is used through its nearest rotation (ShRotation), so compare at that accuracy.
    const double tolerance = 1e-5 * norm(c);
    for (int point = 0; point < 8; ++point) {
      const glm::dvec3 x = random_direction(rng);
      for (int ch = 0; ch < channels; ++ch) {
        EXPECT_NEAR(evaluate(rotated, order, channels, ch, x), evaluate(c, order, channels, ch, g * x), tolerance)
            << "order " << order;
      }
    }
  }
}

TEST(ShProperties, RotationKeepsEveryBandsEnergy) {
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(100 + seed);
    const int order = static_cast<int>(rng() % 33);
    const std::vector<double> c = random_coefficients(sh_count(order), rng);
    const std::vector<double> rotated = rotated_sh(c, order, random_test_rotation(rng), 1);
    for (int l = 0; l <= order; ++l) {
      double before = 0.0, after = 0.0;
      for (int m = -l; m <= l; ++m) {
        before += c[sh_index(l, m)] * c[sh_index(l, m)];
        after += rotated[sh_index(l, m)] * rotated[sh_index(l, m)];
      }
      EXPECT_NEAR(after, before, kExact * std::max(1.0, before)) << "order " << order << " band " << l;
    }
  }
}

TEST(ShProperties, RotationsCompose) {  // seen through g1 then g2 = seen through g1 g2
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(200 + seed);
    const int order = static_cast<int>(rng() % 17);
    const glm::dmat3 g1 = random_rotation(rng), g2 = random_rotation(rng);
    const std::vector<double> c = random_coefficients(sh_count(order) * 3, rng);
    const std::vector<double> twice = rotated_sh(rotated_sh(c, order, g1), order, g2);
    const std::vector<double> once = rotated_sh(c, order, g1 * g2);
    for (size_t i = 0; i < c.size(); ++i) EXPECT_NEAR(twice[i], once[i], kExact * norm(c)) << "order " << order;
  }
}

TEST(ShProperties, PhongFactorsOfRandomExponentsAreBoundedAndExact) {
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(300 + seed);
    // Log-uniform in [1e-3, 1e4], never an integer in practice; σ = 0 and 1e4 are the bounds' cases.
    const double sigma = seed == 0 ? 0.0 : seed == 1 ? 1e4 : std::pow(10.0, std::uniform_real_distribution<>(-3, 4)(rng));
    const int lmax = static_cast<int>(rng() % 65);
    const std::vector<double> w = ZonalLobe::phong(sigma).coefficients(lmax);
    ASSERT_EQ(w.size(), size_t(lmax + 1));
    EXPECT_EQ(w[0], 1.0) << "sigma " << sigma;
    for (int l = 0; l <= lmax; ++l) {
      ASSERT_TRUE(std::isfinite(w[l])) << "sigma " << sigma << " l " << l;
      EXPECT_LE(std::abs(w[l]), 1.0) << "sigma " << sigma << " l " << l;
      EXPECT_NEAR(w[l], test::closed_form_factor(sigma, l), 1e-12) << "sigma " << sigma << " l " << l;
    }
  }
}

}  // namespace
}  // namespace sd
