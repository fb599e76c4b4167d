// Randomized properties of the visibility bake (issue 12, item 8): fixed seeds, each case's seed
// in the failure message (SCOPED_TRACE). Random triangle soups with random (some zero) normals and
// random deformed, scaled, rotated and moved spheres give finite outputs, AO in [0, 1] equal to
// Ṽ_00, M_00,00 and its design's mass, certified designs, and the same result on one thread and
// on two; the vertices of a random convex mesh see the complement of their tangent cone (about
// half the sphere).
#include "sdlighting/spherical_design.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/visibility.h"
#include "sdtesting/meshes.h"
#include "sdtesting/sphere.h"
#include "bake_test_support.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace sd {
namespace {

constexpr double kExact = 1e-12;
constexpr int kCases = 8;

using test::Mesh;

// 4..40 random triangles over 3..60 vertices in a random box, normals random with one in eight zero.
Mesh random_soup(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const glm::dvec3 extent(std::exp(2 * uniform(rng)), std::exp(2 * uniform(rng)), std::exp(2 * uniform(rng)));
  Mesh m;
  const int vertices = 3 + static_cast<int>(rng() % 58), triangles = 4 + static_cast<int>(rng() % 37);
  for (int v = 0; v < vertices; ++v) {
    m.vertices.push_back(extent * glm::dvec3(uniform(rng), uniform(rng), uniform(rng)));
    m.normals.push_back(rng() % 8 == 0 ? glm::dvec3(0.0) : test::random_direction(rng));
  }
  for (int t = 0; t < triangles; ++t) {
    m.triangles.push_back({static_cast<std::int64_t>(rng() % vertices), static_cast<std::int64_t>(rng() % vertices),
                           static_cast<std::int64_t>(rng() % vertices)});
  }
  return m;
}

// The icosphere of level 2 with random axes in [0.5, 2] (and random bumps if not `convex`), turned by
// a random rotation and moved up to 1000 away, normals from the faces.
Mesh random_sphere(std::mt19937_64& rng, bool convex) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Mesh m = test::icosphere(2);
  const glm::dvec3 axes(0.5 + 1.5 * uniform(rng), 0.5 + 1.5 * uniform(rng), 0.5 + 1.5 * uniform(rng));
  const glm::dvec3 bumps(1 + rng() % 5, 1 + rng() % 5, 1 + rng() % 5), offset = 1000.0 * test::random_direction(rng);
  const double depth = convex ? 0.0 : 0.3 * uniform(rng);
  const glm::dmat3 turn = test::random_rotation(rng);
  for (auto& v : m.vertices) {
    const double r = 1.0 + depth * std::sin(bumps.x * v.x) * std::sin(bumps.y * v.y) * std::sin(bumps.z * v.z);
    v = turn * (r * axes * v) + offset;
  }
  test::face_normals(m);
  return m;
}

TransferOptions random_options(std::mt19937_64& rng) {
  TransferOptions o;
  o.rays = 32 + static_cast<int>(rng() % 225);
  o.seed = rng();
  o.visibility_order = static_cast<int>(rng() % 4);
  o.product_order = static_cast<int>(rng() % 3);
  o.product_visibility_order = static_cast<int>(rng() % 3);
  o.transfer_order = static_cast<int>(rng() % 3);
  o.design_order = static_cast<int>(rng() % 3);
  o.design_visibility_order = static_cast<int>(rng() % 3);
  o.warm_start_designs = rng() % 2;
  return o;
}

void expect_finite(const std::vector<double>& values, const char* what) {
  for (double v : values) ASSERT_TRUE(std::isfinite(v)) << what;
}

void expect_consistent(const Mesh& m, const TransferOptions& o, const TransferBake& b) {
  const size_t n = m.vertices.size();
  ASSERT_EQ(b.ambient_occlusion.size(), n);
  expect_finite(b.visibility, "visibility");
  expect_finite(b.product_matrices, "product matrices");
  expect_finite(b.transfer, "transfer");
  expect_finite(b.design_weights, "design weights");
  const int kv = sh_count(o.visibility_order), km = sh_count(o.product_order) * sh_count(o.product_visibility_order);
  for (size_t p = 0; p < n; ++p) {
    const double ao = b.ambient_occlusion[p];
    EXPECT_GE(ao, 0.0) << "vertex " << p;
    EXPECT_LE(ao, 1.0) << "vertex " << p;
    EXPECT_NEAR(b.visibility[p * kv], ao, kExact) << "Ṽ_00, vertex " << p;
    EXPECT_NEAR(b.product_matrices[p * km], ao, kExact) << "M_00,00, vertex " << p;
    const auto begin = b.design_offsets[p], end = b.design_offsets[p + 1];
    EXPECT_EQ(end > begin, ao > 0.0) << "a design exactly where a ray escapes, vertex " << p;
    double mass = 0.0;
    for (auto nu = begin; nu < end; ++nu) {
      EXPECT_GT(b.design_weights[nu], 0.0);
      mass += b.design_weights[nu];
    }
    EXPECT_NEAR(mass, ao, kExact) << "design mass, vertex " << p;
    EXPECT_LE(b.design_residuals[p], kDesignTolerance) << "vertex " << p;
  }
}

