// Designs as numpy arrays, shared by the bindings that return designs.
#pragma once

#include "array_checks.h"
#include "sdlighting/spherical_design.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <utility>

namespace sdpy {

// The one conversion of a design: nodes [N, 3] and weights [N].
inline std::pair<py::array_t<double>, py::array_t<double>> design_arrays(const sd::SphericalDesign& design) {
  py::array_t<double> weights(static_cast<py::ssize_t>(design.size()));
  std::copy(design.weights.begin(), design.weights.end(), weights.mutable_data());
  return {points_array(design.nodes), std::move(weights)};
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
