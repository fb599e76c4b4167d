// Tests of the Embree visibility / transfer bake (sdlighting/visibility.h).
//
// Exact checks (1e-12) recompute the outputs from the recorded ray bits (TransferOptions::record_rays)
// and vertex_ray_directions; Monte-Carlo checks compare with closed forms within the error of the
// spherical Fibonacci rule at the ray count used.
#include "sdlighting/spherical_design.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/visibility.h"
#include "sdlighting/zonal_lobe.h"
#include "sdtesting/meshes.h"
#include "bake_test_support.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <utility>
#include <vector>

namespace sd {
namespace {

constexpr double kExact = 1e-12;

using test::bumpy_sphere;
using test::icosphere;
using test::Mesh;
using test::plane_grid;

TransferBake bake(const Mesh& m, TransferOptions options, const OccluderMesh& occluders = {}) {
  return bake_transfer(m.vertices, m.normals, m.triangles, options, occluders);
}

// Options for `rays` rays per vertex from `seed` that keep every ray's V_r
// (TransferBake::ray_visibility) for the exact checks; each test turns on the outputs it checks.
TransferOptions recorded_rays(int rays, std::uint64_t seed) {
  TransferOptions options;
  options.rays = rays;
  options.seed = seed;
  options.record_rays = true;
  return options;
}

// `options` with the outputs requested: Ṽ of order `visibility`, M of orders `product` = (s, s'), T of
// order `transfer` and the design of `design` = (s, s'); -1 leaves an output out.
TransferOptions requesting(TransferOptions options, int visibility, std::pair<int, int> product, int transfer,
                           std::pair<int, int> design) {
  options.visibility_order = visibility;
  options.product_order = product.first;
  options.product_visibility_order = product.second;
  options.transfer_order = transfer;
  options.design_order = design.first;
  options.design_visibility_order = design.second;
  return options;
}

// The directions of vertex v's escaping rays (V_r = 1), in ray order, of a bake made with
// `options` (record_rays on).
std::vector<glm::dvec3> escaping_rays(const TransferBake& b, const TransferOptions& options, std::size_t v) {
  const auto dirs = vertex_ray_directions(options.rays, options.seed, v);
  std::vector<glm::dvec3> escaping;
  for (int r = 0; r < options.rays; ++r)
    if (b.ray_visibility[v * options.rays + r]) escaping.push_back(dirs[r]);
  return escaping;
}

// The SH expansion of the upper-hemisphere indicator: Ṽ_l0 = ½ √(2l+1) ∫_0^1 P_l, m ≠ 0: 0,
// with ∫_0^1 P_l = (P_{l-1}(0) − P_{l+1}(0)) / (2l+1) for l >= 1.
double hemisphere_coefficient(int l, int m) {
  if (m != 0) return 0.0;
  if (l == 0) return 0.5;
  return 0.5 * std::sqrt(2.0 * l + 1.0) * (legendre(l - 1, 0.0) - legendre(l + 1, 0.0)) / (2.0 * l + 1.0);
}

// ---- the ray sets ----

TEST(VisibilityRays, FibonacciSetAndRotationsAreWellFormed) {
  const auto points = spherical_fibonacci(1001);
  ASSERT_EQ(points.size(), 1001u);
  glm::dvec3 mean(0.0);
  for (const auto& p : points) {
    EXPECT_NEAR(glm::length(p), 1.0, 1e-15);
    mean += p / 1001.0;
  }
  EXPECT_NEAR(mean.z, 0.0, 1e-15);  // z_i = 1 − (2i+1)/R is symmetric
  EXPECT_LT(glm::length(mean), 2e-3);
  for (std::size_t v : {0u, 1u, 77u}) {
    const glm::dmat3 r = vertex_ray_rotation(42, v);
    const glm::dmat3 shouldbe_identity = glm::transpose(r) * r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(shouldbe_identity[i][j], i == j ? 1.0 : 0.0, 1e-14);
    EXPECT_NEAR(glm::determinant(r), 1.0, 1e-14);
  }
  // Different vertices and seeds get different rotations; the same ones the same.
  EXPECT_NE(vertex_ray_rotation(1, 0)[0][0], vertex_ray_rotation(1, 1)[0][0]);
  EXPECT_NE(vertex_ray_rotation(1, 0)[0][0], vertex_ray_rotation(2, 0)[0][0]);
  EXPECT_EQ(vertex_ray_rotation(1, 5)[1][2], vertex_ray_rotation(1, 5)[1][2]);
  const auto dirs = vertex_ray_directions(64, 3, 9);
  const auto r = vertex_ray_rotation(3, 9);
  const auto base = spherical_fibonacci(64);
  for (int i = 0; i < 64; ++i) EXPECT_LT(glm::length(dirs[i] - r * base[i]), 1e-15);
}

// ---- the open plane: V = 1 above, 0 below ----

struct PlaneCase {
  Mesh mesh = plane_grid(10.0, 20);
  std::vector<std::size_t> interior;  // vertices with |x|, |y| <= 2
  PlaneCase() {
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
      if (std::abs(mesh.vertices[v].x) <= 2.0 && std::abs(mesh.vertices[v].y) <= 2.0) interior.push_back(v);
    }
  }
};

TEST(VisibilityPlane, RaysEscapeExactlyAboveTheSurface) {
  PlaneCase plane;
  const TransferBake b = bake(plane.mesh, recorded_rays(2048, 7));
  ASSERT_EQ(b.ray_origins.size(), plane.mesh.vertices.size());
  ASSERT_EQ(b.ray_visibility.size(), plane.mesh.vertices.size() * 2048);
  int grazing = 0;
  for (std::size_t v : plane.interior) {
    const auto dirs = vertex_ray_directions(2048, 7, v);
    const glm::dvec3& origin = b.ray_origins[v];
    EXPECT_GT(origin.z, 0.0);  // above the surface, 1e-3 of the shortest edge (1) from the vertex
    EXPECT_NEAR(glm::length(origin - plane.mesh.vertices[v]), 1e-3, 1e-12);
    for (int r = 0; r < 2048; ++r) {
      const bool escaped = b.ray_visibility[v * 2048 + r] != 0;
      const glm::dvec3& x = dirs[r];
      if (x.z > 0.0) {
        EXPECT_TRUE(escaped) << "vertex " << v << " ray " << r << " z = " << x.z;
        continue;
      }
      // Below: blocked if it meets z = 0 inside the grid (keep clear of the edge by 1e-3).
      const glm::dvec3 hit = origin + (origin.z / -x.z) * x;
      if (std::abs(hit.x) < 10.0 - 1e-3 && std::abs(hit.y) < 10.0 - 1e-3) {
        EXPECT_FALSE(escaped) << "vertex " << v << " ray " << r << " z = " << x.z;
      } else {
        ++grazing;
      }
    }
  }
  EXPECT_LT(grazing, 10);  // only rays within ~3e-4 of the horizon can pass the edge
}

TEST(VisibilityPlane, VisibilityIsTheHemisphereIndicator) {
  PlaneCase plane;
  TransferOptions options;
  options.rays = 4096;
  options.visibility_order = 8;
  const TransferBake b = bake(plane.mesh, options);
  // The error of a randomly rotated 4096-point Fibonacci rule on the hemisphere indicator, measured
  // over 3000 rotations: at most 5.2e-3 per coefficient (l <= 8; median 2.2e-3) and 2.5e-3 (10/R) for
  // the escaping fraction. A wrong hemisphere or sign is off by 0.4 or more.
  constexpr double kFibonacciTolerance = 8e-3, kFractionTolerance = 4e-3;
  for (std::size_t v : plane.interior) {
    EXPECT_NEAR(b.ambient_occlusion[v], 0.5, kFractionTolerance);
    EXPECT_EQ(b.ambient_occlusion[v], b.visibility[v * 81]);
    for (int l = 0; l <= 8; ++l) {
      for (int m = -l; m <= l; ++m) {
        EXPECT_NEAR(b.visibility[v * 81 + sh_index(l, m)], hemisphere_coefficient(l, m), kFibonacciTolerance)
            << "vertex " << v << " l " << l << " m " << m;
      }
    }
  }
  EXPECT_NEAR(hemisphere_coefficient(1, 0), std::sqrt(3.0) / 4.0, 1e-15);
  EXPECT_NEAR(hemisphere_coefficient(2, 0), 0.0, 1e-15);
}

TEST(VisibilityPlane, TransferIsTheLambertLobe) {
  PlaneCase plane;
  TransferOptions options = recorded_rays(4096, 3);
  options.transfer_order = 6;
  const TransferBake b = bake(plane.mesh, options);
  const auto w_hat = ZonalLobe::lambert().coefficients(6);
  const int k = sh_count(6);
  std::vector<double> y(k);
  for (std::size_t v : plane.interior) {
    // Exact: the sum over the escaping (upper) rays of 4 max(0, z) y_lm / R.
    std::vector<double> direct(k, 0.0);
    for (const glm::dvec3& x : escaping_rays(b, options, v)) {
      sh_basis(6, x, y.data());
      for (int i = 0; i < k; ++i) direct[i] += 4.0 * std::max(0.0, x.z) * y[i] / 4096.0;
    }
    for (int i = 0; i < k; ++i) EXPECT_NEAR(b.transfer[v * k + i], direct[i], kExact);
    // Monte-Carlo: T = ŵ_l y_lm(+z) (Funk–Hecke), T_00 = 1.
    EXPECT_NEAR(b.transfer[v * k], 1.0, 1e-3);
    for (int l = 0; l <= 6; ++l) {
      for (int m = -l; m <= l; ++m) {
        const double expected = m == 0 ? w_hat[l] * std::sqrt(2.0 * l + 1.0) : 0.0;
        EXPECT_NEAR(b.transfer[v * k + sh_index(l, m)], expected, 1e-3) << "l " << l << " m " << m;
      }
    }
  }
}

// ---- closed box: nothing escapes ----

TEST(VisibilityBox, PointsInsideAClosedCubeSeeNothing) {
  Mesh inner;
  inner.vertices = {{-0.1, -0.1, 0.0}, {0.1, -0.1, 0.05}, {0.0, 0.1, -0.05}};
  inner.normals = {{0, 0, 1}, {0, 1, 1}, {1, 0, 1}};
  inner.triangles = {{0, 1, 2}};
  TransferOptions options;
  options.rays = 1024;
  options = requesting(options, 4, {3, 2}, 3, {2, 2});
  const TransferBake b = bake(inner, options, test::box(1.0));
  for (double x : b.ambient_occlusion) EXPECT_EQ(x, 0.0);
  for (double x : b.visibility) EXPECT_EQ(x, 0.0);
  for (double x : b.product_matrices) EXPECT_EQ(x, 0.0);
  for (double x : b.transfer) EXPECT_EQ(x, 0.0);
  EXPECT_EQ(b.design_offsets, std::vector<std::int64_t>(4, 0));
  EXPECT_TRUE(b.design_nodes.empty());
  EXPECT_TRUE(b.design_weights.empty());
  EXPECT_EQ(b.design_degree, 4);
  // Without the cube the same points see most of the sphere.
  const TransferBake open = bake(inner, options);
  for (double x : open.ambient_occlusion) EXPECT_GT(x, 0.3);
}

// ---- a convex object: nothing above the tangent plane ----

TEST(VisibilityConvex, IcosphereHasNoSelfOcclusionAboveTheTangentPlane) {
  const Mesh sphere = icosphere(3);
  // Inradius of the polytope: a ray from an origin q with c = −n·x passes the centre at distance
  // about |q| sqrt(1 − c²); below r_in it crosses the inscribed ball and must be blocked.
  double inradius = 1.0;
  for (const auto& f : sphere.triangles) {
    const glm::dvec3 n = glm::normalize(glm::cross(sphere.vertices[f[1]] - sphere.vertices[f[0]],
                                                   sphere.vertices[f[2]] - sphere.vertices[f[0]]));
    inradius = std::min(inradius, std::abs(glm::dot(n, sphere.vertices[f[0]])));
  }
  const TransferBake b = bake(sphere, recorded_rays(1024, 11));
  double farthest = 0.0;
  for (const auto& q : b.ray_origins) farthest = std::max(farthest, glm::length(q));
  const double r = inradius / farthest;
  const double must_block = std::sqrt(1.0 - r * r) + 1e-4;
  for (std::size_t v = 0; v < sphere.vertices.size(); ++v) {
    const auto dirs = vertex_ray_directions(1024, 11, v);
    int above = 0, not_deep = 0;
    for (int r = 0; r < 1024; ++r) {
      const double c = glm::dot(dirs[r], sphere.normals[v]);
      const bool escaped = b.ray_visibility[v * 1024 + r] != 0;
      if (c > 0.0) {
        ++above;
        EXPECT_TRUE(escaped) << "vertex " << v << " ray " << r << " n.x = " << c;
      }
      if (-c < must_block) ++not_deep;
      if (-c >= must_block) EXPECT_FALSE(escaped) << "vertex " << v << " ray " << r << " n.x = " << c;
    }
    EXPECT_GE(b.ambient_occlusion[v], above / 1024.0);
    EXPECT_LE(b.ambient_occlusion[v], not_deep / 1024.0);
    // Rays a little below the horizon pass the facets: AO ≈ 0.5 up to ~ sqrt(1 − r_in²) / 2.
    EXPECT_NEAR(b.ambient_occlusion[v], 0.5, 0.5 * must_block + 4e-3) << "vertex " << v;
  }
  EXPECT_LT(must_block, 0.1);
}

// ---- exactness against direct sums, on a mesh with real self-occlusion ----

TEST(VisibilityExact, OutputsEqualTheDirectSumsOverTheRays) {
  const Mesh m = bumpy_sphere(2);
  const TransferOptions options = requesting(recorded_rays(512, 5), 3, {4, 2}, 5, {-1, -1});
  const TransferBake b = bake(m, options);
  const int kv = sh_count(3), ks = sh_count(4), ksp = sh_count(2), kt = sh_count(5);
  std::vector<double> y(kt);
  double min_ao = 1.0;
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    std::vector<double> vis(kv, 0.0), prod(ks * ksp, 0.0), tr(kt, 0.0);
    double ao = 0.0;
    for (const glm::dvec3& x : escaping_rays(b, options, v)) {
      sh_basis(5, x, y.data());
      ao += 1.0 / 512;
      for (int i = 0; i < kv; ++i) vis[i] += y[i] / 512;
      for (int i = 0; i < ks; ++i)
        for (int j = 0; j < ksp; ++j) prod[i * ksp + j] += y[i] * y[j] / 512;
      const double c = 4.0 * std::max(0.0, glm::dot(glm::normalize(m.normals[v]), x));
      for (int i = 0; i < kt; ++i) tr[i] += c * y[i] / 512;
    }
    min_ao = std::min(min_ao, ao);
    EXPECT_NEAR(b.ambient_occlusion[v], ao, kExact);
    for (int i = 0; i < kv; ++i) EXPECT_NEAR(b.visibility[v * kv + i], vis[i], kExact);
    for (int i = 0; i < ks * ksp; ++i) EXPECT_NEAR(b.product_matrices[v * ks * ksp + i], prod[i], kExact);
    for (int i = 0; i < kt; ++i) EXPECT_NEAR(b.transfer[v * kt + i], tr[i], kExact);
  }
  EXPECT_LT(min_ao, 0.45);  // the bumps do occlude
}

