// Points and faces that coincide. Private to the library.
//
// A mesh split at hard edges or seams (glTF, the add-on's corner copies) has several vertices at
// one point, and every face through the point bounds the free space next to it, whichever copy
// it belongs to. A two-sided sheet is a face given twice over the same points, once in each
// winding (the add-on's back faces, bake/geometry.py; a user's own back-to-back faces): Cycles
// shades each side with its own normal, and both copies are one surface to a ray.
#pragma once

#include "sdlighting/mesh.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace sd {

/// Each point's representative among the points equal to it (the first by index).
std::vector<unsigned> coincident_representatives(const std::vector<glm::dvec3>& points);

/// The triangles with every index replaced by its representative.
std::vector<Triangle> welded_triangles(const std::vector<Triangle>& triangles,
                                       const std::vector<unsigned>& representative);

/// For each triangle of `welded` (indices already welded), the first triangle over the same three
/// points in the same winding: itself, or the one it repeats (a face given twice: the add-on's
/// samples joined with the whole mesh as occluders).
std::vector<std::int64_t> first_copies(const std::vector<Triangle>& welded);

/// For each triangle of `welded` (indices already welded), the index of the triangle over the
/// same three points in the opposite winding, or -1. Triangles pair one to one (of three copies
/// two pair and the third keeps -1); a triangle with a repeated point has no twin.
std::vector<std::int64_t> reversed_twins(const std::vector<Triangle>& welded);

}  // namespace sd
