// The ray BVH of the live shading (sdlighting/ray_bvh.h): its layout holds every triangle once,
// inside every box above it, and its walk answers as a test of every triangle does. Exact results:
// the walk and the brute force make the same float32 tests.
#include "sdlighting/ray_bvh.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace sd {
namespace {

struct Soup {
  std::vector<glm::dvec3> vertices;
  std::vector<Triangle> triangles;
};

// `count` small random triangles in the unit cube, with one zero-area triangle among them.
Soup random_soup(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), jitter(-0.08, 0.08);
  Soup soup;
  for (int i = 0; i < count; ++i) {
    const glm::dvec3 centre(unit(rng), unit(rng), unit(rng));
    for (int k = 0; k < 3; ++k) soup.vertices.push_back(centre + glm::dvec3(jitter(rng), jitter(rng), jitter(rng)));
    soup.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
  }
  soup.triangles.push_back({0, 0, 1});  // zero area
  return soup;
}

// Every triangle's test, the walk's Möller–Trumbore in float32.
bool brute_force(const RayBvh& bvh, const glm::vec3& origin, const glm::vec3& dir, float t_min) {
  for (std::size_t i = 0; i < bvh.triangle_count(); ++i) {
    const float* t = &bvh.triangles[12 * i];
    const glm::vec3 p0(t[0], t[1], t[2]), e1(t[4], t[5], t[6]), e2(t[8], t[9], t[10]);
    const glm::vec3 p = glm::cross(dir, e2);
    const float det = glm::dot(e1, p);
    if (det == 0.0f) continue;
    const float inverse = 1.0f / det;
    const glm::vec3 s = origin - p0;
    const float u = glm::dot(s, p) * inverse;
    const glm::vec3 q = glm::cross(s, e1);
    const float v = glm::dot(dir, q) * inverse;
    if (u >= 0.0f && u <= 1.0f && v >= 0.0f && u + v <= 1.0f && glm::dot(e2, q) * inverse > t_min) return true;
  }
  return false;
}

// The boxes below node `index` lie in its box, and its leaves' triangles too; counts the triangles.
void check_node(const RayBvh& bvh, std::size_t index, int depth, std::vector<int>& seen) {
  ASSERT_LE(depth, kRayBvhMaxDepth);
  const float* node = &bvh.nodes[8 * index];
  const glm::vec3 lower(node[0], node[1], node[2]), upper(node[4], node[5], node[6]);
  // p1 and p2 are stored as edges from p0: p0 + (p1 - p0) rounds within an ulp of p1
  const glm::vec3 ulp(1e-6f);
  auto inside = [&](const glm::vec3& p) {
    return glm::all(glm::greaterThanEqual(p, lower - ulp)) && glm::all(glm::lessThanEqual(p, upper + ulp));
  };
  if (node[3] < 0.0f) {
    const int first = static_cast<int>(-1.0f - node[3]);
    const int count = static_cast<int>(node[7]);
    ASSERT_GE(count, 1);
    ASSERT_LE(count, kRayBvhLeafTriangles);
    for (int i = first; i < first + count; ++i) {
      const float* t = &bvh.triangles[12 * i];
      const glm::vec3 p0(t[0], t[1], t[2]);
      EXPECT_TRUE(inside(p0) && inside(p0 + glm::vec3(t[4], t[5], t[6])) && inside(p0 + glm::vec3(t[8], t[9], t[10])));
      ++seen[i];
    }
    return;
  }
  const std::size_t first = static_cast<std::size_t>(node[3]), second = static_cast<std::size_t>(node[7]);
  EXPECT_EQ(first, index + 1);
  for (std::size_t child : {first, second}) {
    const float* box = &bvh.nodes[8 * child];
    EXPECT_TRUE(inside(glm::vec3(box[0], box[1], box[2])) && inside(glm::vec3(box[4], box[5], box[6])));
    check_node(bvh, child, depth + 1, seen);
  }
}

TEST(RayBvh, HoldsEveryTriangleOnceInsideItsBoxes) {
  const Soup soup = random_soup(3000, 1);
  const RayBvh bvh = build_ray_bvh(soup.vertices, soup.triangles);
  ASSERT_EQ(bvh.triangle_count(), 3000u);  // the zero-area one is left out
  std::vector<std::int64_t> order = bvh.order;
  std::sort(order.begin(), order.end());
  for (std::int64_t i = 0; i < 3000; ++i) ASSERT_EQ(order[i], i);
  std::vector<int> seen(bvh.triangle_count(), 0);
  check_node(bvh, 0, 0, seen);
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
  EXPECT_LT(bvh.node_count(), 2 * bvh.triangle_count());
}

TEST(RayBvh, WalkAnswersAsEveryTriangle) {
  const Soup soup = random_soup(2000, 2);
  const RayBvh bvh = build_ray_bvh(soup.vertices, soup.triangles);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), signed_unit(-1.0f, 1.0f);
  int hits = 0;
  for (int i = 0; i < 4000; ++i) {
    const glm::vec3 origin(unit(rng), unit(rng), unit(rng));
    glm::vec3 dir(signed_unit(rng), signed_unit(rng), signed_unit(rng));
    if (i % 7 == 0) dir = glm::vec3(0.0f, 0.0f, 1.0f);  // axis-aligned: zero slab components
    const float t_min = (i % 2) ? 0.0f : 0.05f;
    const bool walked = ray_bvh_occluded(bvh, origin, dir, t_min);
    ASSERT_EQ(walked, brute_force(bvh, origin, dir, t_min)) << "ray " << i;
    hits += walked;
  }
  EXPECT_GT(hits, 400);  // both answers are met often
  EXPECT_LT(hits, 3600);
}

TEST(RayBvh, SmallAndEmptyMeshes) {
  const std::vector<glm::dvec3> square = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const RayBvh two = build_ray_bvh(square, {{0, 1, 2}, {0, 2, 3}});
  ASSERT_EQ(two.node_count(), 1u);  // one leaf
  EXPECT_TRUE(ray_bvh_occluded(two, {0.2f, 0.7f, 1.0f}, {0.0f, 0.0f, -1.0f}, 0.0f));
  EXPECT_FALSE(ray_bvh_occluded(two, {0.2f, 0.7f, 1.0f}, {0.0f, 0.0f, 1.0f}, 0.0f));
  EXPECT_FALSE(ray_bvh_occluded(two, {1.5f, 0.5f, 1.0f}, {0.0f, 0.0f, -1.0f}, 0.0f));
  EXPECT_FALSE(ray_bvh_occluded(two, {0.2f, 0.7f, 1.0f}, {0.0f, 0.0f, -1.0f}, 1.5f));  // past t_min only
  const RayBvh none = build_ray_bvh(square, {});
  EXPECT_EQ(none.node_count(), 0u);
  EXPECT_FALSE(ray_bvh_occluded(none, {0.2f, 0.7f, 1.0f}, {0.0f, 0.0f, -1.0f}, 0.0f));
}

TEST(RayBvh, RejectsBadInput) {
  const std::vector<glm::dvec3> points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(build_ray_bvh(points, {{0, 1, 3}}), std::invalid_argument);
  EXPECT_THROW(build_ray_bvh({{0, 0, 0}, {1, 0, 0}, {0, std::nan(""), 0}}, {{0, 1, 2}}), std::invalid_argument);
}

}  // namespace
}  // namespace sd
