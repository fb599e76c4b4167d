// Meshes from numpy arrays, shared by the bindings that trace rays (bake, reference).
#pragma once

#include "array_checks.h"
#include "sdlighting/mesh.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace sdpy {

// Points from an (N, 3) float array (N may be 0), finite unless `finite` is false (normals: the
// library repairs non-finite ones).
inline std::vector<glm::dvec3> read_points(const char* name, const DoubleArray& a, bool finite = true) {
  if (a.ndim() != 2 || a.shape(1) != 3) value_error(std::string(name) + " must have shape (N, 3), got " + shape_string(a));
  const size_t n = static_cast<size_t>(a.shape(0));
  if (finite) check_finite(name, a.data(), 3 * n);
  std::vector<glm::dvec3> points(n);
  const double* data = a.data();
  for (size_t i = 0; i < n; ++i) points[i] = glm::dvec3(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
  return points;
}

// Triangles from an (T, 3) integer array (any integer dtype; an empty array of any dtype).
inline std::vector<sd::Triangle> read_triangles(const char* name, const py::object& object) {
  const py::array a = py::array::ensure(object);
  if (!a) value_error(std::string(name) + " must be an integer array of shape (T, 3)");
  if (a.ndim() != 2 || a.shape(1) != 3) value_error(std::string(name) + " must have shape (T, 3), got " + shape_string(a));
  const size_t t = static_cast<size_t>(a.shape(0));
  if (t == 0) return {};
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u') {
    value_error(std::string(name) + " must hold integers, got dtype " + std::string(py::str(a.dtype())));
  }
  using IndexArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const IndexArray indices = IndexArray::ensure(a);
  if (!indices) value_error(std::string(name) + " cannot be converted to int64");
  // uint64 values above INT64_MAX wrap to negative numbers, which the library's range check rejects.
  std::vector<sd::Triangle> triangles(t);
  const std::int64_t* data = indices.data();
  for (size_t i = 0; i < t; ++i) triangles[i] = {data[3 * i], data[3 * i + 1], data[3 * i + 2]};
  return triangles;
}

inline sd::OccluderMesh read_occluders(const std::optional<DoubleArray>& vertices, const py::object& triangles) {
  if (vertices.has_value() != !triangles.is_none()) {
    value_error("occluder_vertices and occluder_triangles must be given together");
  }
  sd::OccluderMesh mesh;
  if (!vertices) return mesh;
  mesh.vertices = read_points("occluder_vertices", *vertices);
  mesh.triangles = read_triangles("occluder_triangles", triangles);
  return mesh;
}

}  // namespace sdpy
