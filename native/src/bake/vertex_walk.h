// The order in which a bake visits its vertices when each vertex's design is refitted from an
// already-built neighbour's (Theorem 2.2 warm starts, sdlighting/weighted_design.h). Private to the
// library.
#pragma once

#include "sdlighting/mesh.h"

#include <cstddef>
#include <vector>

namespace sd {

/// Vertices in depth-first preorder over the mesh's edges, cut into groups of `group` consecutive
/// positions that one worker runs in order. Within a group, each vertex after the first may start
/// from the design of any of a few earlier vertices (its candidates): its neighbours visited
/// earlier in the group, and the previous position; across groups nothing is shared, so the
/// results do not depend on which worker runs which group.
struct VertexWalk {
  std::size_t group = 1;
  std::vector<std::size_t> order;  ///< [N] the vertex at each position
  /// The candidates of position i are sources[first_source[i] .. first_source[i + 1]): earlier
  /// positions in the same group, latest first; none for a group's first position.
  std::vector<std::size_t> first_source;  ///< [N + 1]
  std::vector<std::size_t> sources;
};

/// The walk of `vertex_count` vertices joined by `triangles` (indices already validated), in
/// groups of `group` >= 1. Components are entered at their lowest-index vertex, neighbours in index
/// order, so the walk depends on the mesh only.
VertexWalk vertex_walk(std::size_t vertex_count, const std::vector<Triangle>& triangles, std::size_t group);

}  // namespace sd
