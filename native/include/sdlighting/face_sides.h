// Which sides of a mesh's faces a viewer can see (issue 32, item 2). Cycles lights and shadows
// both sides of every face, shading a face seen from behind with its normal turned towards the
// viewer; the bake shades one side per vertex, the side its normal is on. face_sides says, per
// triangle, what the baked copy needs so that every side a viewer outside the solids can see has
// its own vertices:
//
// - a closed, orientable piece of surface (its triangles joined edge to edge, every edge shared by
//   exactly two, their windings made to agree across each edge) bounds a solid: only its outside
//   shows. The outside is the side the winding points to when the signed volume is positive; a
//   face wound the other way (a flipped face, a mesh turned inside out) is kFlipped: its winding
//   and normals are to be reversed, and it is baked and drawn once, as before.
// - any other piece (an open surface: a ground plane, a wall, a leaf, a cup without thickness; a
//   non-manifold or non-orientable piece) has fronts and possibly visible backs. Up to kSideFaces
//   of its faces, spread over it, look at their backs, each with the rays of kSideRays directions
//   from a point just behind its centroid (in the face's own frame, so that turning or mirroring
//   the mesh changes nothing). A ray met from behind by the first surface it meets (by that
//   surface's winding) starts inside a solid; when at least kSeenShare of the piece's rays do not,
//   its backs can be seen and every face of it is kBoth: it gets a reverse copy with the normals
//   turned (a sheet, coincidence.h), and each copy is drawn only from its own side. Otherwise
//   (a head open only at its eyes, a face inside a solid) its faces are kFront.
// - a face whose reverse is already in the mesh (a user's back-to-back faces) is kSheet.
// - a face without area is kFront: it has no side.
#pragma once

#include "sdlighting/mesh.h"

#include <glm/vec3.hpp>

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

namespace sd {

/// What the baked copy needs of a triangle (see the file comment).
enum class FaceSides : std::uint8_t {
  kFront = 0,    ///< as wound: the back is inside a solid, or the face has no area
  kFlipped = 1,  ///< reversed: the front is inside the solid the face bounds
  kBoth = 2,     ///< both: the back can be seen too, and needs a reverse copy
  kSheet = 3,    ///< both, already: the reverse is another triangle of the mesh
};

/// The rays that look at the back of a face of an open piece: the back half of a Fibonacci set
/// of this size and its mirror image.
constexpr int kSideRays = 16;
/// The faces of an open piece that look at their backs, at most.
constexpr int kSideFaces = 64;
/// The share of an open piece's back rays that must start outside every solid for its backs to be
/// seen.
constexpr double kSeenShare = 0.1;

/// How face_sides runs.
struct FaceSidesOptions {
  int threads = 0;  ///< worker threads; 0 = every hardware thread
  /// As TransferOptions::progress, over the triangles looked at by rays.
  std::function<bool(std::size_t done, std::size_t total)> progress;
  const std::atomic<bool>* cancel = nullptr;  ///< true cancels (BakeCancelled)
};

/// The sides of every triangle of the mesh (see the file comment), with `occluders` among the
/// surfaces that can hide a back. Throws std::invalid_argument on bad input (as bake_transfer),
/// BakeCancelled when cancelled.
std::vector<FaceSides> face_sides(const std::vector<glm::dvec3>& vertices, const std::vector<Triangle>& triangles,
                                  const OccluderMesh& occluders = {}, const FaceSidesOptions& options = {});

}  // namespace sd
