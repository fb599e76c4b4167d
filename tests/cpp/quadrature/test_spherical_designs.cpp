#include "sdlighting/gauss_quadrature.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/weighted_design.h"
#include "sdlighting/zonal_design.h"
#include "sdtesting/sphere.h"
#include "design_test_support.h"
#include "quadrature/clustered_start.h"
#include "quadrature/design_fit.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

namespace sd {
namespace {

using test::expect_lobe_design;

TEST(ZonalDesign, EveryMethodCertifiesForLambertAndPhong) {
  // σ = 0 is the uniform hemisphere, σ = 2.5 a Jacobi weight of non-integer exponent.
  for (double sigma : {0.0, 1.0, 2.5, 8.0, 1000.0, 1e4}) {
    const ZonalLobe lobe = ZonalLobe::phong(sigma);
    const ZonalWeight weight = ZonalWeight::from_lobe(lobe);
    for (int degree = 0; degree <= 8; ++degree) {
      for (DesignMethod method : {DesignMethod::Gauss, DesignMethod::Gradient, DesignMethod::Auto}) {
        expect_lobe_design(zonal_design(weight, degree, method), lobe, degree);
      }
    }
  }
}

TEST(ZonalDesign, ReachesTheSeedsNodeCounts) {
  // The seed: 10 nodes for degree 4 and 18 for degree 6 by gradient projection; 11 and 22 by
  // the Gauss product (with the pole node).
  for (double sigma : {1.0, 8.0, 32.0, 128.0, 1000.0}) {
    const ZonalWeight weight = ZonalWeight::from_lobe(ZonalLobe::phong(sigma));
    EXPECT_LE(zonal_design(weight, 4, DesignMethod::Gradient).size(), 10) << sigma;
    EXPECT_LE(zonal_design(weight, 6, DesignMethod::Gradient).size(), 18) << sigma;
    EXPECT_EQ(zonal_design(weight, 4, DesignMethod::Gauss).size(), 11);
    EXPECT_EQ(zonal_design(weight, 6, DesignMethod::Gauss).size(), 22);
    for (int degree = 2; degree <= 8; ++degree) {
      EXPECT_GE(zonal_design(weight, degree).size(), design_lower_bound(degree));
    }
  }
}

TEST(ZonalDesign, ContinuedFromANeighbouringExponentCertifiesWithNoMoreNodes) {
  // Steps of 1.25 in σ + 1, as the add-on takes them; the count stays at or below the search's.
  for (int degree : {4, 6, 8, 10}) {
    SphericalDesign previous = zonal_design(ZonalWeight::from_lobe(ZonalLobe::phong(8.0)), degree);
    double previous_sigma = 8.0;
    for (double sigma : {10.25, 13.06}) {
      const ZonalLobe lobe = ZonalLobe::phong(sigma);
      const ZonalWeight weight = ZonalWeight::from_lobe(lobe);
      const std::optional<SphericalDesign> continued =
          zonal_design_continued(weight, degree, ZonalWeight::from_lobe(ZonalLobe::phong(previous_sigma)), previous);
      ASSERT_TRUE(continued) << "degree " << degree << " sigma " << sigma;
      expect_lobe_design(*continued, lobe, degree);
      EXPECT_LE(continued->size(), zonal_design(weight, degree).size()) << "degree " << degree << " sigma " << sigma;
      previous = *continued;
      previous_sigma = sigma;
    }
  }
}

TEST(ZonalDesign, ContinuedFromLambertToPhong) {
  // Lambert's weight is Phong's at σ = 1; continuing down to σ = 0.8 and up to 1.25 certifies.
  const SphericalDesign lambert = zonal_design(ZonalWeight::from_lobe(ZonalLobe::lambert()), 8);
  for (double sigma : {0.8, 1.25}) {
    const std::optional<SphericalDesign> continued = zonal_design_continued(
        ZonalWeight::from_lobe(ZonalLobe::phong(sigma)), 8, ZonalWeight::from_lobe(ZonalLobe::lambert()), lambert);
    ASSERT_TRUE(continued) << sigma;
    expect_lobe_design(*continued, ZonalLobe::phong(sigma), 8);
    EXPECT_LE(continued->size(), lambert.size()) << sigma;
  }
}

TEST(ZonalDesign, ContinuedWithoutThinningKeepsTheStartsNodeCount) {
  // The add-on's steps on the way to the exponent it wants: refitted, certified, not thinned.
  const SphericalDesign start = zonal_design(ZonalWeight::from_lobe(ZonalLobe::phong(8.0)), 8, DesignMethod::Gauss);
  const ZonalLobe lobe = ZonalLobe::phong(10.25);
  const std::optional<SphericalDesign> moved = zonal_design_continued(
      ZonalWeight::from_lobe(lobe), 8, ZonalWeight::from_lobe(ZonalLobe::phong(8.0)), start, false);
  ASSERT_TRUE(moved);
  expect_lobe_design(*moved, lobe, 8);
  EXPECT_EQ(moved->size(), start.size());
  const std::optional<SphericalDesign> thinned = zonal_design_continued(
      ZonalWeight::from_lobe(lobe), 8, ZonalWeight::from_lobe(ZonalLobe::phong(8.0)), start, true);
  ASSERT_TRUE(thinned);
  expect_lobe_design(*thinned, lobe, 8);
  EXPECT_LT(thinned->size(), start.size());
}

TEST(ZonalDesign, ContinuedRefusesAStartOfAnotherDegree) {
  const ZonalWeight weight = ZonalWeight::from_lobe(ZonalLobe::phong(8.0));
  const SphericalDesign start = zonal_design(weight, 6);
  EXPECT_THROW(zonal_design_continued(weight, 8, weight, start), std::invalid_argument);
  EXPECT_THROW(zonal_design_continued(weight, kMaxDesignDegree + 1, weight, start), std::invalid_argument);
  EXPECT_THROW(zonal_design_continued(weight, 6, weight, SphericalDesign{}), std::invalid_argument);
}

TEST(ZonalDesign, GaussForOddDegreeUsesThePlainProduct) {
  const ZonalWeight weight = ZonalWeight::from_lobe(ZonalLobe::lambert());
  // n = (k+1)/2 Gauss rings of k+1 nodes beat the Radau variant's 1 + (k+1)²/2.
  EXPECT_EQ(zonal_design(weight, 5, DesignMethod::Gauss).size(), 18);
  EXPECT_EQ(zonal_design(weight, 5, DesignMethod::Gauss).method, "gauss");
  EXPECT_EQ(zonal_design(weight, 6, DesignMethod::Gauss).method, "gauss-radau");
}

TEST(ZonalDesign, TabulatedWeightMatchesTheLobeItSamples) {
  const ZonalLobe lobe = ZonalLobe::phong(8.0);
  std::vector<double> t, w;
  for (int i = 0; i <= 4000; ++i) {
    t.push_back(-1.0 + 2.0 * i / 4000.0);
    w.push_back(lobe.value(t.back()));
  }
  const ZonalWeight tabulated = ZonalWeight::tabulated(t, w);
  EXPECT_NEAR(tabulated.mass(), 1.0, 1e-5);  // linear interpolation error only
  const SphericalDesign design = zonal_design(tabulated, 6);
  EXPECT_LE(design.residual, kDesignTolerance);
  EXPECT_LE(design.size(), 18);
  const auto exact = lobe.coefficients(6);
  const auto table = tabulated.legendre_moments(6);
  for (int l = 0; l <= 6; ++l) EXPECT_NEAR(table[l], exact[l], 1e-5);
}

TEST(ZonalDesign, TabulatedWeightAwayFromThePole) {
  // A band 0.2 <= t <= 0.6: no Radau pole node is possible, designs still certify.
  const ZonalWeight band = ZonalWeight::tabulated({0.2, 0.4, 0.6}, {1.0, 2.0, 1.0});
  for (int degree : {2, 4, 6}) {
    const SphericalDesign design = zonal_design(band, degree);
    EXPECT_LE(design.residual, kDesignTolerance);
    EXPECT_NEAR(std::accumulate(design.weights.begin(), design.weights.end(), 0.0), band.mass(), 1e-13);
  }
  EXPECT_EQ(zonal_design(band, 4, DesignMethod::Gauss).method, "gauss");
}

TEST(ZonalDesign, TabulatedWeightHasTheMomentsOfItsPiecewiseLinearWeight) {
  // A ragged band: the SH moments of the interpolated weight by a product rule on each segment
  // (Gauss–Legendre in z, exact for the linear weight times y_l0; equally spaced φ for m ≠ 0).
  const std::vector<double> t = {-0.5, 0.0, 0.3, 0.9}, w = {0.0, 2.0, 0.5, 3.0};
  const ZonalWeight band = ZonalWeight::tabulated(t, w);
  constexpr int kDegree = 6, kNodes = 8;
  const Rule1D unit = gauss_rule(jacobi_recurrence_unit_interval(0.0, kNodes), kNodes);
  std::vector<glm::dvec3> dirs;
  std::vector<double> weights;
  for (size_t segment = 0; segment + 1 < t.size(); ++segment) {
    const double a = t[segment], b = t[segment + 1];
    std::vector<double> z(kNodes), dz(kNodes);
    for (int i = 0; i < kNodes; ++i) {
      z[i] = a + (b - a) * unit.nodes[i];
      dz[i] = 0.5 * (b - a) * unit.weights[i];  // dμ = dz dφ / 4π
    }
    const test::SphereRule rule = test::product_rule(z, dz, kDegree + 1, 0.25);
    for (size_t q = 0; q < rule.dirs.size(); ++q) {
      const double s = (rule.dirs[q].z - a) / (b - a);
      dirs.push_back(rule.dirs[q]);
      weights.push_back(rule.weights[q] * ((1.0 - s) * w[segment] + s * w[segment + 1]));
    }
  }
  const double mass = std::accumulate(weights.begin(), weights.end(), 0.0);
  EXPECT_NEAR(band.mass(), mass, 1e-14);
  for (DesignMethod method : {DesignMethod::Auto, DesignMethod::Gauss}) {
    const SphericalDesign design = zonal_design(band, kDegree, method);
    const auto expected = design_moments(dirs, weights, kDegree);
    const auto got = design_moments(design.nodes, design.weights, kDegree);
    for (size_t j = 0; j < got.size(); ++j) EXPECT_NEAR(got[j], expected[j], kDesignTolerance * mass) << j;
  }
}

TEST(ZonalDesign, RejectsBadInput) {
  const ZonalWeight weight = ZonalWeight::from_lobe(ZonalLobe::lambert());
  EXPECT_THROW(zonal_design(weight, -1), std::invalid_argument);
  EXPECT_THROW(zonal_design(weight, kMaxDesignDegree + 1), std::invalid_argument);
  EXPECT_THROW(design_method_from_name("newton"), std::invalid_argument);
  EXPECT_THROW(ZonalWeight::tabulated({0.0}, {1.0}), std::invalid_argument);
  EXPECT_THROW(ZonalWeight::tabulated({0.0, 0.5}, {1.0, -1.0}), std::invalid_argument);
  EXPECT_THROW(ZonalWeight::tabulated({0.5, 0.0}, {1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ZonalWeight::tabulated({0.0, 1.5}, {1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ZonalWeight::tabulated({0.0, 0.5}, {std::nan(""), 1.0}), std::invalid_argument);
  EXPECT_THROW(ZonalWeight::tabulated({0.0, 0.5}, {0.0, 0.0}), std::invalid_argument);
}

using test::random_directions;

TEST(WeightedDesign, CompressesARandomMeasure) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(0.1, 2.0);
  const auto dirs = random_directions(2000, rng);
  std::vector<double> weights(dirs.size());
  for (double& w : weights) w = uniform(rng);
  const double mass = std::accumulate(weights.begin(), weights.end(), 0.0);
  for (int degree : {2, 4, 6}) {
    const SphericalDesign design = weighted_design(dirs, weights, degree);
    const auto expected = design_moments(dirs, weights, degree);
    const auto got = design_moments(design.nodes, design.weights, degree);
    for (size_t j = 0; j < got.size(); ++j) EXPECT_NEAR(got[j], expected[j], kDesignTolerance * mass);
    EXPECT_LE(design.size(), sh_count(degree));
    EXPECT_LT(design.size(), sh_count(degree)) << "gradient projection removed no node at degree " << degree;
    for (double w : design.weights) EXPECT_GT(w, 0.0);
  }
}

TEST(WeightedDesign, VisibilityLikeHemisphere) {
  // Ray samples of an open plane: only the upper hemisphere escapes.
  std::mt19937_64 rng(5);
  std::vector<glm::dvec3> dirs;
  for (const auto& d : random_directions(1024, rng))
    if (d.z > 0.0) dirs.push_back(d);
  const std::vector<double> weights(dirs.size(), 1.0 / 1024.0);
  const SphericalDesign design = weighted_design(dirs, weights, 6);
  EXPECT_LE(design.residual, kDesignTolerance);
  EXPECT_LE(design.size(), 30);
}

// Of 1024 random directions, those above the plane at `height` along the normal (sin tilt, 0,
// cos tilt): a vertex's visibility, tilted (a hemisphere at height 0, a cap above it).
std::vector<glm::dvec3> tilted_hemisphere(std::uint64_t seed, double tilt, double height = 0.0) {
  std::mt19937_64 rng(seed);
  const glm::dvec3 normal(std::sin(tilt), 0.0, std::cos(tilt));
  std::vector<glm::dvec3> dirs;
  for (const auto& d : random_directions(1024, rng))
    if (glm::dot(d, normal) > height) dirs.push_back(d);
  return dirs;
}

TEST(WeightedDesign, RefitsANeighboursDesign) {
  const auto here = tilted_hemisphere(5, 0.0), next = tilted_hemisphere(6, 0.05);
  const std::vector<double> here_weights(here.size(), 1.0 / 1024), next_weights(next.size(), 1.0 / 1024);
  for (int degree : {4, 6}) {
    const SphericalDesign start = weighted_design(here, here_weights, degree);
    const SphericalDesign design = weighted_design(next, next_weights, degree, {&start});
    EXPECT_EQ(design.method, "refit") << "degree " << degree;
    EXPECT_LE(design.size(), start.size());
    const auto expected = design_moments(next, next_weights, degree);
    const auto got = design_moments(design.nodes, design.weights, degree);
    const double mass = next.size() / 1024.0;
    for (size_t j = 0; j < got.size(); ++j) EXPECT_NEAR(got[j], expected[j], kDesignTolerance * mass);
    EXPECT_LE(design.residual, kDesignTolerance);
    for (double w : design.weights) EXPECT_GT(w, 0.0);
  }
}

TEST(WeightedDesign, TurnsANeighboursDesignWithItsSky) {
  // next's sky is here's turned by 0.8 rad about y. Here's is symmetric about the zenith, its mean
  // direction, so the smallest rotation between the mean directions is that turn: turned, here's
  // design is next's already, and the refit stays by it (0.08 rad at most at degree 4, where a
  // node by the horizon is moved into the support). Unturned, half of its nodes lie where next has
  // no mass, and the refit ends elsewhere (0.36 rad at degree 4, 0.38 at 6).
  std::vector<glm::dvec3> here;
  for (const glm::dvec3& d : tilted_hemisphere(5, 0.0)) {
    here.push_back(d);
    here.emplace_back(-d.x, -d.y, d.z);
  }
  const double c = std::cos(0.8), s = std::sin(0.8);
  auto turned = [&](const glm::dvec3& d) { return glm::dvec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z); };
  std::vector<glm::dvec3> next;
  for (const glm::dvec3& d : here) next.push_back(turned(d));
  const std::vector<double> weights(here.size(), 1.0 / 1024);
  for (int degree : {4, 6}) {
    const SphericalDesign start = weighted_design(here, weights, degree);
    const SphericalDesign design = weighted_design(next, weights, degree, {&start});
    EXPECT_EQ(design.method, "refit") << "degree " << degree;
    EXPECT_EQ(design.size(), start.size()) << "degree " << degree;
    EXPECT_LE(design.residual, kDesignTolerance);
    double farthest = 0.0;  // of the design's nodes from the turned start's nearest
    for (const glm::dvec3& node : design.nodes) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const glm::dvec3& x : start.nodes) {
        nearest = std::min(nearest, std::acos(std::min(1.0, glm::dot(node, turned(x)))));
      }
      farthest = std::max(farthest, nearest);
    }
    EXPECT_LT(farthest, 0.2) << "degree " << degree;
  }
}

TEST(WeightedDesign, RefitsTheClosestOfSeveralStarts) {
  // The farther start's sky is smaller as well as tilted: turning it towards next's does not
  // bring it nearer than here's.
  const auto here = tilted_hemisphere(5, 0.0), next = tilted_hemisphere(6, 0.05),
             farther = tilted_hemisphere(7, 0.3, 0.3);
  const std::vector<double> here_weights(here.size(), 1.0 / 1024), next_weights(next.size(), 1.0 / 1024),
      farther_weights(farther.size(), 1.0 / 1024);
  const SphericalDesign near_start = weighted_design(here, here_weights, 6);
  const SphericalDesign farther_start = weighted_design(farther, farther_weights, 6);
  // Both refit on their own, to different designs; in either order the nearer one is refitted.
  const SphericalDesign from_near = weighted_design(next, next_weights, 6, {&near_start});
  const SphericalDesign from_farther = weighted_design(next, next_weights, 6, {&farther_start});
  ASSERT_EQ(from_near.method, "refit");
  ASSERT_EQ(from_farther.method, "refit");
  ASSERT_NE(from_farther.nodes, from_near.nodes);
  for (const auto& starts : {std::vector<const SphericalDesign*>{&farther_start, nullptr, &near_start},
                             std::vector<const SphericalDesign*>{&near_start, &farther_start}}) {
    const SphericalDesign design = weighted_design(next, next_weights, 6, starts);
    EXPECT_EQ(design.nodes, from_near.nodes);
    EXPECT_EQ(design.weights, from_near.weights);
  }
}

TEST(WeightedDesign, RanksTheStartsAfterMovingTheirNodesIntoTheSupport) {
  const auto here = tilted_hemisphere(5, 0.0), next = tilted_hemisphere(6, 0.05);
  const std::vector<double> here_weights(here.size(), 1.0 / 1024), next_weights(next.size(), 1.0 / 1024);
  // A cap around the zenith: its design lies inside next's support, away from next's moments.
  std::vector<glm::dvec3> cap;
  for (const glm::dvec3& d : tilted_hemisphere(7, 0.0))
    if (d.z > 0.5) cap.push_back(d);
  const SphericalDesign cap_start = weighted_design(cap, std::vector<double>(cap.size(), 1.0 / 1024), 6);
  // The near start with a node at the nadir, where `next` has no mass: as given, far beyond the
  // cap's design; with that node on the nearest sample direction, nearer than it.
  SphericalDesign near_start = weighted_design(here, here_weights, 6);
  near_start.nodes.emplace_back(0.0, 0.0, -1.0);
  near_start.weights.push_back(0.1 * near_start.weights.front());
  const SphericalDesign from_near = weighted_design(next, next_weights, 6, {&near_start});
  const SphericalDesign from_cap = weighted_design(next, next_weights, 6, {&cap_start});
  ASSERT_EQ(from_near.method, "refit");
  ASSERT_NE(from_near.nodes, from_cap.nodes);
  const SphericalDesign design = weighted_design(next, next_weights, 6, {&cap_start, &near_start});
  EXPECT_EQ(design.nodes, from_near.nodes);
}

TEST(WeightedDesign, AnUnusableStartFallsBackToAClusteredStartThenCompression) {
  // A point mass's design, one node: turned onto down's sky it still cannot hold degree 6, nor
  // can the three rounds of exchanged nodes or a clustered start of its count, and the compression
  // builds the design. A start of another degree is skipped.
  const auto down = tilted_hemisphere(6, 3.1);
  const std::vector<double> down_weights(down.size(), 1.0 / 1024);
  const SphericalDesign start = weighted_design({{0.0, 0.0, 1.0}}, {1.0}, 6);
  const auto up = tilted_hemisphere(5, 0.0);
  const SphericalDesign other_degree = weighted_design(up, std::vector<double>(up.size(), 1.0 / 1024), 4);
  ASSERT_EQ(start.size(), 1);
  for (const SphericalDesign* given : {&start, &other_degree}) {
    const SphericalDesign design = weighted_design(down, down_weights, 6, {given});
    EXPECT_LE(design.residual, kDesignTolerance);
    for (double w : design.weights) EXPECT_GT(w, 0.0);
  }
  const std::string from_point = weighted_design(down, down_weights, 6, {&start}).method;
  EXPECT_TRUE(from_point == "tchakaloff" || from_point == "gradient") << from_point;
  // A start of another degree is skipped: the design is the clustered start's refit, as with no
  // usable start at all; without starts, the compression from scratch.
  const SphericalDesign skipped = weighted_design(down, down_weights, 6, {&other_degree});
  const SphericalDesign none = weighted_design(down, down_weights, 6, {nullptr});
  EXPECT_EQ(skipped.method, "clustered");
  EXPECT_EQ(skipped.nodes, none.nodes);
  const std::string compressed = weighted_design(down, down_weights, 6).method;
  EXPECT_TRUE(compressed == "tchakaloff" || compressed == "gradient") << compressed;
}

TEST(WeightedDesign, HardlyMorePointsThanMomentsAreCompressedAtOnce) {
  // 27 points for the 25 moments of degree 4: even the measure's own design, which would refit at
  // once, is not refitted (weighted_design.cpp, kFewPoints).
  std::mt19937_64 rng(11);
  const auto dirs = random_directions(27, rng);
  const std::vector<double> weights(dirs.size(), 1.0 / 27);
  const SphericalDesign own = weighted_design(dirs, weights, 4);
  const SphericalDesign design = weighted_design(dirs, weights, 4, {&own});
  EXPECT_TRUE(design.method == "tchakaloff" || design.method == "gradient") << design.method;
  EXPECT_EQ(design.nodes, own.nodes);
  EXPECT_LE(design.residual, kDesignTolerance);
}

TEST(PruneDesign, DropsTheLightestOrTheSmallestMomentsFirst) {
  // F(x) = (x, y, 100 z): the lightest node, on the z axis, has the largest moments.
  MomentSystem system;
  system.size = system.raw_size = 3;
  system.transform = BasisTransform{{0, 1, 2}, Eigen::Vector3d(1.0, 1.0, 100.0).asDiagonal()};
  system.target = Eigen::Vector3d::Zero();
  system.evaluate = [](const glm::dvec3& x, double* values, double* gradients) {
    values[0] = x.x, values[1] = x.y, values[2] = x.z;
    if (gradients) {
      for (int i = 0; i < 9; ++i) gradients[i] = i % 4 == 0 ? 1.0 : 0.0;
    }
  };
  SphericalDesign design;
  design.nodes = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
  design.weights = {0.1, 0.5, 1.0};
  // No fit steps and every candidate accepted: one node dropped, the others as they were.
  const FitOptions unchanged{0.0, 0};
  auto accept = [](SphericalDesign&) { return true; };
  const SphericalDesign lightest = prune_design(system, design, 2, accept, unchanged);
  EXPECT_EQ(lightest.nodes, (std::vector<glm::dvec3>{{0, 1, 0}, {1, 0, 0}}));
  const SphericalDesign smallest = prune_design(system, design, 2, accept, unchanged, PruneOptions{true});
  EXPECT_EQ(smallest.nodes, (std::vector<glm::dvec3>{{0, 0, 1}, {0, 1, 0}}));
}

TEST(ClusteredStart, SpreadsDistinctNodesOverTheSamplesAndKeepsTheMass) {
  // Four directions on a meridian: three clusters seed at the two ends and the middle pair's
  // farther point, never twice at one direction.
  std::vector<glm::dvec3> meridian;
  for (double degrees : {0.0, 60.0, 120.0, 180.0}) {
    const double a = degrees * 3.14159265358979323846 / 180.0;
    meridian.emplace_back(std::sin(a), 0.0, std::cos(a));
  }
  const SphericalDesign three = clustered_start(meridian, {1.0, 2.0, 3.0, 4.0}, 3, 4);
  ASSERT_EQ(three.size(), 3);
  EXPECT_NEAR(std::accumulate(three.weights.begin(), three.weights.end(), 0.0), 10.0, 1e-12);
  EXPECT_EQ(three.method, "clustered");
  // As many clusters as directions: the measure itself.
  const SphericalDesign four = clustered_start(meridian, {1.0, 2.0, 3.0, 4.0}, 9, 4);
  ASSERT_EQ(four.size(), 4);
  for (int i = 0; i < 4; ++i) {
    const auto direction = static_cast<std::size_t>(four.weights[i]) - 1;  // weights 1..4 name them
    ASSERT_LT(direction, meridian.size());
    EXPECT_NEAR(glm::dot(four.nodes[i], meridian[direction]), 1.0, 1e-12);
  }

  // A vertex's visibility: every requested cluster is used, each node within a few sample
  // spacings of its nearest sample direction, and the weights sum to the mass.
  const auto sky = tilted_hemisphere(5, 0.4);
  const std::vector<double> weights(sky.size(), 1.0 / 1024);
  const double mass = sky.size() / 1024.0;
  for (int count : {1, 9, 17, 44}) {
    const SphericalDesign design = clustered_start(sky, weights, count, 9);
    ASSERT_EQ(design.size(), count);
    EXPECT_NEAR(std::accumulate(design.weights.begin(), design.weights.end(), 0.0), mass, 1e-12);
    const glm::dvec3 normal(std::sin(0.4), 0.0, std::cos(0.4));
    for (const glm::dvec3& node : design.nodes) {
      EXPECT_NEAR(glm::length(node), 1.0, 1e-12);
      EXPECT_GT(glm::dot(node, normal), 0.0) << "a node outside the visible hemisphere";
    }
  }
}

TEST(WeightedDesign, FewerPointsThanMomentsKeepsThePoints) {
  const std::vector<glm::dvec3> dirs = {{0, 0, 1}, {1, 0, 0}, {0, 2, 0}};
  const SphericalDesign design = weighted_design(dirs, {0.5, 0.25, 0.25}, 6);
  EXPECT_LE(design.size(), 3);
  EXPECT_LE(design.residual, kDesignTolerance);
  // Given a start, the compression still runs, and not a refit: even of a start that is already
  // this measure's design.
  const SphericalDesign from_start = weighted_design(dirs, {0.5, 0.25, 0.25}, 6, {&design});
  EXPECT_TRUE(from_start.method == "tchakaloff" || from_start.method == "gradient") << from_start.method;
  EXPECT_EQ(from_start.nodes, design.nodes);
}

TEST(WeightedDesign, APointMassGivesOneNode) {
  // All the mass on one direction, given twice and unnormalised, beside a zero weight.
  const SphericalDesign design = weighted_design({{0, 0, 2}, {0, 0, 5}, {1, 0, 0}}, {1.5, 0.5, 0.0}, 6);
  ASSERT_EQ(design.size(), 1);
  EXPECT_NEAR(glm::length(design.nodes[0] - glm::dvec3(0, 0, 1)), 0.0, 1e-12);
  EXPECT_NEAR(design.weights[0], 2.0, 1e-12);
}

TEST(WeightedDesign, RejectsBadInput) {
  const std::vector<glm::dvec3> dirs = {{0, 0, 1}, {1, 0, 0}};
  EXPECT_THROW(weighted_design(dirs, {1.0}, 2), std::invalid_argument);
  EXPECT_THROW(weighted_design(dirs, {1.0, -1.0}, 2), std::invalid_argument);
  EXPECT_THROW(weighted_design(dirs, {0.0, 0.0}, 2), std::invalid_argument);
  EXPECT_THROW(weighted_design(dirs, {1.0, std::nan("")}, 2), std::invalid_argument);
  EXPECT_THROW(weighted_design({{0, 0, 0}, {1, 0, 0}}, {1.0, 1.0}, 2), std::invalid_argument);
  EXPECT_THROW(weighted_design(dirs, {1.0, 1.0}, -1), std::invalid_argument);
  EXPECT_THROW(weighted_design(dirs, {1.0, 1.0}, kMaxDesignDegree + 1), std::invalid_argument);
}

}  // namespace
}  // namespace sd
