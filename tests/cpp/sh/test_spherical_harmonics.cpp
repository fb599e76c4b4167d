#include "sdlighting/limits.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdtesting/sphere.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <random>

namespace sd {
namespace {

constexpr double kExact = 1e-12;

using test::product_rule;
using test::random_direction;
using test::SphereRule;

TEST(SphericalHarmonics, LowOrderClosedForms) {
  const glm::dvec3 d = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
  const auto y = sh_basis(2, d);
  EXPECT_NEAR(y[sh_index(0, 0)], 1.0, kExact);
  EXPECT_NEAR(y[sh_index(1, -1)], std::sqrt(3.0) * d.y, kExact);
  EXPECT_NEAR(y[sh_index(1, 0)], std::sqrt(3.0) * d.z, kExact);
  EXPECT_NEAR(y[sh_index(1, 1)], std::sqrt(3.0) * d.x, kExact);
  EXPECT_NEAR(y[sh_index(2, -2)], std::sqrt(15.0) * d.x * d.y, kExact);
  EXPECT_NEAR(y[sh_index(2, 2)], std::sqrt(15.0) / 2.0 * (d.x * d.x - d.y * d.y), kExact);
  EXPECT_NEAR(y[sh_index(2, 0)], std::sqrt(5.0) / 2.0 * (3.0 * d.z * d.z - 1.0), kExact);
}

TEST(SphericalHarmonics, OrthonormalUpToOrder32) {
  const int order = 32;
  // Product rule (Gauss–Legendre in z × equispaced φ, azimuths at half spacings) exact for degree
  // 2·order: enough to integrate y_a y_b exactly.
  const SphereRule rule = product_rule(2 * order, 0.5);
  const int k = sh_count(order);
  std::vector<double> gram(size_t(k) * k, 0.0), y(k);
  for (size_t q = 0; q < rule.dirs.size(); ++q) {
    sh_basis(order, rule.dirs[q], y.data());
    for (int a = 0; a < k; ++a)
      for (int b = 0; b <= a; ++b) gram[size_t(a) * k + b] += rule.weights[q] * y[a] * y[b];
  }
  double worst = 0.0;
  for (int a = 0; a < k; ++a)
    for (int b = 0; b <= a; ++b) worst = std::max(worst, std::abs(gram[size_t(a) * k + b] - (a == b)));
  EXPECT_LT(worst, kExact);
}

TEST(SphericalHarmonics, AdditionTheoremUpToTheHighestOrder) {
  const int order = kMaxShOrder;
  std::mt19937_64 rng(7);
  std::vector<double> ya(sh_count(order)), yb(sh_count(order)), p(order + 1);
  for (int trial = 0; trial < 50; ++trial) {
    const glm::dvec3 a = random_direction(rng), b = random_direction(rng);
    sh_basis(order, a, ya.data());
    sh_basis(order, b, yb.data());
    legendre_all(order, glm::dot(a, b), p.data());
    for (int l = 0; l <= order; ++l) {
      double sum = 0.0;
      for (int m = -l; m <= l; ++m) sum += ya[sh_index(l, m)] * yb[sh_index(l, m)];
      EXPECT_NEAR(sum, (2 * l + 1) * p[l], kExact * (2 * l + 1)) << "l=" << l;
    }
  }
}

TEST(SphericalHarmonics, GradientMatchesFiniteDifferences) {
  const int order = 10;
  std::mt19937_64 rng(3);
  const int k = sh_count(order);
  std::vector<double> values(k), grads(3 * k), plus(k), minus(k);
  for (int trial = 0; trial < 20; ++trial) {
    const glm::dvec3 d = random_direction(rng);
    sh_basis_with_gradient(order, d, values.data(), grads.data());
    glm::dvec3 tangent = glm::normalize(glm::cross(d, random_direction(rng)));
    const double h = 1e-6;
    sh_basis(order, glm::normalize(d + h * tangent), plus.data());
    sh_basis(order, glm::normalize(d - h * tangent), minus.data());
    for (int i = 0; i < k; ++i) {
      const double fd = (plus[i] - minus[i]) / (2 * h);
      const glm::dvec3 g(grads[3 * i], grads[3 * i + 1], grads[3 * i + 2]);
      EXPECT_NEAR(glm::dot(g, tangent), fd, 1e-6 * (1.0 + std::abs(fd)));
      EXPECT_NEAR(glm::dot(g, d), 0.0, kExact);
      EXPECT_NEAR(values[i], plus[i] * 0.5 + minus[i] * 0.5, 1e-6 * (1.0 + std::abs(values[i])) * order * order);
    }
  }
}

TEST(Legendre, MatchesClosedFormsAndRecurrence) {
  for (double t : {-1.0, -0.3, 0.0, 0.5, 1.0}) {
    EXPECT_NEAR(legendre(2, t), 0.5 * (3 * t * t - 1), kExact);
    EXPECT_NEAR(legendre(3, t), 0.5 * (5 * t * t * t - 3 * t), kExact);
    EXPECT_NEAR(legendre(60, 1.0), 1.0, kExact);
    std::vector<double> all(41);
    legendre_all(40, t, all.data());
    EXPECT_NEAR(all[40], legendre(40, t), kExact);
  }
}

}  // namespace
}  // namespace sd