void expect_same_on_one_and_two_threads(const Mesh& m, TransferOptions o, const TransferBake& two) {
  o.threads = 1;
  test::expect_same(bake_transfer(m.vertices, m.normals, m.triangles, o), two);
}

TEST(BakeProperties, RandomTriangleSoupsGiveConsistentDeterministicBakes) {
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(seed);
    const Mesh m = random_soup(rng);
    TransferOptions o = random_options(rng);
    o.threads = 2;
    const TransferBake b = bake_transfer(m.vertices, m.normals, m.triangles, o);
    expect_consistent(m, o, b);
    for (auto v : b.fallback_normals) EXPECT_EQ(m.normals[v], glm::dvec3(0.0)) << "only zero normals fall back";
    expect_same_on_one_and_two_threads(m, o, b);
  }
}

TEST(BakeProperties, RandomBumpySpheresGiveConsistentDeterministicBakes) {
  for (unsigned seed = 0; seed < kCases / 2; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(100 + seed);
    const Mesh m = random_sphere(rng, false);
    TransferOptions o = random_options(rng);
    o.threads = 2;
    const TransferBake b = bake_transfer(m.vertices, m.normals, m.triangles, o);
    expect_consistent(m, o, b);
    EXPECT_TRUE(b.fallback_normals.empty());
    expect_same_on_one_and_two_threads(m, o, b);
  }
}

TEST(BakeProperties, ConvexMeshVerticesSeeTheComplementOfTheirTangentCone) {
  // A vertex p of a convex polytope sees exactly the directions outside its tangent cone
  // {x : x·n_f <= 0 for every face f at p}: a ray above every face plane escapes, one inside the
  // cone (below every plane by more than the origin's offset can clear) is blocked — about half
  // the sphere, a little more where the facets meet at an angle.
  for (unsigned seed = 0; seed < kCases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(200 + seed);
    const Mesh m = random_sphere(rng, true);
    glm::dvec3 centre(0.0);
    for (const auto& v : m.vertices) centre += v / static_cast<double>(m.vertices.size());
    std::vector<std::vector<glm::dvec3>> planes(m.vertices.size());  // outward face normals at each vertex
    for (const auto& f : m.triangles) {
      glm::dvec3 n = glm::normalize(glm::cross(m.vertices[f[1]] - m.vertices[f[0]], m.vertices[f[2]] - m.vertices[f[0]]));
      if (glm::dot(n, m.vertices[f[0]] - centre) < 0.0) n = -n;
      for (auto v : f) planes[v].push_back(n);
    }
    TransferOptions o;
    o.rays = 256;
    o.seed = rng();
    o.record_rays = true;
    const TransferBake b = bake_transfer(m.vertices, m.normals, m.triangles, o);
    double mean = 0.0;
    for (size_t p = 0; p < m.vertices.size(); ++p) {
      const auto dirs = vertex_ray_directions(o.rays, o.seed, p);
      for (int r = 0; r < o.rays; ++r) {
        double lowest = 1.0, highest = -1.0;
        for (const auto& n : planes[p]) {
          lowest = std::min(lowest, glm::dot(dirs[r], n));
          highest = std::max(highest, glm::dot(dirs[r], n));
        }
        const bool escaped = b.ray_visibility[p * o.rays + r] != 0;
        if (lowest > 0.0) EXPECT_TRUE(escaped) << "vertex " << p << " ray " << r << " above every face";
        if (highest < -0.01) EXPECT_FALSE(escaped) << "vertex " << p << " ray " << r << " inside the solid";
      }
      mean += b.ambient_occlusion[p] / static_cast<double>(m.vertices.size());
    }
    EXPECT_NEAR(mean, 0.5, 0.1);
  }
}

}  // namespace
}  // namespace sd
