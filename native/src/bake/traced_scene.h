// The scene a bake or a reference traces, and the point each vertex's rays start from. Private to
// the library.
//
// A ray that starts at a vertex p, or at p + εn, meets the surfaces through p at t ≈ 0 in float32:
// at a concave hard edge whose vertices are split (glTF), p + εn lies in the plane of the wall rising
// from the edge and the open quarter-space reads as blocked; at the bottom corner of a box standing
// on a floor, p + εn lies below the floor and the lower half-space leaks in. So each vertex's rays
// start at a point q = p + η u in free space next to p:
// "The triangles around p" are all the object's triangles through the point p, also those of other
// vertices at exactly p (a mesh split at hard edges or seams).
//   η = kOriginOffset × the shortest edge of the triangles around p (the size of the local
//       geometry: thin slabs and fine detail stay resolved, the scale of the object does not
//       matter), at least kOriginFloat × |p|∞ in the traced space (above float32 rounding);
//   u is the first of these candidates whose q passes the probes: n + t, t the part of (c − p)/h
//       across n, at most unit length — along the normal and into the faces around p, towards the
//       area-weighted mean c of their centroids (h the shortest edge), as Cycles' bakes move their
//       ray origins into the face; across n only, since at a convex hard edge c lies back along −n
//       and the whole (c − p)/h cancelled n, leaving q in the plane of p's faces —, then n, then the
//       faces' own area-weighted normal m (by their winding: it survives a flipped n), then
//       kCandidateDirections spherical-Fibonacci directions by decreasing u·m;
//   q fails a probe when the first surface a segment from q meets is met from behind (the side
//       opposite its outward normal: q is then inside a solid or under a surface) or is a sheet
//       crossed before the segment's end (q is on its other side). Which faces bound a solid and
//       which way they face is classify_sides' answer (face_sides.h): closed pieces by their
//       volume, open faces whose back is hidden inside a solid by their winding; every other face
//       (a ground plane, a wall, a leaf, whatever its winding) is a sheet, free on both sides.
//       The probes run from q through p to 2|q − p| with p's own faces skipped (other
//       surfaces through p: a floor the object stands on) and, unless q is in front of every face
//       around p (then no segment from q can meet them from behind) with no sheet through p, from
//       q to the centroid of each face around p (the largest kProbedFaces).
//   When no candidate passes (an enclosed vertex, a mesh with inconsistent winding) the first is used.
//   A vertex without faces (a probe point) starts at p + η n, η = kFacelessOffset × the diagonal of
//   the object's bounding box (of the occluders' when the object is one point), at least the floor.
// A face given with both windings (a face and its reverse over the same points: coincidence.h) is
// one sheet to the rays; a vertex of the reverse copy alone is on the sheet's back, its faces
// the reverse copies, so its origin is found on that side.
// The traced space is the object's space shifted by the centre of its vertices' bounding box, so
// Embree's float32 keeps the object's own precision however far from the origin it sits.
#pragma once

#include "sdlighting/visibility.h"

#include "bake/embree_scene.h"
#include "util/parallel_for.h"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace sd {

/// η = kOriginOffset × the shortest edge around the vertex (see the file comment).
constexpr double kOriginOffset = 1e-3;
/// ... but at least kOriginFloat × the vertex's largest coordinate in the traced space.
constexpr double kOriginFloat = 1e-5;
/// The largest coordinate's magnitude, which kOriginFloat scales: what float rounding is relative to.
inline double largest_coordinate(const glm::dvec3& p) {
  return std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
}
/// The faces around a vertex whose centroids a candidate origin is probed towards, largest first.
constexpr int kProbedFaces = 16;
/// η of a vertex without faces, relative to the object's bounding-box diagonal.
constexpr double kFacelessOffset = 1e-4;
/// A sheet met within this fraction of a probe's length from its end is at the end (float32
/// rounding of the hit; the probes are η long).
constexpr double kSheetTolerance = 0.05;
/// Spherical-Fibonacci candidates tried after n + (c − p)/h, n and the faces' normal.
constexpr int kCandidateDirections = 64;

/// The object's and the occluders' triangles in one Embree scene, in the traced space, and every
/// object vertex's ray origin.
class TracedScene {
 public:
  /// vertices/unit_normals/triangles: the object (checked by the caller); occluders: other
  /// blocking triangles; parallel: how the origins are found (threads, progress over the vertices,
  /// cancel); offset_origins: false gives every vertex the faceless rule
  /// (TransferOptions::offset_origins). Throws BakeCancelled when cancelled.
  TracedScene(const std::vector<glm::dvec3>& vertices, const std::vector<glm::dvec3>& unit_normals,
              const std::vector<Triangle>& triangles, const OccluderMesh& occluders,
              const ParallelOptions& parallel, bool offset_origins = true);

  const EmbreeScene& scene() const { return scene_; }
  /// Vertex v's ray origin in the traced space (the one scene() is built in).
  const glm::dvec3& origin(std::size_t v) const { return origins_[v]; }
  /// Every ray origin in object space.
  std::vector<glm::dvec3> object_space_origins() const;

 private:
  glm::dvec3 centre_;
  EmbreeScene scene_;
  std::vector<glm::dvec3> origins_;
};

}  // namespace sd
