// Argument checks and conversions shared by the sdnative bindings: bad input raises ValueError
// with a message that names the argument.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "sdlighting/limits.h"
#include "sdlighting/spherical_design.h"

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace sdpy {

namespace py = pybind11;

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// The library's one range checker: its std::invalid_argument surfaces as ValueError.
using sd::check_order;
using sd::check_range;

[[noreturn]] inline void value_error(const std::string& message) { throw py::value_error(message); }

/// Points as a fresh (N, 3) float64 array.
inline py::array_t<double> points_array(const std::vector<glm::dvec3>& points) {
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t(3)});
  double* data = out.mutable_data();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const glm::dvec3& p = points[i];
    data[3 * i + 0] = p.x;
    data[3 * i + 1] = p.y;
    data[3 * i + 2] = p.z;
  }
  return out;
}

inline std::string shape_string(const py::array& a) {
  std::ostringstream out;
  out << '(';
  for (py::ssize_t i = 0; i < a.ndim(); ++i) {
    if (i > 0) out << ", ";
    out << a.shape(i);
  }
  if (a.ndim() == 1) out << ',';
  out << ')';
  return out.str();
}

inline void check_design_degree(int degree) { check_order("degree", degree, sd::kMaxDesignDegree); }

inline void check_finite(const char* name, const double* data, size_t count) {
  for (size_t i = 0; i < count; ++i) {
    if (!std::isfinite(data[i])) {
      value_error(std::string(name) + " contains NaN or infinity (flat index " + std::to_string(i) + ")");
    }
  }
}

// A 1-D array of length >= min_length.
inline size_t check_vector(const char* name, const DoubleArray& a, size_t min_length = 0) {
  if (a.ndim() != 1) value_error(std::string(name) + " must be 1-D, got shape " + shape_string(a));
  const size_t n = static_cast<size_t>(a.shape(0));
  if (n < min_length) {
    value_error(std::string(name) + " needs at least " + std::to_string(min_length) + " entries, got " +
                std::to_string(n));
  }
  return n;
}

// Unit vector along (x, y, z); scaled by the largest component first so that neither huge nor
// tiny (but non-zero) finite vectors overflow or underflow.
inline glm::dvec3 unit_direction(const char* name, size_t index, const double* v) {
  if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
    value_error(std::string(name) + "[" + std::to_string(index) + "] contains NaN or infinity");
  }
  const double scale = std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])});
  if (!(scale > 0.0)) value_error(std::string(name) + "[" + std::to_string(index) + "] is the zero vector");
  const glm::dvec3 d(v[0] / scale, v[1] / scale, v[2] / scale);
  return d / std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
}

// Directions from an [N, 3] array (or a single [3] one when allow_single), normalised.
inline std::vector<glm::dvec3> read_directions(const char* name, const DoubleArray& a, bool allow_single) {
  const bool single = allow_single && a.ndim() == 1 && a.shape(0) == 3;
  if (!single && !(a.ndim() == 2 && a.shape(1) == 3)) {
    value_error(std::string(name) + " must have shape (N, 3)" + (allow_single ? " or (3,)" : "") + ", got " +
                shape_string(a));
  }
  const size_t n = single ? 1 : static_cast<size_t>(a.shape(0));
  const double* data = a.data();
  std::vector<glm::dvec3> dirs(n);
  for (size_t i = 0; i < n; ++i) dirs[i] = unit_direction(name, i, data + 3 * i);
  return dirs;
}

// The order s of an SH expansion with `count` = (s+1)² coefficients, at most max_order.
inline int sh_order_from_count(const char* name, py::ssize_t count, int max_order) {
  const auto root = static_cast<py::ssize_t>(std::llround(std::sqrt(static_cast<double>(count))));
  if (count < 1 || root * root != count) {
    value_error(std::string(name) + " must hold (lmax+1)^2 SH coefficients (a perfect square), got " +
                std::to_string(count));
  }
  const int order = static_cast<int>(root) - 1;
  check_order(std::string("lmax of ") + name, order, max_order);
  return order;
}

// numpy row-major R[row][col] -> glm column-major m[col][row].
inline glm::dmat3 read_rotation(const DoubleArray& r) {
  if (r.ndim() != 2 || r.shape(0) != 3 || r.shape(1) != 3) {
    value_error("rotation must have shape (3, 3), got " + shape_string(r));
  }
  check_finite("rotation", r.data(), 9);
  const auto view = r.unchecked<2>();
  glm::dmat3 m(1.0);
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) m[col][row] = view(row, col);
  }
  return m;
}

}  // namespace sdpy
