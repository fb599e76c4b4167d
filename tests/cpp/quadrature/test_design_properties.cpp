// Randomized properties of the designs (issue 12, item 8): fixed seeds, each case's seed in the
// failure message (SCOPED_TRACE). Weighted designs of random discrete measures — random sizes,
// supports (whole sphere, a cap, clusters), weights spanning decades at any scale from 1e-300 to
// 1e300 — certify with positive weights, keep the mass, integrate random polynomials of their
// degree exactly, and refit to a changed measure; zonal designs of random non-integer Phong
// exponents match the Funk–Hecke moments.
#include "design_test_support.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/weighted_design.h"
#include "sdlighting/zonal_design.h"
#include "sdtesting/sphere.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace sd {
namespace {

constexpr int kCases = 30;

struct Measure {
  std::vector<glm::dvec3> dirs;
  std::vector<double> weights;
};

// A random discrete measure: 1..400 points on the whole sphere, in a random cap or in a few
// tight clusters; weights log-uniform over up to 6 decades times 10^e, e in [−300, 300].
Measure random_measure(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const int count = 1 + static_cast<int>(rng() % 400), support = static_cast<int>(rng() % 3);
  const glm::dvec3 axis = test::random_direction(rng);
  const double cap = -1.0 + 1.9 * uniform(rng);  // the cap x·axis > cap
  std::vector<glm::dvec3> centres(1 + rng() % 4);
  for (auto& c : centres) c = test::random_direction(rng);
  const double decades = 6.0 * uniform(rng), scale = std::pow(10.0, -300.0 + 600.0 * uniform(rng));
  Measure m;
  while (static_cast<int>(m.dirs.size()) < count) {
    glm::dvec3 x = test::random_direction(rng);
    if (support == 1 && glm::dot(x, axis) <= cap) continue;
    if (support == 2) x = glm::normalize(centres[rng() % centres.size()] + 0.05 * x);
    m.dirs.push_back(x);
    m.weights.push_back(scale * std::pow(10.0, -decades * uniform(rng)));
  }
  return m;
}

// Σ_i w_i f(x_i) for f = Σ_j a_j y_j of the given degree.
double integrate(const std::vector<glm::dvec3>& x, const std::vector<double>& w, const std::vector<double>& a,
                 int degree) {
  double sum = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    const std::vector<double> y = sh_basis(degree, x[i]);
    double f = 0.0;
    for (int j = 0; j < sh_count(degree); ++j) f += a[j] * y[j];
    sum += w[i] * f;
  }
  return sum;
}

void expect_design_of(const SphericalDesign& design, const Measure& m, int degree, std::mt19937_64& rng) {
  const double mass = std::accumulate(m.weights.begin(), m.weights.end(), 0.0);
  ASSERT_GT(design.size(), 0);
  EXPECT_EQ(design.degree, degree);
  EXPECT_LE(design.residual, kDesignTolerance);
  EXPECT_LE(design.size(), std::min<int>(sh_count(degree), static_cast<int>(m.dirs.size())));
  for (double w : design.weights) EXPECT_GT(w, 0.0);
  EXPECT_NEAR(std::accumulate(design.weights.begin(), design.weights.end(), 0.0), mass, 1e-10 * mass);
  // Exact on random polynomials of the degree: |Σ a_j Δmoment_j| <= ‖a‖ ‖Δmoment‖ <= ‖a‖ tol mass.
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<double> a(sh_count(degree));
    double norm = 0.0;
    for (double& v : a) {
      v = normal(rng);
      norm += v * v;
    }
    EXPECT_NEAR(integrate(design.nodes, design.weights, a, degree), integrate(m.dirs, m.weights, a, degree),
                1.01 * kDesignTolerance * std::sqrt(norm) * mass);
  }
}

TEST(DesignProperties, WeightedDesignsOfRandomMeasuresCertifyAndIntegrateTheirDegree) {
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(seed);
    const Measure m = random_measure(rng);
    const int degree = static_cast<int>(rng() % 9);
    expect_design_of(weighted_design(m.dirs, m.weights, degree), m, degree, rng);
  }
}

TEST(DesignProperties, RefitsToARandomlyChangedMeasure) {  // the bake's vertex walk (start = a neighbour's)
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(1000 + seed);
    Measure m = random_measure(rng);
    const int degree = static_cast<int>(rng() % 7);
    const SphericalDesign start = weighted_design(m.dirs, m.weights, degree);
    std::uniform_real_distribution<double> change(0.5, 1.5);
    for (double& w : m.weights) w *= change(rng);
    expect_design_of(weighted_design(m.dirs, m.weights, degree, {&start}), m, degree, rng);
  }
}

TEST(DesignProperties, ZonalDesignsOfRandomPhongExponentsHaveTheFunkHeckeMoments) {
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(2000 + seed);
    const double sigma = std::pow(10.0, std::uniform_real_distribution<>(-3, 4)(rng));  // log-uniform, non-integer
    const int degree = static_cast<int>(rng() % 9);
    const ZonalLobe lobe = ZonalLobe::phong(sigma);
    test::expect_lobe_design(zonal_design(ZonalWeight::from_lobe(lobe), degree), lobe, degree);
  }
}

}  // namespace
}  // namespace sd