TEST(VisibilityExact, HorizonTracesTheRaysAboveAndKeepsTheTransfer) {
  const Mesh m = bumpy_sphere(2);
  const TransferOptions full = requesting(recorded_rays(512, 9), -1, {-1, -1}, 5, {-1, -1});
  TransferOptions above = full;
  above.horizon = true;
  const TransferBake a = bake(m, full), b = bake(m, above);
  for (std::size_t i = 0; i < a.transfer.size(); ++i) EXPECT_NEAR(b.transfer[i], a.transfer[i], kExact);
  std::size_t below = 0;
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    const auto dirs = vertex_ray_directions(full.rays, full.seed, v);
    const glm::dvec3 n = glm::normalize(m.normals[v]);
    int escaping = 0;
    for (int r = 0; r < full.rays; ++r) {
      const std::size_t k = v * full.rays + r;
      if (glm::dot(n, dirs[r]) <= 0.0) {
        EXPECT_EQ(b.ray_visibility[k], 0) << "vertex " << v << ", ray " << r;  // blocked, not traced
        ++below;
      } else {
        EXPECT_EQ(b.ray_visibility[k], a.ray_visibility[k]) << "vertex " << v << ", ray " << r;
        escaping += b.ray_visibility[k];
      }
    }
    EXPECT_NEAR(b.ambient_occlusion[v], escaping / 512.0, kExact);  // a surface closed below
  }
  EXPECT_GT(below, m.vertices.size() * 200);  // about half the rays were not traced
  EXPECT_GT(a.transfer[0], 0.0);
}

