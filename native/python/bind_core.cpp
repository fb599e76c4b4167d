// Bindings of the core: spherical harmonics, rotation, lobes, Gaunt coefficients and designs.
//
// Every array argument is accepted as anything numpy can convert to a C-contiguous float64 array;
// every array result is a fresh float64 (or int32 for index tables) numpy array. Shapes, finiteness
// and ranges are checked here so that bad input raises ValueError with a message naming the
// argument; the library's own std::invalid_argument also surfaces as ValueError and its
// std::runtime_error ("no certified design") as RuntimeError. Long computations release the GIL.
#include "array_checks.h"
#include "bindings.h"
#include "sdlighting/gaunt.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_design.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/weighted_design.h"
#include "sdlighting/zonal_design.h"
#include "sdlighting/zonal_lobe.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sdpy {
namespace {

// The one conversion of a design: nodes [N, 3] and weights [N].
std::pair<py::array_t<double>, py::array_t<double>> design_arrays(const sd::SphericalDesign& design) {
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

py::tuple design_tuple(const sd::SphericalDesign& design) {
  auto arrays = design_arrays(design);
  return py::make_tuple(std::move(arrays.first), std::move(arrays.second));
}

py::dict design_dict(const sd::SphericalDesign& design) {
  auto arrays = design_arrays(design);
  py::dict result;
  result["nodes"] = std::move(arrays.first);
  result["weights"] = std::move(arrays.second);
  result["degree"] = design.degree;
  result["residual"] = design.residual;
  result["method"] = design.method;
  return result;
}

// ---- designs (computed without the GIL) ----

sd::SphericalDesign compute_zonal_design(const std::string& lobe, double exponent, int degree,
                                         const std::string& method) {
  check_design_degree(degree);
  const sd::ZonalLobe zonal_lobe = sd::ZonalLobe::from_name(lobe, exponent);
  const sd::DesignMethod design_method = sd::design_method_from_name(method);
  py::gil_scoped_release release;
  return sd::zonal_design(sd::ZonalWeight::from_lobe(zonal_lobe), degree, design_method);
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

// ---- the exposed functions ----

py::array_t<double> py_sh_basis(int lmax, const DoubleArray& dirs) {
  check_order("lmax", lmax, sd::kMaxShOrder);
  const bool single = dirs.ndim() == 1;
  const std::vector<glm::dvec3> d = read_directions("dirs", dirs, true);
  const py::ssize_t k = sd::sh_count(lmax), n = static_cast<py::ssize_t>(d.size());
  py::array_t<double> out = single ? py::array_t<double>(k) : py::array_t<double>({n, k});
  double* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) sd::sh_basis(lmax, d[i], data + i * k);
  }
  return out;
}

py::array_t<double> numpy_copy(const std::vector<double>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(values.size()), values.data());
}

py::dict py_sh_recurrence_constants(int order) {
  const sd::ShRecurrence r = sd::sh_recurrence(order);
  py::dict out;
  out["diagonal"] = numpy_copy(r.diagonal);
  out["a"] = numpy_copy(r.a);
  out["b"] = numpy_copy(r.b);
  return out;
}

py::array_t<double> py_rotate_sh(const DoubleArray& coeffs, const DoubleArray& rotation) {
  if (coeffs.ndim() != 1 && coeffs.ndim() != 2) {
    value_error("coeffs must have shape (K,) or (K, C), got " + shape_string(coeffs));
  }
  const py::ssize_t k = coeffs.shape(0);
  const py::ssize_t channels = coeffs.ndim() == 2 ? coeffs.shape(1) : 1;
  const int order = sh_order_from_count("coeffs", k, sd::kMaxShOrder);
  if (channels > std::numeric_limits<int>::max()) value_error("coeffs has too many channels");
  check_finite("coeffs", coeffs.data(), static_cast<size_t>(k * channels));
  const glm::dmat3 r = read_rotation(rotation);

  std::vector<py::ssize_t> shape(coeffs.shape(), coeffs.shape() + coeffs.ndim());
  py::array_t<double> out(shape);
  const double* in = coeffs.data();
  double* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    const sd::ShRotation d(r, order);  // validates the rotation: std::invalid_argument -> ValueError
    if (channels > 0) d.apply(in, data, static_cast<int>(channels));
  }
  return out;
}

py::array_t<double> py_zonal_coefficients(const std::string& lobe, double exponent, int lmax) {
  check_order("lmax", lmax, sd::kMaxLegendreOrder);
  return numpy_copy(sd::ZonalLobe::from_name(lobe, exponent).coefficients(lmax));
}

py::array_t<double> py_legendre(int lmax, const DoubleArray& t) {
  check_order("lmax", lmax, sd::kMaxLegendreOrder);
  if (t.ndim() > 1) value_error("t must be a scalar or 1-D, got shape " + shape_string(t));
  const bool scalar = t.ndim() == 0;
  const py::ssize_t n = scalar ? 1 : t.shape(0), width = lmax + 1;
  check_finite("t", t.data(), static_cast<size_t>(n));
  py::array_t<double> out = scalar ? py::array_t<double>(width) : py::array_t<double>({n, width});
  const double* in = t.data();
  double* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) sd::legendre_all(lmax, in[i], data + i * width);
  }
  return out;
}

