// Bindings of the spherical harmonics: the basis and its recurrence constants, rotation (of any
// function, and of the environment of eq. (1)), the lobes' Funk–Hecke factors, Legendre
// polynomials and Gaunt coefficients. Bad input raises ValueError naming the argument.
#include "array_checks.h"
#include "bindings.h"
#include "sdlighting/gaunt.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/zonal_lobe.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace sdpy {
namespace {

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

// SH coefficients of shape (K,) or (K, C) (C channels), K = (lmax+1)², finite: (lmax, C).
std::pair<int, int> read_sh_coefficients(const DoubleArray& coeffs) {
  if (coeffs.ndim() != 1 && coeffs.ndim() != 2) {
    value_error("coeffs must have shape (K,) or (K, C), got " + shape_string(coeffs));
  }
  const py::ssize_t k = coeffs.shape(0);
  const py::ssize_t channels = coeffs.ndim() == 2 ? coeffs.shape(1) : 1;
  const int order = sh_order_from_count("coeffs", k, sd::kMaxShOrder);
  if (channels > std::numeric_limits<int>::max()) value_error("coeffs has too many channels");
  check_finite("coeffs", coeffs.data(), static_cast<size_t>(k * channels));
  return {order, static_cast<int>(channels)};
}

py::array_t<double> shaped_like(const DoubleArray& a) {
  return py::array_t<double>(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()));
}

py::array_t<double> py_rotate_sh(const DoubleArray& coeffs, const DoubleArray& rotation) {
  const auto [order, channels] = read_sh_coefficients(coeffs);
  const glm::dmat3 r = read_rotation(rotation);
  py::array_t<double> out = shaped_like(coeffs);
  const double* in = coeffs.data();
  double* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    const sd::ShRotation d(r, order);  // validates the rotation: std::invalid_argument -> ValueError
    if (channels > 0) d.apply(in, data, channels);
  }
  return out;
}

py::array_t<double> py_rotated_environment_sh(const DoubleArray& coeffs, const DoubleArray& g) {
  const auto [order, channels] = read_sh_coefficients(coeffs);
  const glm::dmat3 rotation = read_rotation(g);
  const std::vector<double> in(coeffs.data(), coeffs.data() + coeffs.size());
  std::vector<double> rotated;
  {
    py::gil_scoped_release release;
    rotated = sd::rotated_sh(in, order, rotation, channels);  // bad g or no channel: ValueError
  }
  py::array_t<double> out = shaped_like(coeffs);
  std::copy(rotated.begin(), rotated.end(), out.mutable_data());
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
  // The recurrence grows like (|t| + sqrt(t² − 1))^l outside [−1, 1] and overflows to inf.
  for (py::ssize_t i = 0; i < n; ++i) {
    if (std::abs(t.data()[i]) > 1.0) {
      value_error("t must lie in [-1, 1] (Legendre polynomials of cos theta), got t[" + std::to_string(i) +
                  "] = " + py::str(py::float_(t.data()[i])).cast<std::string>());
    }
  }
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

void bind_sh(py::module_& m) {
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
          orthogonal to 1e-5 (float32 matrices pass; the nearest exact rotation is used) and
          not a reflection (det -1); otherwise ValueError.
Returns an array of the same shape as coeffs. For the environment seen through a rotation g,
L(g x), use rotated_environment_sh(L, g).)doc");

  m.def("rotated_environment_sh", &py_rotated_environment_sh, py::arg("coeffs"), py::arg("g"),
        R"doc(Coefficients of x -> L(g x), the environment seen through the rotation g of eq. (1):
D(g^T) L (the same as rotate_sh(coeffs, g.T)), by the one C++ function that states the convention.

coeffs: shape (K, 3) (or (K,), (K, C)) with K = (lmax+1)**2, lmax <= MAX_SH_ORDER.
g: proper rotation of shape (3, 3), numpy row-major. Returns the shape of coeffs.)doc");

  m.def("zonal_coefficients", &py_zonal_coefficients, py::arg("lobe"), py::arg("exponent"), py::arg("lmax"),
        R"doc(Funk-Hecke factors w_l = 1/2 integral_{-1}^{1} w(t) P_l(t) dt, l = 0 .. lmax, of a lobe.

lobe: "lambert" (exponent ignored) or "phong" (exponent sigma in [0, MAX_PHONG_EXPONENT]).
lmax: >= 0.
Returns shape (lmax+1,); element 0 is 1 (the lobes are normalised), and
integral f(x) w(a.x) dmu(x) = sum_lm w_l f_lm y_lm(a).)doc");

  m.def("legendre", &py_legendre, py::arg("lmax"), py::arg("t"),
        R"doc(Legendre polynomials P_0(t) .. P_lmax(t) by the three-term recurrence.

t: values in [-1, 1], shape (N,) (or a scalar); others raise ValueError. Returns shape (N, lmax+1) (or (lmax+1,)).)doc");

  m.def("gaunt_coefficients", &py_gaunt_coefficients, py::arg("order_a"), py::arg("order_b"), py::arg("order_c"),
        R"doc(Every non-zero real Gaunt coefficient G_abc = integral y_a y_b y_c dmu with l_a <= order_a,
l_b <= order_b, l_c <= order_c (orders in [0, MAX_SH_ORDER]), so that y_a y_b = sum_c G_abc y_c
when order_c >= l_a + l_b.

Returns (indices, values): indices int32 of shape (E, 3) holding flat SH indices (a, b, c), sorted
by (a, b, c); values float64 of shape (E,).)doc");
}

}  // namespace sdpy