TEST(VisibilityExact, ProductMatrixColumnZeroIsTheVisibility) {
  const Mesh m = bumpy_sphere(1);
  TransferOptions options;
  options.rays = 300;
  options = requesting(options, 4, {3, 4}, -1, {-1, -1});  // s <= s': every row l <= s has its Ṽ_lm
  const TransferBake b = bake(m, options);
  const int kv = sh_count(4), ks = sh_count(3);
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    const double* mv = b.product_matrices.data() + v * ks * kv;
    EXPECT_NEAR(mv[0], b.ambient_occlusion[v], kExact);
    for (int i = 0; i < ks; ++i) {
      EXPECT_NEAR(mv[i * kv + 0], b.visibility[v * kv + i], kExact);
      for (int j = 0; j < ks; ++j) EXPECT_NEAR(mv[i * kv + j], mv[j * kv + i], kExact);  // symmetric block
    }
  }
}

// ---- determinism ----

using test::expect_same;

TEST(VisibilityDeterminism, SameSeedSameResultForAnyThreadCount) {
  const Mesh m = bumpy_sphere(2);
  TransferOptions options = requesting(recorded_rays(256, 1234), 2, {2, 2}, 2, {2, 2});
  options.threads = 1;
  const TransferBake one = bake(m, options);
  options.threads = 2;
  const TransferBake two = bake(m, options);
  options.threads = 5;
  const TransferBake five = bake(m, options);
  options.threads = 0;
  const TransferBake all = bake(m, options);
  expect_same(one, two);
  expect_same(one, five);
  expect_same(one, all);
  options.seed = 1235;
  const TransferBake other = bake(m, options);
  EXPECT_NE(one.ray_visibility, other.ray_visibility);
  EXPECT_NE(one.visibility, other.visibility);
}

