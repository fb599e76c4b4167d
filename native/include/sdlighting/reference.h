// The ground truth every method is measured against: eq. (1) by Monte Carlo, with the
// full-resolution environment (not band-limited), ray-traced visibility and the exact lobe.
#pragma once

#include "sdlighting/environment.h"
#include "sdlighting/mesh.h"
#include "sdlighting/shading.h"

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace sd {

/// How much work the reference does.
struct ReferenceOptions {
  int samples = 4096;       ///< sample pairs per vertex (each pair traces up to two rays)
  std::uint64_t seed = 0;   ///< the estimate depends on (seed, vertex) only, not on threads
  int threads = 0;          ///< 0: every hardware thread
  /// V is also 0 below each vertex's own tangent plane (n·x <= 0): with no triangles, the lobe over
  /// the hemisphere the surface faces - what the split sum's glossy light stands for.
  bool horizon = false;
  /// As TransferOptions::progress, over the vertices ((0, 0) while the scene is built; the calling
  /// thread then only reports); returning false cancels (BakeCancelled).
  std::function<bool(std::size_t done, std::size_t total)> progress;
  const std::atomic<bool>* cancel = nullptr;  ///< true cancels (BakeCancelled)
};

/// B per vertex and the Monte Carlo standard error of each value (both vertex_count × 3).
struct ReferenceResult {
  std::vector<double> radiance;
  std::vector<double> standard_error;
  int samples = 0;
};

/// B_p(v, g) = ∫ L(g x) V_p(x) w(a_p·x) dμ(x), eq. (1), for every vertex: each sample pair draws one
/// direction from the environment (EnvironmentSampler, texels ∝ luminance) and one from the lobe
/// (exactly: t = u^(1/(σ+1))), combined by the balance heuristic (multiple importance sampling),
/// so that both a sun and a narrow highlight converge. V is traced with Embree against the
/// object's triangles and the occluders from the bake's ray origins (src/bake/traced_scene.h). L
/// is the map's texels (piecewise constant), unfiltered. `views` (unit, vertex → eye) are read for Phong only.
/// `rotation` must be a rotation (proper_rotation's checks, sh_rotation.h: float32 ones pass).
/// Throws std::invalid_argument on bad input (as bake_transfer does, samples < 1, a zero or
/// non-finite view for Phong, a matrix that is no rotation).
ReferenceResult shade_reference(const Environment& environment, const glm::dmat3& rotation,
                                const std::vector<glm::dvec3>& vertices, const std::vector<glm::dvec3>& normals,
                                const std::vector<glm::dvec3>& views, const std::vector<Triangle>& triangles,
                                const Material& material, const ReferenceOptions& options,
                                const OccluderMesh& occluders = {});

}  // namespace sd
