// Designs as numpy arrays, shared by the bindings that return designs.
#pragma once

#include "array_checks.h"
#include "sdlighting/spherical_design.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <utility>

namespace sdpy {

// The one conversion of a design: nodes [N, 3] and weights [N].
inline std::pair<py::array_t<double>, py::array_t<double>> design_arrays(const sd::SphericalDesign& design) {
  const py::ssize_t n = design.size();
  py::array_t<double> nodes({n, py::ssize_t(3)});
  py::array_t<double> weights(n);
  double* node_data = nodes.mutable_data();
  double* weight_data = weights.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    node_data[3 * i + 0] = design.nodes[i].x;
    node_data[3 * i + 1] = design.nodes[i].y;
    node_data[3 * i + 2] = design.nodes[i].z;
    weight_data[i] = design.weights[i];
  }
  return {std::move(nodes), std::move(weights)};
}

inline py::tuple design_tuple(const sd::SphericalDesign& design) {
  auto arrays = design_arrays(design);
  return py::make_tuple(std::move(arrays.first), std::move(arrays.second));
}

inline py::dict design_dict(const sd::SphericalDesign& design) {
  auto arrays = design_arrays(design);
  py::dict result;
  result["nodes"] = std::move(arrays.first);
  result["weights"] = std::move(arrays.second);
  result["degree"] = design.degree;
  result["residual"] = design.residual;
  result["method"] = design.method;
  return result;
}

}  // namespace sdpy
