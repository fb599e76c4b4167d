// The bake's vertex walk (src/bake/vertex_walk.h): every vertex once, warm-start sources earlier in
// the same group and adjacent.
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

TEST(VertexWalk, VisitsEveryVertexOnceAndStartsFromAnEarlierNeighbourInTheGroup) {
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
    std::vector<std::size_t> sorted = walk.order;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t v = 0; v < n; ++v) ASSERT_EQ(sorted[v], v);
    std::size_t warm = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t source = walk.source[i];
      if (source < 0) continue;
      ++warm;
      const auto s = static_cast<std::size_t>(source);
      EXPECT_LT(s, i);
      EXPECT_EQ(s / group, i / group) << "a source outside the group makes the result depend on the threads";
      if (walk.order[i] + 1 == n) continue;  // the loose vertex follows the previous position
      EXPECT_TRUE(edges.count({walk.order[s], walk.order[i]})) << "position " << i;
    }
    // Depth-first, most vertices follow an earlier neighbour in their group; those that do not are
    // a group's first and those whose parent is in an earlier group after a backtrack.
    EXPECT_GE(static_cast<double>(warm), (1.0 - 3.0 / group) * n) << "group " << group;
  }
}

TEST(VertexWalk, VerticesWithoutEdgesStartFromThePreviousPosition) {
  const VertexWalk walk = vertex_walk(10, {}, 4);
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(walk.order[i], i);
    EXPECT_EQ(walk.source[i], i % 4 == 0 ? -1 : static_cast<std::int64_t>(i - 1));
  }
}

}  // namespace
}  // namespace sd
