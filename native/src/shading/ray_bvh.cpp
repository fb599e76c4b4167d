#include "sdlighting/ray_bvh.h"

#include "bake/embree_scene.h"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>

namespace sd {
namespace {

// The tree Embree's builder makes through the callbacks, in its thread-local memory; laid out
// flat afterwards.
struct BuildNode {
  bool leaf;
};
struct Box {
  glm::vec3 lower, upper;
};
struct InnerNode : BuildNode {
  Box boxes[2];
  BuildNode* children[2];
};
struct LeafNode : BuildNode {
  unsigned count;
  unsigned ids[kRayBvhLeafTriangles];
};

void* create_inner(RTCThreadLocalAllocator allocator, unsigned child_count, void*) {
  if (child_count != 2) return nullptr;  // maxBranchingFactor is 2
  void* memory = rtcThreadLocalAlloc(allocator, sizeof(InnerNode), 16);
  auto* node = new (memory) InnerNode();
  node->leaf = false;
  return node;
}

void set_children(void* node, void** children, unsigned count, void*) {
  for (unsigned i = 0; i < count && i < 2; ++i) static_cast<InnerNode*>(node)->children[i] = static_cast<BuildNode*>(children[i]);
}

void set_bounds(void* node, const RTCBounds** bounds, unsigned count, void*) {
  for (unsigned i = 0; i < count && i < 2; ++i) {
    static_cast<InnerNode*>(node)->boxes[i] = {{bounds[i]->lower_x, bounds[i]->lower_y, bounds[i]->lower_z},
                                               {bounds[i]->upper_x, bounds[i]->upper_y, bounds[i]->upper_z}};
  }
}

void* create_leaf(RTCThreadLocalAllocator allocator, const RTCBuildPrimitive* primitives, size_t count, void*) {
  if (count > static_cast<size_t>(kRayBvhLeafTriangles)) return nullptr;  // maxLeafSize bounds it
  void* memory = rtcThreadLocalAlloc(allocator, sizeof(LeafNode), 16);
  auto* leaf = new (memory) LeafNode();
  leaf->leaf = true;
  leaf->count = static_cast<unsigned>(count);
  for (size_t i = 0; i < count; ++i) leaf->ids[i] = primitives[i].primID;
  return leaf;
}

void put_box(float* out, const Box& box, float a, float b) {
  const float values[8] = {box.lower.x, box.lower.y, box.lower.z, a, box.upper.x, box.upper.y, box.upper.z, b};
  std::copy(values, values + 8, out);
}

// Depth first from `node` (box `box`), appending its nodes and its leaves' triangles.
void lay_out(const BuildNode* node, const Box& box, const std::vector<std::array<glm::vec3, 3>>& corners,
             const std::vector<std::int64_t>& kept, RayBvh& bvh) {
  const std::size_t index = bvh.node_count();
  bvh.nodes.resize(bvh.nodes.size() + 8);
  if (node->leaf) {
    const auto* leaf = static_cast<const LeafNode*>(node);
    put_box(&bvh.nodes[8 * index], box, -1.0f - static_cast<float>(bvh.triangle_count()), static_cast<float>(leaf->count));
    for (unsigned i = 0; i < leaf->count; ++i) {
      const auto& p = corners[leaf->ids[i]];
      const glm::vec3 rows[3] = {p[0], p[1] - p[0], p[2] - p[0]};
      for (const glm::vec3& row : rows) bvh.triangles.insert(bvh.triangles.end(), {row.x, row.y, row.z, 0.0f});
      bvh.order.push_back(kept[leaf->ids[i]]);
    }
    return;
  }
  const auto* inner = static_cast<const InnerNode*>(node);
  lay_out(inner->children[0], inner->boxes[0], corners, kept, bvh);
  const float second = static_cast<float>(bvh.node_count());
  lay_out(inner->children[1], inner->boxes[1], corners, kept, bvh);
  put_box(&bvh.nodes[8 * index], box, static_cast<float>(index + 1), second);
}

// Embree's device for the builder, released on every path.
struct Device {
  RTCDevice device = rtcNewDevice(nullptr);
  ~Device() {
    if (device) rtcReleaseDevice(device);
  }
};

// The slab test of a ray against a node's box, t in (t_min, t_max].
bool hits_box(const float* node, const glm::vec3& origin, const glm::vec3& inverse, float t_min, float t_max) {
  const glm::vec3 t0 = (glm::vec3(node[0], node[1], node[2]) - origin) * inverse;
  const glm::vec3 t1 = (glm::vec3(node[4], node[5], node[6]) - origin) * inverse;
  const glm::vec3 lower = glm::min(t0, t1);
  const glm::vec3 upper = glm::max(t0, t1);
  const float enter = std::max(std::max(lower.x, lower.y), std::max(lower.z, t_min));
  const float leave = std::min(std::min(upper.x, upper.y), std::min(upper.z, t_max));
  return enter <= leave;
}

// Möller–Trumbore against a triangle's 12 floats.
bool hits_triangle(const float* triangle, const glm::vec3& origin, const glm::vec3& dir, float t_min) {
  const glm::vec3 p0(triangle[0], triangle[1], triangle[2]);
  const glm::vec3 e1(triangle[4], triangle[5], triangle[6]);
  const glm::vec3 e2(triangle[8], triangle[9], triangle[10]);
  const glm::vec3 p = glm::cross(dir, e2);
  const float det = glm::dot(e1, p);
  if (det == 0.0f) return false;
  const float inverse = 1.0f / det;
  const glm::vec3 s = origin - p0;
  const float u = glm::dot(s, p) * inverse;
  const glm::vec3 q = glm::cross(s, e1);
  const float v = glm::dot(dir, q) * inverse;
  // the shader's test, as written there (a NaN fails it)
  return u >= 0.0f && u <= 1.0f && v >= 0.0f && u + v <= 1.0f && glm::dot(e2, q) * inverse > t_min;
}

}  // namespace

RayBvh build_ray_bvh(const std::vector<glm::dvec3>& vertices, const std::vector<Triangle>& triangles) {
  check_points("vertices", vertices);
  check_triangles("triangles", triangles, vertices.size(), "vertices");
  if (static_cast<std::int64_t>(triangles.size()) > kMaxRayBvhTriangles) {
    throw std::invalid_argument("a ray BVH holds at most " + std::to_string(kMaxRayBvhTriangles) + " triangles, got " +
                                std::to_string(triangles.size()));
  }
  std::vector<std::array<glm::vec3, 3>> corners;
  std::vector<std::int64_t> kept;
  std::vector<RTCBuildPrimitive> primitives;
  Box root{glm::vec3(std::numeric_limits<float>::infinity()), glm::vec3(-std::numeric_limits<float>::infinity())};
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const std::array<glm::vec3, 3> p = {glm::vec3(vertices[triangles[i][0]]), glm::vec3(vertices[triangles[i][1]]),
                                        glm::vec3(vertices[triangles[i][2]])};
    const glm::vec3 normal = glm::cross(p[1] - p[0], p[2] - p[0]);
    if (glm::dot(normal, normal) == 0.0f) continue;
    const glm::vec3 lower = glm::min(glm::min(p[0], p[1]), p[2]);
    const glm::vec3 upper = glm::max(glm::max(p[0], p[1]), p[2]);
    RTCBuildPrimitive primitive{};
    primitive.lower_x = lower.x;
    primitive.lower_y = lower.y;
    primitive.lower_z = lower.z;
    primitive.upper_x = upper.x;
    primitive.upper_y = upper.y;
    primitive.upper_z = upper.z;
    primitive.geomID = 0;
    primitive.primID = static_cast<unsigned>(corners.size());
    primitives.push_back(primitive);
    corners.push_back(p);
    kept.push_back(static_cast<std::int64_t>(i));
    root.lower = glm::min(root.lower, lower);
    root.upper = glm::max(root.upper, upper);
  }
  RayBvh bvh;
  if (primitives.empty()) return bvh;

