// Triangle meshes as the ray tracers take them (the visibility bake and the reference): points
// and normals as glm::dvec3 arrays, triangles as index triples.
#pragma once

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace sd {

/// A triangle as three vertex indices (each must be in [0, vertex count)).
using Triangle = std::array<std::int64_t, 3>;

/// Triangles that block rays without being baked (a ground plane, other objects).
struct OccluderMesh {
  std::vector<glm::dvec3> vertices;
  std::vector<Triangle> triangles;
};

}  // namespace sd