py::tuple py_gaunt_coefficients(int order_a, int order_b, int order_c) {
  check_order("order_a", order_a, sd::kMaxShOrder);
  check_order("order_b", order_b, sd::kMaxShOrder);
  check_order("order_c", order_c, sd::kMaxShOrder);
  std::vector<sd::GauntEntry> entries;
  {
    py::gil_scoped_release release;
    entries = sd::gaunt_coefficients(order_a, order_b, order_c);
  }
  const auto e = static_cast<py::ssize_t>(entries.size());
  py::array_t<std::int32_t> indices({e, py::ssize_t(3)});
  py::array_t<double> values(e);
  std::int32_t* index_data = indices.mutable_data();
  double* value_data = values.mutable_data();
  for (py::ssize_t i = 0; i < e; ++i) {
    index_data[3 * i + 0] = entries[i].a;
    index_data[3 * i + 1] = entries[i].b;
    index_data[3 * i + 2] = entries[i].c;
    value_data[i] = entries[i].value;
  }
  return py::make_tuple(std::move(indices), std::move(values));
}

}  // namespace

void bind_core(py::module_& m) {
  m.attr("DESIGN_TOLERANCE") = sd::kDesignTolerance;

  m.def("sh_basis", &py_sh_basis, py::arg("lmax"), py::arg("dirs"),
        R"doc(Real SH y_lm (module convention) for all l <= lmax at the given directions.

lmax: order in [0, MAX_SH_ORDER].
dirs: float array of shape (N, 3), or a single direction of shape (3,). Directions are
      normalised here; zero-length or non-finite ones raise ValueError.
Returns an array of shape (N, (lmax+1)**2), or ((lmax+1)**2,) for a single direction; column
l*l + l + m holds y_lm.)doc");

  m.def("sh_recurrence_constants", &py_sh_recurrence_constants, py::arg("order"),
        R"doc(The constants of the recurrences sh_basis evaluates with (the very numbers of the C++ code),
for l <= order (0 .. MAX_SH_ORDER): Q_mm = diagonal[m]; for m < l,
Q_lm(z) = a[k] z Q_{l-1,m}(z) - b[k] Q_{l-2,m}(z) with k = l (l + 1) / 2 + m, a_{m+1,m} = sqrt(2m+3),
b_{m+1,m} = 0; entries with m == l are 0. Then y_l0 = Q_l0, y_l,+m = Q_lm Re (x + i y)^m,
y_l,-m = Q_lm Im (x + i y)^m.
Returns a dict of float64 arrays: "diagonal" (order+1,), "a" and "b" ((order+1)(order+2)/2,).)doc");

  m.def("rotate_sh", &py_rotate_sh, py::arg("coeffs"), py::arg("rotation"),
        R"doc(Rotates SH expansions: returns the coefficients of x -> f(R^T x) (f turned by R).

coeffs: shape (K,) or (K, C) (C channels, e.g. RGB); K = (lmax+1)**2 with lmax <= MAX_SH_ORDER.
rotation: proper rotation matrix R of shape (3, 3), numpy row-major (R[i, j] = row i, column j),
          orthogonal with det +1 to about 1e-9; otherwise ValueError.
Returns an array of the same shape as coeffs. The environment seen through a rotation g,
L(g x), has coefficients rotate_sh(L, g.T).)doc");

  m.def("zonal_coefficients", &py_zonal_coefficients, py::arg("lobe"), py::arg("exponent"), py::arg("lmax"),
        R"doc(Funk-Hecke factors w_l = 1/2 integral_{-1}^{1} w(t) P_l(t) dt, l = 0 .. lmax, of a lobe.

lobe: "lambert" (exponent ignored) or "phong" (exponent sigma in [0, MAX_PHONG_EXPONENT]).
lmax: >= 0.
Returns shape (lmax+1,); element 0 is 1 (the lobes are normalised), and
integral f(x) w(a.x) dmu(x) = sum_lm w_l f_lm y_lm(a).)doc");

  m.def("legendre", &py_legendre, py::arg("lmax"), py::arg("t"),
        R"doc(Legendre polynomials P_0(t) .. P_lmax(t) by the three-term recurrence.

t: finite values, shape (N,) (or a scalar). Returns shape (N, lmax+1) (or (lmax+1,)).)doc");

  m.def("gaunt_coefficients", &py_gaunt_coefficients, py::arg("order_a"), py::arg("order_b"), py::arg("order_c"),
        R"doc(Every non-zero real Gaunt coefficient G_abc = integral y_a y_b y_c dmu with l_a <= order_a,
l_b <= order_b, l_c <= order_c (orders in [0, MAX_SH_ORDER]), so that y_a y_b = sum_c G_abc y_c
when order_c >= l_a + l_b.

Returns (indices, values): indices int32 of shape (E, 3) holding flat SH indices (a, b, c), sorted
by (a, b, c); values float64 of shape (E,).)doc");

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
