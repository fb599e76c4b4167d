// The orthonormal basis around a direction, the one builder of the library: the rotation g_a of
// Theorem 2.1 (any rotation taking e3 to a lobe axis a), the directions around the lobe axis that
// the Monte Carlo reference samples, and the tangent plane in which a design fit moves a node.
// Private to the library.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <cmath>

namespace sd {

/// Unit tangents t1, t2 with (t1, t2, a) a right-handed orthonormal basis, for a unit a, so that
/// g_a x = x.x t1 + x.y t2 + x.z a: t1 = a × h / |a × h| with h the x axis, or the y axis where
/// |a.x| >= 0.6 (so |a × h| >= 0.6: no cancellation), and t2 = a × t1. The twist does not matter
/// for a zonal lobe (the GLSL evaluator takes Duff et al.'s basis, another twist).
inline void orthonormal_basis(const glm::dvec3& a, glm::dvec3& t1, glm::dvec3& t2) {
  const glm::dvec3 helper = std::abs(a.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  t1 = glm::normalize(glm::cross(a, helper));
  t2 = glm::cross(a, t1);
}

}  // namespace sd
