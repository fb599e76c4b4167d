// The order in which a bake visits its vertices when each vertex's design is refitted from an
// already-built neighbour's (Theorem 2.2 warm starts, sdlighting/weighted_design.h). Private to the
// library.
#pragma once

#include "sdlighting/mesh.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace sd {

/// Vertices in depth-first preorder over the mesh's edges, cut into groups of `group` consecutive
/// positions that one worker runs in order. Within a group, each vertex after the first starts from
/// an earlier vertex's design: usually a neighbour (its depth-first parent), else the previous
/// position; across groups nothing is shared, so the results do not depend on which worker runs
/// which group.
struct VertexWalk {
  std::size_t group = 1;
  std::vector<std::size_t> order;     ///< [N] the vertex at each position
  /// [N] per position, the earlier position in the same group to warm-start from, or -1 for a
  /// group's first: the latest-visited neighbour in the group; for a vertex without one (its
  /// parent in an earlier group, or no edges), the previous position.
  std::vector<std::int64_t> source;
};

/// The walk of `vertex_count` vertices joined by `triangles` (indices already validated), in
/// groups of `group` >= 1. Components are entered at their lowest-index vertex, neighbours in index
/// order, so the walk depends on the mesh only.
VertexWalk vertex_walk(std::size_t vertex_count, const std::vector<Triangle>& triangles, std::size_t group);

}  // namespace sd
