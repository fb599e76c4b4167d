#include "bake/vertex_walk.h"

#include <algorithm>
#include <functional>
#include <utility>

namespace sd {
namespace {

// Compressed adjacency: the neighbours of v are neighbours[first[v] .. first[v + 1]), ascending.
struct Adjacency {
  std::vector<std::size_t> first;
  std::vector<std::size_t> neighbours;

  Adjacency(std::size_t n, const std::vector<Triangle>& triangles) : first(n + 1, 0) {
    std::vector<std::pair<std::size_t, std::size_t>> edges;
    edges.reserve(6 * triangles.size());
    for (const Triangle& t : triangles) {
      for (int i = 0; i < 3; ++i) {
        const auto a = static_cast<std::size_t>(t[i]), b = static_cast<std::size_t>(t[(i + 1) % 3]);
        if (a == b) continue;
        edges.emplace_back(a, b);
        edges.emplace_back(b, a);
      }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    neighbours.reserve(edges.size());
    for (const auto& [a, b] : edges) {
      ++first[a + 1];
      neighbours.push_back(b);
    }
    for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
  }
};

constexpr std::size_t kUnvisited = static_cast<std::size_t>(-1);

}  // namespace

VertexWalk vertex_walk(std::size_t vertex_count, const std::vector<Triangle>& triangles, std::size_t group) {
  const Adjacency adjacency(vertex_count, triangles);
  VertexWalk walk;
  walk.group = std::max<std::size_t>(group, 1);
  walk.order.reserve(vertex_count);
  std::vector<std::size_t> position(vertex_count, kUnvisited);

  // Iterative depth-first search; each stack entry is a vertex and its next neighbour to try.
  std::vector<std::pair<std::size_t, std::size_t>> stack;
  for (std::size_t root = 0; root < vertex_count; ++root) {
    if (position[root] != kUnvisited) continue;
    position[root] = walk.order.size();
    walk.order.push_back(root);
    stack.emplace_back(root, adjacency.first[root]);
    while (!stack.empty()) {
      auto& [v, next] = stack.back();
      if (next == adjacency.first[v + 1]) {
        stack.pop_back();
        continue;
      }
      const std::size_t w = adjacency.neighbours[next++];
      if (position[w] != kUnvisited) continue;
      position[w] = walk.order.size();
      walk.order.push_back(w);
      stack.emplace_back(w, adjacency.first[w]);
    }
  }

  walk.first_source.assign(vertex_count + 1, 0);
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const std::size_t v = walk.order[i];
    const std::size_t group_start = i - i % walk.group;
    const std::size_t first = walk.sources.size();
    for (std::size_t j = adjacency.first[v]; j < adjacency.first[v + 1]; ++j) {
      const std::size_t p = position[adjacency.neighbours[j]];
      if (p >= group_start && p < i) walk.sources.push_back(p);
    }
    // The previous position is a neighbour, or after a backtrack a few edges away, or in another
    // component; weighted_design does not refit a start whose sky is too far from this vertex's.
    if (i > group_start && std::find(walk.sources.begin() + first, walk.sources.end(), i - 1) == walk.sources.end()) {
      walk.sources.push_back(i - 1);
    }
    std::sort(walk.sources.begin() + first, walk.sources.end(), std::greater<>());
    walk.first_source[i + 1] = walk.sources.size();
  }
  return walk;
}

}  // namespace sd
