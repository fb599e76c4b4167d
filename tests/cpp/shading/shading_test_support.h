// Random shading inputs shared by the shading tests (test_shading.cpp, the randomized
// test_shading_properties.cpp): scenes of random light, normals, views and Ṽ, visibility given by
// ray samples with its product matrices and per-vertex designs, and a relative comparison.
#pragma once

#include "sdlighting/shading.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/weighted_design.h"
#include "sdtesting/sphere.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace sd::test {

struct Scene {
  int s = 4, s_v = 2;
  std::vector<double> light, normals, views, visibility;
  size_t count = 0;
};

/// Gaussian light of order s (L_00 = 5 per channel), random unit normals and views, Gaussian Ṽ of
/// order s_v around Ṽ_00 = 0.7, for `count` vertices.
inline Scene random_scene(size_t count, int s, int s_v, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Scene scene;
  scene.s = s;
  scene.s_v = s_v;
  scene.count = count;
  scene.light.resize(3 * sh_count(s));
  for (double& v : scene.light) v = normal(rng);
  scene.light[0] = scene.light[1] = scene.light[2] = 5.0;
  scene.visibility.resize(count * sh_count(s_v));
  for (double& v : scene.visibility) v = 0.3 * normal(rng);
  for (size_t p = 0; p < count; ++p) {
    scene.visibility[p * sh_count(s_v)] = 0.7;
    for (auto* field : {&scene.normals, &scene.views}) {
      const glm::dvec3 d = random_direction(rng, normal);
      field->insert(field->end(), {d.x, d.y, d.z});
    }
  }
  return scene;
}

inline ShadingInputs inputs(const Scene& scene, Material material) {
  ShadingInputs in;
  in.light_order = scene.s;
  in.light = scene.light.data();
  in.vertex_count = scene.count;
  in.normals = scene.normals.data();
  in.view_dirs = scene.views.data();
  in.material = material;
  return in;
}

/// A visibility function per vertex given by `rays` random rays — escaping where the ray clears a
/// random tilted plane — as the bake stores it: product matrices M of orders (s, s_v) for
/// (8)-(9) and designs of degree s + s_v of its discrete measure for (13).
struct RayVisibility {
  std::vector<double> matrices, nodes, weights;
  std::vector<int64_t> offsets = {0};
  VertexDesigns designs() const { return VertexDesigns{offsets.data(), nodes.data(), weights.data()}; }
};

inline RayVisibility random_ray_visibility(size_t count, int s, int s_v, int rays, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const int k = sh_count(s), kv = sh_count(s_v);
  RayVisibility out;
  std::vector<double> y(sh_count(std::max(s, s_v)));
  for (size_t p = 0; p < count; ++p) {
    const glm::dvec3 occluder = random_direction(rng, normal);
    std::vector<glm::dvec3> escaping;
    std::vector<double> m(size_t(k) * kv, 0.0);
    for (int r = 0; r < rays; ++r) {
      const glm::dvec3 x = random_direction(rng, normal);
      if (glm::dot(x, occluder) < 0.3) continue;
      escaping.push_back(x);
      sh_basis(std::max(s, s_v), x, y.data());
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < kv; ++j) m[size_t(i) * kv + j] += y[i] * y[j] / rays;
    }
    out.matrices.insert(out.matrices.end(), m.begin(), m.end());
    const SphericalDesign design = weighted_design(escaping, std::vector<double>(escaping.size(), 1.0 / rays), s + s_v);
    for (int nu = 0; nu < design.size(); ++nu) {
      out.nodes.insert(out.nodes.end(), {design.nodes[nu].x, design.nodes[nu].y, design.nodes[nu].z});
      out.weights.push_back(design.weights[nu]);
    }
    out.offsets.push_back(static_cast<int64_t>(out.weights.size()));
  }
  return out;
}

/// max |a − b| <= tolerance × max |b| (and b not all zero).
inline void expect_relative_equal(const std::vector<double>& a, const std::vector<double>& b, double tolerance) {
  double scale = 0.0, error = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    scale = std::max(scale, std::abs(b[i]));
    error = std::max(error, std::abs(a[i] - b[i]));
  }
  EXPECT_GT(scale, 0.0);
  EXPECT_LE(error, tolerance * scale) << "max error " << error << " of scale " << scale;
}

}  // namespace sd::test