TEST(VisibilityDeterminism, ScalingByAPowerOfTwoChangesNothing) {
  Mesh m = bumpy_sphere(1);
  const TransferOptions options = recorded_rays(256, 0);
  const TransferBake unit = bake(m, options);
  for (auto& v : m.vertices) v *= 1024.0;
  const TransferBake big = bake(m, options);
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    EXPECT_EQ(big.ray_origins[v], 1024.0 * unit.ray_origins[v]);  // the origins follow the scale exactly
  }
  EXPECT_EQ(unit.ray_visibility, big.ray_visibility);
}

// ---- designs ----

class VisibilityDesign : public ::testing::TestWithParam<bool> {};

TEST_P(VisibilityDesign, DesignsReproduceTheRayMeasure) {
  const Mesh m = bumpy_sphere(1);
  constexpr int kRays = 400, kDegree = 6;
  TransferOptions options = recorded_rays(kRays, 9);
  options.design_order = 4;
  options.design_visibility_order = 2;
  options.warm_start_designs = GetParam();
  const TransferBake b = bake(m, options);
  ASSERT_EQ(b.design_degree, kDegree);
  ASSERT_EQ(b.design_offsets.size(), m.vertices.size() + 1);
  EXPECT_EQ(b.design_offsets.front(), 0);
  EXPECT_EQ(static_cast<std::size_t>(b.design_offsets.back()), b.design_nodes.size());
  const int k = sh_count(kDegree);
  std::vector<double> y(k);
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    const auto begin = b.design_offsets[v], end = b.design_offsets[v + 1];
    ASSERT_GT(end, begin) << "vertex " << v;
    EXPECT_LE(end - begin, k);
    EXPECT_LE(b.design_residuals[v], kDesignTolerance);
    const std::vector<glm::dvec3> nodes(b.design_nodes.begin() + begin, b.design_nodes.begin() + end);
    const std::vector<double> weights(b.design_weights.begin() + begin, b.design_weights.begin() + end);
    for (double w : weights) EXPECT_GT(w, 0.0);
    EXPECT_NEAR(std::accumulate(weights.begin(), weights.end(), 0.0), b.ambient_occlusion[v], kExact);
    // Σ λ y_lm(x_ν) = (1/R) Σ V_r y_lm(x_r) for l <= s + s'.
    std::vector<double> target(k, 0.0);
    for (const glm::dvec3& x : escaping_rays(b, options, v)) {
      sh_basis(kDegree, x, y.data());
      for (int i = 0; i < k; ++i) target[i] += y[i] / kRays;
    }
    const auto moments = design_moments(nodes, weights, kDegree);
    for (int i = 0; i < k; ++i) {
      EXPECT_NEAR(moments[i], target[i], 2 * kDesignTolerance * b.ambient_occlusion[v]) << "vertex " << v;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(WarmAndCold, VisibilityDesign, ::testing::Bool());

TEST(VisibilityDesignWarmStart, NoMoreNodesThanFromScratch) {
  const Mesh m = bumpy_sphere(2);
  TransferOptions options = recorded_rays(512, 3);
  options.design_order = 3;
  options.design_visibility_order = 2;
  const TransferBake warm = bake(m, options);
  options.warm_start_designs = false;
  const TransferBake cold = bake(m, options);
  long warm_max = 0, cold_max = 0;
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    warm_max = std::max<long>(warm_max, warm.design_offsets[v + 1] - warm.design_offsets[v]);
    cold_max = std::max<long>(cold_max, cold.design_offsets[v + 1] - cold.design_offsets[v]);
    EXPECT_LE(warm.design_residuals[v], kDesignTolerance);
  }
  EXPECT_LE(warm.design_nodes.size(), cold.design_nodes.size());
  EXPECT_LE(warm_max, cold_max);
  EXPECT_NE(warm.design_nodes, cold.design_nodes) << "no design was refitted";
}

// ---- progress and cancellation ----

TEST(VisibilityCancel, ProgressReturningFalseCancels) {
  const Mesh m = bumpy_sphere(1);
  TransferOptions options;
  options.rays = 64;
  options.visibility_order = 2;
  int calls = 0;
  options.progress = [&](std::size_t, std::size_t) { return ++calls < 2; };  // stop at the second report
  EXPECT_THROW(bake(m, options), BakeCancelled);
  EXPECT_EQ(calls, 2);
  options.progress = [](std::size_t, std::size_t) { return false; };
  EXPECT_THROW(bake(m, options), BakeCancelled);
}

TEST(VisibilityCancel, ProgressIsMonotoneAndEndsAtTheTotal) {
  const Mesh m = bumpy_sphere(3);
  TransferOptions options;
  options.rays = 256;
  options = requesting(options, -1, {-1, -1}, -1, {2, 2});
  std::vector<std::pair<std::size_t, std::size_t>> reports;
  options.progress = [&](std::size_t done, std::size_t total) {
    reports.emplace_back(done, total);
    return true;
  };
  const TransferBake b = bake(m, options);
  ASSERT_GE(reports.size(), 3u);
  // (0, 0) while the scene is built, then (done, count) from before the first vertex: the first
  // report with the count is where the rays' time starts (plan/bake_time.py)
  EXPECT_EQ(reports.front(), (std::pair<std::size_t, std::size_t>{0, 0}));
  const auto rays = std::find_if(reports.begin(), reports.end(), [](const auto& r) { return r.second > 0; });
  ASSERT_NE(rays, reports.end());
  EXPECT_EQ(*rays, (std::pair<std::size_t, std::size_t>{0, m.vertices.size()}));
  EXPECT_EQ(reports.back().first, m.vertices.size());
  for (auto r = reports.begin(); r != reports.end(); ++r) {
    if (r < rays)
      EXPECT_EQ(*r, (std::pair<std::size_t, std::size_t>{0, 0}));
    else
      EXPECT_EQ(r->second, m.vertices.size());
    if (r != reports.begin()) EXPECT_GE(r->first, (r - 1)->first);
  }
  EXPECT_GT(b.seconds, 0.0);
}

TEST(VisibilityCancel, ACancelInterruptsADesignInTheMiddle) {
  // One design of degree 16 from 4096 rays takes many seconds; a cancel must not wait for it.
  const Mesh m = test::square_fan(1.0, 0.0);
  TransferOptions options;
  options.rays = 4096;
  options.threads = 1;
  options.design_order = 14;
  options.design_visibility_order = 2;
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  Clock::time_point cancelled_at{};
  options.progress = [&](std::size_t, std::size_t) {
    if (Clock::now() - start < std::chrono::milliseconds(300)) return true;
    if (cancelled_at == Clock::time_point{}) cancelled_at = Clock::now();
    return false;
  };
  EXPECT_THROW(bake(m, options), BakeCancelled);
  ASSERT_NE(cancelled_at, Clock::time_point{});
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - cancelled_at).count(), 1.0);
}

