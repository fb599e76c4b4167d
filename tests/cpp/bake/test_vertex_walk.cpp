// The bake's vertex walk (src/bake/vertex_walk.h): every vertex once, warm-start candidates earlier
// in the same group: the earlier neighbours there and the previous position.
#include "bake/vertex_walk.h"

#include "sdtesting/meshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <utility>

namespace sd {
namespace {

std::set<std::pair<std::size_t, std::size_t>> edges_of(const std::vector<Triangle>& triangles) {
  std::set<std::pair<std::size_t, std::size_t>> edges;
  for (const Triangle& t : triangles) {
    for (int i = 0; i < 3; ++i) {
      const auto a = static_cast<std::size_t>(t[i]), b = static_cast<std::size_t>(t[(i + 1) % 3]);
      edges.insert({a, b});
      edges.insert({b, a});
    }
  }
  return edges;
}

TEST(VertexWalk, VisitsEveryVertexOnceAndStartsFromEarlierNeighboursAndThePreviousPosition) {
  test::Mesh mesh = test::bumpy_sphere(2);
  // A second component and a loose vertex.
  const test::Mesh box = test::solid_box({3, 3, 3}, {4, 4, 4});
  const auto offset = static_cast<std::int64_t>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), box.vertices.begin(), box.vertices.end());
  for (Triangle t : box.triangles) mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  mesh.vertices.emplace_back(9, 9, 9);
  const auto edges = edges_of(mesh.triangles);
  const std::size_t n = mesh.vertices.size();

  for (std::size_t group : {1, 7, 32}) {
    const VertexWalk walk = vertex_walk(n, mesh.triangles, group);
    ASSERT_EQ(walk.order.size(), n);
    ASSERT_EQ(walk.first_source.size(), n + 1);
    std::vector<std::size_t> sorted = walk.order;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t v = 0; v < n; ++v) ASSERT_EQ(sorted[v], v);
    std::vector<std::size_t> position(n);
    for (std::size_t i = 0; i < n; ++i) position[walk.order[i]] = i;
    std::size_t adjacent = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t group_start = i - i % group;
      const std::vector<std::size_t> sources(walk.sources.begin() + walk.first_source[i],
                                             walk.sources.begin() + walk.first_source[i + 1]);
      // Earlier neighbours in the group and the previous position, latest first: a source outside
      // the group would make the result depend on the threads.
      std::set<std::size_t> expected;
      if (i > group_start) expected.insert(i - 1);
      for (const auto& [a, b] : edges) {
        if (a == walk.order[i] && position[b] >= group_start && position[b] < i) expected.insert(position[b]);
      }
      EXPECT_EQ(sources, std::vector<std::size_t>(expected.rbegin(), expected.rend()))
          << "position " << i << ", group " << group;
      if (i > group_start && edges.count({walk.order[i], walk.order[i - 1]}) == 0) {
        adjacent += sources.size() > 1;
      } else {
        adjacent += i > group_start;
      }
    }
    // Depth-first, most vertices have an earlier neighbour in their group; those that do not are
    // a group's first and those whose parent is in an earlier group after a backtrack.
    EXPECT_GE(static_cast<double>(adjacent), (1.0 - 3.0 / group) * n) << "group " << group;
  }
}

TEST(VertexWalk, VerticesWithoutEdgesStartFromThePreviousPosition) {
  const VertexWalk walk = vertex_walk(10, {}, 4);
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(walk.order[i], i);
    const std::vector<std::size_t> sources(walk.sources.begin() + walk.first_source[i],
                                           walk.sources.begin() + walk.first_source[i + 1]);
    EXPECT_EQ(sources, i % 4 == 0 ? std::vector<std::size_t>{} : std::vector<std::size_t>{i - 1});
  }
}

}  // namespace
}  // namespace sd
