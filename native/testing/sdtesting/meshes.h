// Test meshes shared by the C++ tests and the benchmarks (header-only, namespace sd::test): a flat
// grid, an icosphere with and without bumps, a box and a square fan to bake, and a closed box and
// a ground quad as occluders.
#pragma once

#include "sdlighting/mesh.h"

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace sd::test {

/// A mesh to bake: vertices, their normals and triangles.
struct Mesh {
  std::vector<glm::dvec3> vertices, normals;
  std::vector<Triangle> triangles;
};

/// A flat square grid in z = 0 of half-size `half`, `cells` × `cells` quads, normals +z.
inline Mesh plane_grid(double half, int cells) {
  Mesh m;
  for (int j = 0; j <= cells; ++j) {
    for (int i = 0; i <= cells; ++i) {
      m.vertices.emplace_back(-half + 2.0 * half * i / cells, -half + 2.0 * half * j / cells, 0.0);
      m.normals.emplace_back(0.0, 0.0, 1.0);
    }
  }
  auto at = [&](int i, int j) { return static_cast<std::int64_t>(j * (cells + 1) + i); };
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return m;
}

/// The unit icosphere after `levels` subdivisions, with the radial normals.
inline Mesh icosphere(int levels) {
  const double t = 0.5 * (1.0 + std::sqrt(5.0));
  Mesh m;
  for (const auto& v : {glm::dvec3(-1, t, 0), glm::dvec3(1, t, 0), glm::dvec3(-1, -t, 0), glm::dvec3(1, -t, 0),
                        glm::dvec3(0, -1, t), glm::dvec3(0, 1, t), glm::dvec3(0, -1, -t), glm::dvec3(0, 1, -t),
                        glm::dvec3(t, 0, -1), glm::dvec3(t, 0, 1), glm::dvec3(-t, 0, -1), glm::dvec3(-t, 0, 1)}) {
    m.vertices.push_back(glm::normalize(v));
  }
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> midpoints;
    auto midpoint = [&](std::int64_t a, std::int64_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto found = midpoints.find(key);
      if (found != midpoints.end()) return found->second;
      m.vertices.push_back(glm::normalize(m.vertices[a] + m.vertices[b]));
      const auto index = static_cast<std::int64_t>(m.vertices.size() - 1);
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<Triangle> finer;
    for (const auto& f : m.triangles) {
      const auto a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      finer.push_back({f[0], a, c});
      finer.push_back({f[1], b, a});
      finer.push_back({f[2], c, b});
      finer.push_back({a, b, c});
    }
    m.triangles = std::move(finer);
  }
  m.normals = m.vertices;
  return m;
}

/// Sets the normals to the area-weighted sums of the faces' normals, normalised.
inline void face_normals(Mesh& m) {
  m.normals.assign(m.vertices.size(), glm::dvec3(0.0));
  for (const auto& f : m.triangles) {
    const glm::dvec3 n = glm::cross(m.vertices[f[1]] - m.vertices[f[0]], m.vertices[f[2]] - m.vertices[f[0]]);
    for (int k = 0; k < 3; ++k) m.normals[f[k]] += n;
  }
  for (auto& n : m.normals) n = glm::normalize(n);
}

/// An icosphere with bumps: real self-occlusion, normals from the faces.
inline Mesh bumpy_sphere(int levels) {
  Mesh m = icosphere(levels);
  for (auto& v : m.vertices) v *= 1.0 + 0.25 * std::sin(5.0 * v.x) * std::sin(4.0 * v.y + 1.0) * std::sin(3.0 * v.z);
  face_normals(m);
  return m;
}

/// The box [lo, hi] to bake: 8 welded corners with their averaged normals, outward winding.
inline Mesh solid_box(const glm::dvec3& lo, const glm::dvec3& hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    m.normals.push_back(glm::normalize(glm::dvec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1)));
  }
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

/// A square of half-size `half` at height z facing +z (or −z) to bake: four triangles around a
/// centre vertex (index 0), every vertex with the face's normal.
inline Mesh square_fan(double half, double z, bool up = true) {
  Mesh m;
  m.vertices = {{0, 0, z}, {-half, -half, z}, {half, -half, z}, {half, half, z}, {-half, half, z}};
  m.normals.assign(5, glm::dvec3(0, 0, up ? 1 : -1));
  for (std::int64_t k = 1; k <= 4; ++k) {
    const std::int64_t next = k % 4 + 1;
    m.triangles.push_back(up ? Triangle{0, k, next} : Triangle{0, next, k});
  }
  return m;
}

/// The closed axis-aligned cube [-h, h]³ as 12 triangles (an occluder).
inline OccluderMesh box(double h) {
  OccluderMesh c;
  for (int i = 0; i < 8; ++i) c.vertices.emplace_back(i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h);
  c.triangles = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                 {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  return c;
}

/// A square ground quad [-half, half]² at height z (an occluder).
inline OccluderMesh ground_quad(double half, double z) {
  return {{{-half, -half, z}, {half, -half, z}, {half, half, z}, {-half, half, z}}, {{0, 1, 2}, {0, 2, 3}}};
}

}  // namespace sd::test