TEST(VisibilityCancel, CancelFlagAndThrowingProgressStopTheBake) {
  const Mesh m = bumpy_sphere(3);
  TransferOptions options;
  options.rays = 256;
  options = requesting(options, -1, {-1, -1}, -1, {4, 2});
  std::atomic<bool> cancel{true};
  options.cancel = &cancel;
  EXPECT_THROW(bake(m, options), BakeCancelled);

  // Raised mid-bake by another party: the flag is set from the progress callback once work started.
  cancel = false;
  std::size_t seen = 0;
  options.progress = [&](std::size_t done, std::size_t) {
    seen = done;
    if (done > 0) cancel = true;
    return true;
  };
  try {
    bake(m, options);
    FAIL() << "not cancelled";
  } catch (const BakeCancelled& e) {
    EXPECT_LT(seen, m.vertices.size());
    EXPECT_NE(std::string(e.what()).find("cancelled"), std::string::npos);
  }

  struct Stop {};
  options.cancel = nullptr;
  options.progress = [](std::size_t done, std::size_t) {
    if (done > 0) throw Stop{};
    return true;
  };
  EXPECT_THROW(bake(m, options), Stop);
}

// ---- bad input ----

TEST(VisibilityInput, BadInputThrowsInvalidArgument) {
  const Mesh good = icosphere(0);
  TransferOptions options;
  options.rays = 16;
  auto expect_invalid = [&](Mesh m, TransferOptions o, const OccluderMesh& occ = {}) {
    EXPECT_THROW(bake_transfer(m.vertices, m.normals, m.triangles, o, occ), std::invalid_argument);
  };
  EXPECT_NO_THROW(bake(good, options));
  Mesh m = good;
  m.vertices[3].y = std::nan("");
  expect_invalid(m, options);
  m = good;
  m.vertices[0].x = INFINITY;
  expect_invalid(m, options);
  m = good;
  m.triangles[4][1] = 12;
  expect_invalid(m, options);
  m = good;
  m.triangles[0][2] = -1;
  expect_invalid(m, options);
  m = good;
  m.normals.pop_back();
  expect_invalid(m, options);
  expect_invalid(Mesh{}, options);
  OccluderMesh occ = test::box(2.0);
  occ.triangles[3][0] = 8;
  expect_invalid(good, options, occ);
  occ = test::box(2.0);
  occ.vertices[1].z = std::nan("");
  expect_invalid(good, options, occ);

  auto with = [&](auto change) {
    TransferOptions o = options;
    change(o);
    return o;
  };
  expect_invalid(good, with([](TransferOptions& o) { o.rays = 0; }));
  expect_invalid(good, with([](TransferOptions& o) { o.rays = -5; }));
  expect_invalid(good, with([](TransferOptions& o) { o.threads = -1; }));
  expect_invalid(good, with([](TransferOptions& o) { o.visibility_order = 9; }));
  expect_invalid(good, with([](TransferOptions& o) { o.visibility_order = -2; }));
  expect_invalid(good, with([](TransferOptions& o) { o.transfer_order = 17; }));
  expect_invalid(good, with([](TransferOptions& o) { o.product_order = 2; }));  // s' missing
  expect_invalid(good, with([](TransferOptions& o) { o.product_order = 17, o.product_visibility_order = 2; }));
  expect_invalid(good, with([](TransferOptions& o) { o.product_order = 2, o.product_visibility_order = 9; }));
  expect_invalid(good, with([](TransferOptions& o) { o.design_visibility_order = 2; }));  // s missing
  expect_invalid(good, with([](TransferOptions& o) { o.design_order = 2, o.design_visibility_order = 9; }));
  EXPECT_THROW(bake_visibility(good.vertices, good.normals, good.triangles, 9, 16), std::invalid_argument);

  // Degenerate triangles and a probe without triangles are fine.
  m = good;
  m.triangles.push_back({0, 0, 1});
  m.triangles.push_back({2, 2, 2});
  EXPECT_NO_THROW(bake(m, options));
  m.triangles.clear();
  const TransferBake probes = bake(m, options);
  for (double ao : probes.ambient_occlusion) EXPECT_EQ(ao, 1.0);
}

