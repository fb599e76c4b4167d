// Bindings of the weighted spherical designs (eq. 11): of a zonal lobe, of a tabulated zonal
// weight and of a discrete measure. Bad input raises ValueError naming the argument; a design that
// cannot be certified raises RuntimeError. The designs are built without the GIL.
#include "array_checks.h"
#include "bindings.h"
#include "design_arrays.h"
#include "sdlighting/spherical_design.h"
#include "sdlighting/weighted_design.h"
#include "sdlighting/zonal_design.h"
#include "sdlighting/zonal_lobe.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <glm/vec3.hpp>

#include <optional>
#include <string>
#include <vector>

namespace sdpy {
namespace {

sd::SphericalDesign compute_zonal_design(const std::string& lobe, double exponent, int degree,
                                         const std::string& method) {
  check_design_degree(degree);
  const sd::ZonalLobe zonal_lobe = sd::ZonalLobe::from_name(lobe, exponent);
  const sd::DesignMethod design_method = sd::design_method_from_name(method);
  py::gil_scoped_release release;
  return sd::zonal_design(sd::ZonalWeight::from_lobe(zonal_lobe), degree, design_method);
}

std::optional<sd::SphericalDesign> compute_continued_design(const std::string& lobe, double exponent, int degree,
                                            double start_exponent, const DoubleArray& start_nodes,
                                            const DoubleArray& start_weights, bool thin) {
  check_design_degree(degree);
  const sd::ZonalLobe zonal_lobe = sd::ZonalLobe::from_name(lobe, exponent);
  const sd::ZonalLobe start_lobe = sd::ZonalLobe::from_name(lobe, start_exponent);
  if (start_nodes.ndim() != 2 || start_nodes.shape(1) != 3 || start_nodes.shape(0) == 0) {
    value_error("start_nodes must have shape (N, 3), N >= 1, got " + shape_string(start_nodes));
  }
  const size_t n = static_cast<size_t>(start_nodes.shape(0));
  if (start_weights.ndim() != 1 || static_cast<size_t>(start_weights.shape(0)) != n) {
    value_error("start_weights must have shape (" + std::to_string(n) + ",) to match start_nodes, got " +
                shape_string(start_weights));
  }
  check_finite("start_weights", start_weights.data(), n);
  sd::SphericalDesign start;
  start.degree = degree;
  start.nodes = read_directions("start_nodes", start_nodes, false);
  start.weights.assign(start_weights.data(), start_weights.data() + n);
  for (size_t i = 0; i < n; ++i) {
    if (!(start.weights[i] > 0.0)) value_error("start_weights must be positive, start_weights[" + std::to_string(i) + "] <= 0");
  }
  py::gil_scoped_release release;
  return sd::zonal_design_continued(sd::ZonalWeight::from_lobe(zonal_lobe), degree,
                                    sd::ZonalWeight::from_lobe(start_lobe), start, thin);
}

sd::SphericalDesign compute_tabulated_design(const DoubleArray& t, const DoubleArray& w, int degree,
                                             const std::string& method) {
  check_design_degree(degree);
  const size_t n = check_vector("t", t, 2);
  if (check_vector("w", w) != n) {
    value_error("t and w must have the same length, got " + std::to_string(n) + " and " +
                std::to_string(w.shape(0)));
  }
  check_finite("t", t.data(), n);
  check_finite("w", w.data(), n);
  for (size_t i = 0; i < n; ++i) {
    if (w.data()[i] < 0.0) value_error("w must be non-negative, w[" + std::to_string(i) + "] < 0");
  }
  const sd::DesignMethod design_method = sd::design_method_from_name(method);
  std::vector<double> tv(t.data(), t.data() + n), wv(w.data(), w.data() + n);
  py::gil_scoped_release release;
  return sd::zonal_design(sd::ZonalWeight::tabulated(tv, wv), degree, design_method);
}

sd::SphericalDesign compute_weighted_design(const DoubleArray& dirs, const DoubleArray& weights, int degree) {
  check_design_degree(degree);
  if (dirs.ndim() != 2 || dirs.shape(1) != 3) value_error("dirs must have shape (M, 3), got " + shape_string(dirs));
  const size_t m = static_cast<size_t>(dirs.shape(0));
  if (m == 0) value_error("dirs is empty: the measure needs at least one direction");
  if (weights.ndim() != 1 || static_cast<size_t>(weights.shape(0)) != m) {
    value_error("weights must have shape (" + std::to_string(m) + ",) to match dirs, got " + shape_string(weights));
  }
  std::vector<glm::dvec3> d = read_directions("dirs", dirs, false);
  check_finite("weights", weights.data(), m);
  std::vector<double> w(weights.data(), weights.data() + m);
  double mass = 0.0;
  for (size_t i = 0; i < m; ++i) {
    if (w[i] < 0.0) value_error("weights must be non-negative, weights[" + std::to_string(i) + "] < 0");
    mass += w[i];
  }
  if (!(mass > 0.0)) value_error("weights sum to zero: the measure is empty");
  py::gil_scoped_release release;
  return sd::weighted_design(d, w, degree);
}

}  // namespace

void bind_designs(py::module_& m) {
  m.attr("DESIGN_TOLERANCE") = sd::kDesignTolerance;

  m.def(
      "zonal_design",
      [](const std::string& lobe, double exponent, int degree, const std::string& method) {
        return design_tuple(compute_zonal_design(lobe, exponent, degree, method));
      },
      py::arg("lobe"), py::arg("exponent"), py::arg("degree"), py::arg("method") = "auto",
      R"doc(A weighted spherical design of the given degree for a lobe's weight w(x . e3) (nodes around +z).

lobe: "lambert" (exponent ignored) or "phong" (exponent in [0, MAX_PHONG_EXPONENT]).
degree: in [0, MAX_DESIGN_DEGREE].
method: "gauss" (Gauss product rule, or its Radau variant with the pole as a node), "gradient"
        (gradient projection, eq. 14), or "auto" (the smaller of both).
Returns (nodes, weights): nodes of shape (N, 3) (unit vectors), weights of shape (N,), all
positive, summing to 1. Raises RuntimeError if no design can be certified. Releases the GIL.)doc");

  m.def(
      "zonal_design_continued",
      [](const std::string& lobe, double exponent, int degree, double start_exponent, const DoubleArray& start_nodes,
         const DoubleArray& start_weights, bool thin) {
        const std::optional<sd::SphericalDesign> design =
            compute_continued_design(lobe, exponent, degree, start_exponent, start_nodes, start_weights, thin);
        return design ? py::object(design_tuple(*design)) : py::object(py::none());
      },
      py::arg("lobe"), py::arg("exponent"), py::arg("degree"), py::arg("start_exponent"), py::arg("start_nodes"),
      py::arg("start_weights"), py::arg("thin") = true,
      R"doc(As zonal_design, continued from a design of the same lobe and degree at a neighbouring
exponent (start_nodes (N, 3), start_weights (N,), positive): each node moves along its meridian to
the same fraction of the lobe's mass, then gradient projection refits the design and, if thin,
removes nodes while it certifies (costly at high degrees: for the last of a chain of steps). Milliseconds where zonal_design's search takes seconds to minutes, with about as
many nodes as the start. Returns (nodes, weights), certified like zonal_design's, or None when the
moved design does not refit to a certified one (the step was too large: continue in smaller steps,
or call zonal_design). Releases the GIL.)doc");

  m.def(
      "zonal_design_tabulated",
      [](const DoubleArray& t, const DoubleArray& w, int degree, const std::string& method) {
        return design_tuple(compute_tabulated_design(t, w, degree, method));
      },
      py::arg("t"), py::arg("w"), py::arg("degree"), py::arg("method") = "auto",
      R"doc(A weighted spherical design for a tabulated zonal weight w(x . e3).

t: strictly increasing samples of t = cos(theta) in [-1, 1], shape (M,), M >= 2.
w: the weight at t, finite and >= 0, shape (M,); linear between samples, zero outside.
degree, method: as for zonal_design.
Returns (nodes, weights); the weights sum to the weight's mass integral w(x . e3) dmu(x)
(not necessarily 1). Releases the GIL.)doc");

  m.def(
      "weighted_design",
      [](const DoubleArray& dirs, const DoubleArray& weights, int degree) {
        return design_tuple(compute_weighted_design(dirs, weights, degree));
      },
      py::arg("dirs"), py::arg("weights"), py::arg("degree"),
      R"doc(A weighted spherical design for the discrete measure sum_i weights[i] delta(dirs[i])
(e.g. visibility or an environment given by samples): Caratheodory-Tchakaloff compression picks
a subset of the (normalised) sample directions, then gradient projection may move nodes while it
removes others, so the returned nodes need not be sample directions.

dirs: shape (M, 3), finite and non-zero (normalised here).
weights: shape (M,), finite, >= 0, with a positive sum.
degree: in [0, MAX_DESIGN_DEGREE].
Returns (nodes, weights), at most (degree+1)**2 nodes, weights positive and summing to
sum(weights); the SH moments up to the degree match to DESIGN_TOLERANCE * mass. Raises
RuntimeError if no design can be certified. Releases the GIL.)doc");

  m.def(
      "zonal_design_report",
      [](const std::string& lobe, double exponent, int degree, const std::string& method) {
        return design_dict(compute_zonal_design(lobe, exponent, degree, method));
      },
      py::arg("lobe"), py::arg("exponent"), py::arg("degree"), py::arg("method") = "auto",
      R"doc(As zonal_design, but returns a dict with keys nodes, weights, degree (int), residual (float:
the moment residual relative to the mass) and method (str: "gauss", "gauss-radau" or "gradient").)doc");

  m.def(
      "weighted_design_report",
      [](const DoubleArray& dirs, const DoubleArray& weights, int degree) {
        return design_dict(compute_weighted_design(dirs, weights, degree));
      },
      py::arg("dirs"), py::arg("weights"), py::arg("degree"),
      R"doc(As weighted_design, but returns a dict with keys nodes, weights, degree (int), residual
(float: the moment residual relative to the mass) and method (str: "tchakaloff" or "gradient").)doc");
}

}  // namespace sdpy
