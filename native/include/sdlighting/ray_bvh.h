// The scene's triangles as a bounding volume hierarchy laid out flat, for the rays the live shading
// traces per pixel (issue 28: a sharp glossy lobe's visibility, which no per-vertex or low-order
// visibility carries; shaders/sd_ray_bvh.glsl walks it). Embree builds the hierarchy
// (rtcBuildBVH, its SAH builder on every core); this lays it out in the arrays a texture holds.
#pragma once

#include "sdlighting/mesh.h"

#include <cstdint>
#include <vector>

namespace sd {

/// Most triangles in one leaf: the shader tests a leaf's triangles one after another.
constexpr int kRayBvhLeafTriangles = 4;
/// Deepest leaf below the root (Embree's builder keeps to it): a walk's stack holds at most one
/// more entry.
constexpr int kRayBvhMaxDepth = 32;
/// Most triangles a RayBvh holds: node and triangle indices are stored as float32, exact below 2^24.
constexpr std::int64_t kMaxRayBvhTriangles = std::int64_t(1) << 22;

/// A binary BVH in depth-first order: node 0 is the root, an inner node's first child follows it.
struct RayBvh {
  /// Per node 8 floats: its box's lower x, y, z, then a, its box's upper x, y, z, then b. An inner
  /// node has a = its first child's index, b = its second's; a leaf has a = −1 − its first
  /// triangle's index and b = how many triangles follow from there (1..kRayBvhLeafTriangles).
  std::vector<float> nodes;
  /// Per triangle, in the leaves' order, 12 floats: its corners p0, p1 − p0, p2 − p0 (each x, y, z,
  /// then 0), what a ray–triangle test reads.
  std::vector<float> triangles;
  /// Per entry of `triangles`, the index of that triangle in the input.
  std::vector<std::int64_t> order;

  std::size_t node_count() const { return nodes.size() / 8; }
  std::size_t triangle_count() const { return order.size(); }
};

/// The BVH of `triangles` over `vertices`. Degenerate triangles (zero area) are left out: no ray
/// can hit them. No triangles give an empty RayBvh (no nodes). Throws std::invalid_argument for an
/// index out of range, a point that is not finite, or more than kMaxRayBvhTriangles triangles.
RayBvh build_ray_bvh(const std::vector<glm::dvec3>& vertices, const std::vector<Triangle>& triangles);

/// Whether the ray origin + t dir, t in (t_min, ∞), hits a triangle of `bvh`: the walk the shader
/// makes (the same order, tests and float32 arithmetic), for the tests. Throws
/// std::invalid_argument for a tree deeper than kRayBvhMaxDepth (not one build_ray_bvh made).
bool ray_bvh_occluded(const RayBvh& bvh, const glm::vec3& origin, const glm::vec3& dir, float t_min);

}  // namespace sd
