// The classification behind face_sides (sdlighting/face_sides.h) on a scene already built: the
// bake classifies the object's and the occluders' triangles in the scene it traces, to know which
// bound a solid (and which way) and which are sheets. Private to the library.
#pragma once

#include "sdlighting/face_sides.h"

#include "bake/embree_scene.h"
#include "util/parallel_for.h"

#include <glm/geometric.hpp>

#include <cstdint>
#include <vector>

namespace sd {

/// Where a triangle is in an EmbreeScene.
struct SceneFace {
  int geometry;
  unsigned primitive;
};

/// A probe length past every surface of a scene within the box [lo, hi].
inline double reach_past(const glm::dvec3& lo, const glm::dvec3& hi) { return 4.0 * glm::length(hi - lo) + 1.0; }

/// face_sides of `triangles` over `points` (in the scene's space). The backs are looked at in
/// `scene` (committed, its triangles read as wound), which holds triangle t as in_scene[t];
/// `reach`: a distance past every surface. Throws BakeCancelled when cancelled.
std::vector<FaceSides> classify_sides(const std::vector<glm::dvec3>& points, const std::vector<Triangle>& triangles,
                                      const EmbreeScene& scene, const std::vector<SceneFace>& in_scene, double reach,
                                      const ParallelOptions& parallel);

/// How a probe reads a triangle of the given sides (EmbreeScene::orient): +1 as wound (kFront),
/// -1 the other way (kFlipped), 0 a sheet (kBoth, kSheet).
std::int8_t probe_orientation(FaceSides sides);

}  // namespace sd
