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
// - any other face (an open surface: a ground plane, a wall, a leaf; a non-manifold or
//   non-orientable piece) has a front and possibly a visible back. Its back is looked at by
//   kSideRays rays from a point just behind its centroid: when every one of them meets a surface
//   from behind (by that surface's winding), the point lies inside a solid and the back is hidden
//   (kFront); otherwise the face is kBoth: it gets a reverse copy with the normals turned (a
//   sheet, coincidence.h), and each copy is drawn only from its own side.
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

/// Rays that look at the back of a face of an open surface.
constexpr int kSideRays = 16;

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
