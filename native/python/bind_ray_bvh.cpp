// Bindings of the ray BVH the live shading walks (sdlighting/ray_bvh.h): ray_bvh builds it,
// ray_bvh_occluded walks it as the shader does.
//
// Errors: arrays of the wrong shape, non-finite points and indices out of range raise ValueError.
// Both run without the GIL.
#include "array_checks.h"
#include "bindings.h"
#include "mesh_arrays.h"
#include "sdlighting/ray_bvh.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

namespace sdpy {
namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

std::vector<float> read_rows(const char* name, const FloatArray& a, py::ssize_t width) {
  if (a.ndim() != 2 || a.shape(1) != width) {
    value_error(std::string(name) + " must have shape (N, " + std::to_string(width) + "), got " + shape_string(a));
  }
  return std::vector<float>(a.data(), a.data() + a.size());
}

}  // namespace

void bind_ray_bvh(py::module_& m) {
  m.def(
      "ray_bvh",
      [](const DoubleArray& vertices, const py::object& triangles) {
        const std::vector<glm::dvec3> points = read_points("vertices", vertices);
        const std::vector<sd::Triangle> indices = read_triangles("triangles", triangles);
        sd::RayBvh bvh;
        {
          py::gil_scoped_release release;
          bvh = sd::build_ray_bvh(points, indices);
        }
        const auto nodes = static_cast<py::ssize_t>(bvh.node_count());
        const auto count = static_cast<py::ssize_t>(bvh.triangle_count());
        py::dict out;
        out["nodes"] = FloatArray({nodes, py::ssize_t(8)}, bvh.nodes.data());
        out["triangles"] = FloatArray({count, py::ssize_t(12)}, bvh.triangles.data());
        out["order"] = py::array_t<std::int64_t>({count}, bvh.order.data());
        return out;
      },
      py::arg("vertices"), py::arg("triangles"),
      R"doc(The BVH of a triangle mesh laid out for the shader's rays (Embree's SAH builder).

vertices: (V, 3) float; triangles: (T, 3) integer indices into vertices. Returns a dict:
"nodes" (N, 8) float32, per node its box's lower x, y, z, a, its upper x, y, z, b, depth first
from the root (an inner node: a, b its children's rows; a leaf: a = -1 - its first row of
"triangles", b its count, at most RAY_BVH_LEAF_TRIANGLES); "triangles" (K, 12) float32, per
triangle p0, p1 - p0, p2 - p0 each followed by 0; "order" (K,) int64, each row's triangle in the
input. Zero-area triangles are left out (K <= T); no triangles give no nodes.)doc");

  m.def(
      "ray_bvh_occluded",
      [](const FloatArray& nodes, const FloatArray& triangles, const DoubleArray& origins,
         const DoubleArray& directions, float t_min) {
        sd::RayBvh bvh;
        bvh.nodes = read_rows("nodes", nodes, 8);
        bvh.triangles = read_rows("triangles", triangles, 12);
        bvh.order.resize(bvh.triangles.size() / 12);
        const std::vector<glm::dvec3> from = read_points("origins", origins);
        const std::vector<glm::dvec3> along = read_points("directions", directions);
        if (from.size() != along.size()) {
          value_error("origins and directions must have the same length, got " + std::to_string(from.size()) +
                      " and " + std::to_string(along.size()));
        }
        const auto node_count = static_cast<float>(bvh.node_count());
        const auto triangle_count = static_cast<float>(bvh.triangle_count());
        for (std::size_t i = 0; i < bvh.node_count(); ++i) {
          const float a = bvh.nodes[8 * i + 3], b = bvh.nodes[8 * i + 7];
          const bool leaf = a < 0.0f;
          const bool valid = leaf ? (-1.0f - a >= 0.0f && b >= 1.0f && -1.0f - a + b <= triangle_count)
                                  : (a > static_cast<float>(i) && a < node_count && b > a && b < node_count);
          if (!valid) value_error("nodes[" + std::to_string(i) + "] is not a node of a ray BVH");
        }
        py::array_t<bool> hit(static_cast<py::ssize_t>(from.size()));
        bool* out = hit.mutable_data();
        {
          py::gil_scoped_release release;
          for (std::size_t i = 0; i < from.size(); ++i) {
            out[i] = sd::ray_bvh_occluded(bvh, glm::vec3(from[i]), glm::vec3(along[i]), t_min);
          }
        }
        return hit;
      },
      py::arg("nodes"), py::arg("triangles"), py::arg("origins"), py::arg("directions"), py::arg("t_min") = 0.0f,
      R"doc(Whether each ray origins[i] + t directions[i], t > t_min, hits a triangle of the BVH
(ray_bvh's "nodes" and "triangles"), walked as the live shader walks it, in float32. Returns (R,)
bool.)doc");
  m.attr("RAY_BVH_LEAF_TRIANGLES") = sd::kRayBvhLeafTriangles;
  m.attr("RAY_BVH_MAX_DEPTH") = sd::kRayBvhMaxDepth;
  m.attr("MAX_RAY_BVH_TRIANGLES") = sd::kMaxRayBvhTriangles;
}

}  // namespace sdpy