TEST(Visibility, ZeroAndNonFiniteNormalsGetTheirFacesNormal) {
  // A zero normal used to fail the whole bake. Now the vertex is baked with the area-weighted
  // normal of its faces (outward on a closed sphere: the same AO and T as with its own normal)
  // and listed; a vertex without faces gets +Z.
  const Mesh good = test::icosphere(1);
  TransferOptions options;
  options.rays = 256;
  options.transfer_order = 2;
  Mesh m = good;
  m.normals[2] = glm::dvec3(0.0);
  m.normals[5] = glm::dvec3(std::nan(""), 0.0, 1.0);
  m.normals[7].z = -INFINITY;
  m.vertices.push_back({5.0, 0.0, 0.0});  // a loose vertex
  m.normals.push_back(glm::dvec3(0.0));
  const TransferBake repaired = bake_transfer(m.vertices, m.normals, m.triangles, options);
  const TransferBake reference = bake_transfer(good.vertices, good.normals, good.triangles, options);
  const std::int64_t loose = static_cast<std::int64_t>(good.vertices.size());
  EXPECT_EQ(repaired.fallback_normals, (std::vector<std::int64_t>{2, 5, 7, loose}));
  EXPECT_TRUE(reference.fallback_normals.empty());
  for (std::size_t v : {2, 5, 7}) {
    // The icosphere's vertex normals are its faces' normals up to the tessellation (a few degrees).
    EXPECT_NEAR(repaired.ambient_occlusion[v], reference.ambient_occlusion[v], 0.02) << v;
    EXPECT_NEAR(repaired.transfer[9 * v], reference.transfer[9 * v], 0.05) << v;
  }
  // Only the sphere 4 radii away blocks its rays: a cone of (1 − cos asin(1/5))/2 ≈ 1 %.
  EXPECT_NEAR(repaired.ambient_occlusion[loose], 0.99, 0.01);
  // The normals baked with are returned: the given ones unchanged, the fallbacks in their place.
  ASSERT_EQ(repaired.normals.size(), m.vertices.size());
  EXPECT_LT(glm::length(repaired.normals[0] - glm::normalize(good.normals[0])), 1e-15);
  for (std::size_t v : {2, 5, 7}) EXPECT_GT(glm::dot(repaired.normals[v], good.normals[v]), 0.99) << v;
  EXPECT_EQ(repaired.normals[loose], glm::dvec3(0.0, 0.0, 1.0));
  // NaN positions stay an error.
  m.vertices[0].x = std::nan("");
  EXPECT_THROW(bake_transfer(m.vertices, m.normals, m.triangles, options), std::invalid_argument);
}

TEST(VisibilityWrapper, BakeVisibilityIsTheTransferBakesVisibility) {
  const Mesh m = bumpy_sphere(1);
  const OccluderMesh ground = test::ground_quad(5.0, -1.2);
  TransferOptions options;
  options.rays = 128;
  options.seed = 77;
  options.visibility_order = 3;
  const TransferBake b = bake(m, options, ground);
  EXPECT_EQ(bake_visibility(m.vertices, m.normals, m.triangles, 3, 128, 77, ground), b.visibility);
  // The ground occludes: lower visibility than without it for the lowest vertices.
  const TransferBake free = bake(m, options);
  double with_ground = 0.0, without = 0.0;
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    with_ground += b.ambient_occlusion[v];
    without += free.ambient_occlusion[v];
  }
  EXPECT_LT(with_ground, without - 1.0);
}

}  // namespace
}  // namespace sd