  Device device;
  if (!device.device) throw std::runtime_error("Embree: cannot create a device for the ray BVH");
  RTCBVH tree = rtcNewBVH(device.device);
  RTCBuildArguments arguments = rtcDefaultBuildArguments();
  arguments.buildQuality = RTC_BUILD_QUALITY_MEDIUM;
  arguments.maxBranchingFactor = 2;
  arguments.maxDepth = kRayBvhMaxDepth;
  arguments.minLeafSize = 1;
  arguments.maxLeafSize = kRayBvhLeafTriangles;
  arguments.bvh = tree;
  arguments.primitives = primitives.data();
  arguments.primitiveCount = primitives.size();
  arguments.primitiveArrayCapacity = primitives.size();
  arguments.createNode = create_inner;
  arguments.setNodeChildren = set_children;
  arguments.setNodeBounds = set_bounds;
  arguments.createLeaf = create_leaf;
  const auto* top = static_cast<const BuildNode*>(rtcBuildBVH(&arguments));
  if (!top || rtcGetDeviceError(device.device) != RTC_ERROR_NONE) {
    rtcReleaseBVH(tree);
    throw std::runtime_error("Embree could not build the ray BVH of " + std::to_string(primitives.size()) + " triangles");
  }
  bvh.nodes.reserve(8 * (2 * primitives.size()));
  bvh.triangles.reserve(12 * primitives.size());
  lay_out(top, root, corners, kept, bvh);
  rtcReleaseBVH(tree);  // the tree's nodes live in the BVH's memory: released after the layout
  return bvh;
}

bool ray_bvh_occluded(const RayBvh& bvh, const glm::vec3& origin, const glm::vec3& dir, float t_min) {
  if (bvh.nodes.empty()) return false;
  const float tiny = 1e-20f;
  const glm::vec3 inverse(1.0f / (std::abs(dir.x) > tiny ? dir.x : std::copysign(tiny, dir.x)),
                          1.0f / (std::abs(dir.y) > tiny ? dir.y : std::copysign(tiny, dir.y)),
                          1.0f / (std::abs(dir.z) > tiny ? dir.z : std::copysign(tiny, dir.z)));
  const float t_max = std::numeric_limits<float>::max();
  int stack[kRayBvhMaxDepth + 1];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const float* node = &bvh.nodes[8 * static_cast<std::size_t>(stack[--top])];
    if (!hits_box(node, origin, inverse, t_min, t_max)) continue;
    if (node[3] < 0.0f) {
      const int first = static_cast<int>(-1.0f - node[3]);
      for (int i = 0; i < static_cast<int>(node[7]); ++i) {
        if (hits_triangle(&bvh.triangles[12 * static_cast<std::size_t>(first + i)], origin, dir, t_min)) return true;
      }
    } else {
      if (top + 2 > kRayBvhMaxDepth + 1) throw std::invalid_argument("the ray BVH is deeper than kRayBvhMaxDepth");
      stack[top++] = static_cast<int>(node[7]);
      stack[top++] = static_cast<int>(node[3]);
    }
  }
  return false;
}

}  // namespace sd
