// Bindings of the shading formulas: sdnative.shade(method, ...).
#include "array_checks.h"
#include "bindings.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/shading.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/zonal_design.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <glm/matrix.hpp>

#include <iterator>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace sdpy {
namespace {

using IndexArray = py::array_t<int64_t, py::array::c_style | py::array::forcecast>;

// Lobe designs depend only on (material, degree): built once per process.
const sd::SphericalDesign& cached_lobe_design(const sd::Material& material, int degree) {
  static std::mutex mutex;
  static std::map<std::tuple<bool, double, int>, sd::SphericalDesign> cache;
  const auto key = std::make_tuple(material.glossy, material.exponent, degree);
  std::lock_guard<std::mutex> lock(mutex);
  auto found = cache.find(key);
  if (found == cache.end()) {
    found = cache.emplace(key, sd::zonal_design(sd::ZonalWeight::from_lobe(material.lobe()), degree)).first;
  }
  return found->second;
}

// Unit rows of an (N, 3) array, flattened.
std::vector<double> unit_rows(const char* name, const DoubleArray& a, size_t expected_rows) {
  const std::vector<glm::dvec3> dirs = read_directions(name, a, false);
  if (dirs.size() != expected_rows) {
    value_error(std::string(name) + " must have " + std::to_string(expected_rows) + " rows, got " +
                std::to_string(dirs.size()));
  }
  std::vector<double> flat;
  flat.reserve(3 * dirs.size());
  for (const auto& d : dirs) flat.insert(flat.end(), {d.x, d.y, d.z});
  return flat;
}

// A required per-vertex array of exactly `shape`, finite.
const DoubleArray& require(const char* name, const std::optional<DoubleArray>& a, const std::vector<py::ssize_t>& shape) {
  if (!a) value_error(std::string("this method needs ") + name);
  bool ok = a->ndim() == static_cast<py::ssize_t>(shape.size());
  for (size_t i = 0; ok && i < shape.size(); ++i) ok = a->shape(i) == shape[i];
  if (!ok) {
    std::string expected = "(";
    for (size_t i = 0; i < shape.size(); ++i) expected += (i ? ", " : "") + std::to_string(shape[i]);
    value_error(std::string(name) + " must have shape " + expected + "), got " + shape_string(*a));
  }
  check_finite(name, a->data(), static_cast<size_t>(a->size()));
  return *a;
}

// The order s' of per-vertex SH data whose last axis holds (s'+1)² coefficients.
int trailing_order(const char* name, const std::optional<DoubleArray>& a) {
  if (!a || a->ndim() < 2) value_error(std::string("this method needs ") + name + " with SH coefficients on its last axis");
  return sh_order_from_count(name, a->shape(a->ndim() - 1), sd::kMaxShadingOrder);
}

// The arguments of shade() that the methods read, checked shape by shape by the method that reads them.
struct ShadeArguments {
  const sd::ShadingInputs& in;
  py::ssize_t rows;  // N
  const std::optional<DoubleArray>& ambient_occlusion;
  const std::optional<DoubleArray>& transfer;
  const std::optional<DoubleArray>& visibility;
  const std::optional<DoubleArray>& product_matrices;
  std::optional<int> visibility_order;
  const std::optional<IndexArray>& design_offsets;
  const std::optional<DoubleArray>& design_nodes;
  const std::optional<DoubleArray>& design_weights;

  // sh_count(s), the light's coefficients.
  py::ssize_t k() const { return sd::sh_count(in.light_order); }

  // Ṽ of shape (N, (s'+1)²) for prt_gaunt and msd_lobe; s_v receives s'.
  const DoubleArray& visibility_sh(int& s_v) const {
    s_v = trailing_order("visibility", visibility);
    return require("visibility", visibility, {rows, sd::sh_count(s_v)});
  }
};

// One method of shade(): its id (sdnative.shade's name, the add-on's and the shader's SD_METHOD_<ID>)
// and what it does: check the arrays it reads, then run its evaluator (shading.h's shade_<id>)
// without the GIL into out (N × 3).
struct ShadeMethod {
  const char* id;
  void (*shade)(const ShadeArguments& a, double* out);
};

// The methods, keyed by id.
const ShadeMethod kShadeMethods[] = {
    {"unshadowed",
     [](const ShadeArguments& a, double* out) {
       py::gil_scoped_release release;
       sd::shade_unshadowed(a.in, out);
     }},
    {"ambient_occlusion",
     [](const ShadeArguments& a, double* out) {
       const DoubleArray& ao = require("ambient_occlusion", a.ambient_occlusion, {a.rows});
       py::gil_scoped_release release;
       sd::shade_ambient_occlusion(a.in, ao.data(), out);
     }},
    {"prt_diffuse",
     [](const ShadeArguments& a, double* out) {
       const DoubleArray& t = require("transfer", a.transfer, {a.rows, a.k()});
       py::gil_scoped_release release;
       sd::shade_prt_diffuse(a.in, t.data(), out);
     }},
    {"prt_matrix",
     [](const ShadeArguments& a, double* out) {
       const int s_v = trailing_order("product_matrices", a.product_matrices);
       const DoubleArray& m = require("product_matrices", a.product_matrices, {a.rows, a.k(), sd::sh_count(s_v)});
       py::gil_scoped_release release;
       sd::shade_prt_matrix(a.in, s_v, m.data(), out);
     }},
    {"prt_gaunt",
     [](const ShadeArguments& a, double* out) {
       int s_v = 0;
       const DoubleArray& v = a.visibility_sh(s_v);
       py::gil_scoped_release release;
       sd::shade_prt_gaunt(a.in, s_v, v.data(), out);
     }},
    {"msd_lobe",
     [](const ShadeArguments& a, double* out) {
       int s_v = 0;
       const DoubleArray& v = a.visibility_sh(s_v);
       py::gil_scoped_release release;
       sd::shade_msd_lobe(a.in, s_v, v.data(), cached_lobe_design(a.in.material, a.in.light_order + s_v), out);
     }},
    {"msd_visibility",
     [](const ShadeArguments& a, double* out) {
       if (!a.visibility_order) value_error("msd_visibility needs visibility_order (s', the order of the truncated lobe)");
       check_order("visibility_order", *a.visibility_order, sd::kMaxShadingOrder);
       if (!a.design_offsets || a.design_offsets->ndim() != 1 || a.design_offsets->shape(0) != a.rows + 1) {
         value_error("msd_visibility needs design_offsets of shape (N+1,)");
       }
       const int64_t* offsets = a.design_offsets->data();
       const size_t n = static_cast<size_t>(a.rows);
       if (offsets[0] != 0) value_error("design_offsets must start at 0");
       for (size_t p = 0; p < n; ++p) {
         if (offsets[p + 1] < offsets[p]) value_error("design_offsets must be non-decreasing");
       }
       const py::ssize_t total = static_cast<py::ssize_t>(offsets[n]);
       const DoubleArray& nodes = require("design_nodes", a.design_nodes, {total, 3});
       const DoubleArray& weights = require("design_weights", a.design_weights, {total});
       py::gil_scoped_release release;
       sd::shade_msd_visibility(a.in, *a.visibility_order, sd::VertexDesigns{offsets, nodes.data(), weights.data()},
                                out);
     }},
};

// The method with this id; ValueError listing the ids otherwise.
const ShadeMethod& shade_method(const std::string& id) {
  for (const ShadeMethod& method : kShadeMethods) {
    if (id == method.id) return method;
  }
  std::string ids;
  const size_t count = std::size(kShadeMethods);
  for (size_t i = 0; i < count; ++i) {
    ids += std::string(i == 0 ? "" : i + 1 == count ? " or " : ", ") + kShadeMethods[i].id;
  }
  value_error("unknown method '" + id + "' (expected " + ids + ")");
}

py::array_t<double> shade(const std::string& method, const DoubleArray& light, const DoubleArray& normals,
                          const std::optional<DoubleArray>& views, const std::optional<DoubleArray>& rotation,
                          const std::string& lobe, double exponent, const std::optional<DoubleArray>& ambient_occlusion,
                          const std::optional<DoubleArray>& transfer, const std::optional<DoubleArray>& visibility,
                          const std::optional<DoubleArray>& product_matrices, std::optional<int> visibility_order,
                          const std::optional<IndexArray>& design_offsets, const std::optional<DoubleArray>& design_nodes,
                          const std::optional<DoubleArray>& design_weights) {
  if (light.ndim() != 2 || light.shape(1) != 3) value_error("light must have shape (K, 3), got " + shape_string(light));
  const int s = sh_order_from_count("light", light.shape(0), sd::kMaxShadingOrder);
  check_finite("light", light.data(), static_cast<size_t>(light.size()));
  if (normals.ndim() != 2) value_error("normals must have shape (N, 3), got " + shape_string(normals));
  const size_t n = static_cast<size_t>(normals.shape(0));
  const auto rows = static_cast<py::ssize_t>(n);
  const std::vector<double> unit_normals = unit_rows("normals", normals, n);
  sd::Material material = sd::Material::from_name(lobe, exponent);
  std::vector<double> unit_views;
  if (material.glossy) {
    if (!views) value_error("a phong material needs views (unit vectors from the vertices to the eye)");
    unit_views = unit_rows("views", *views, n);
  }

  const glm::dmat3 g = rotation ? read_rotation(*rotation) : glm::dmat3(1.0);
  const std::vector<double> rotated =
      sd::rotated_sh(std::vector<double>(light.data(), light.data() + light.size()), s, g);

  sd::ShadingInputs in;
  in.light_order = s;
  in.light = rotated.data();
  in.vertex_count = n;
  in.normals = unit_normals.data();
  in.view_dirs = material.glossy ? unit_views.data() : nullptr;
  in.material = material;

  const ShadeMethod& evaluator = shade_method(method);
  py::array_t<double> out({rows, py::ssize_t{3}});
  evaluator.shade(ShadeArguments{in, rows, ambient_occlusion, transfer, visibility, product_matrices, visibility_order,
                                 design_offsets, design_nodes, design_weights},
                  out.mutable_data());
  return out;
}

}  // namespace

void bind_shading(py::module_& m) {
  m.def("shade", &shade, py::arg("method"), py::arg("light"), py::arg("normals"), py::arg("views") = py::none(),
        py::arg("rotation") = py::none(), py::arg("lobe") = "lambert", py::arg("exponent") = 1.0,
        py::arg("ambient_occlusion") = py::none(), py::arg("transfer") = py::none(),
        py::arg("visibility") = py::none(), py::arg("product_matrices") = py::none(),
        py::arg("visibility_order") = py::none(), py::arg("design_offsets") = py::none(),
        py::arg("design_nodes") = py::none(), py::arg("design_weights") = py::none(),
        R"doc(Reflected radiance B (eq. 1) at every vertex by one of the method's formulas, on both cores.

method: which formula (equation numbers of the seed):
  "unshadowed"         Σ ŵ_l L_lm(g) y_lm(a), V = 1
  "ambient_occlusion"  ambient_occlusion × unshadowed
  "prt_diffuse"        eq. (2): Σ L_lm(g) T_lm with transfer T (Lambert only)
  "prt_matrix"         eqs. (8)-(9) with product_matrices M
  "prt_gaunt"          eq. (10) with visibility Ṽ and real Gaunt coefficients
  "msd_lobe"           eq. (12), Theorem 2.1: a lobe design of degree s+s' (built once and cached)
  "msd_visibility"     eq. (13), Theorem 2.2: per-vertex designs of V, lobe truncated at visibility_order
light: environment SH coefficients, shape ((s+1)**2, 3), s <= MAX_SHADING_ORDER, *not* rotated.
normals: (N, 3); views: (N, 3) unit vectors from the vertex to the eye (needed for phong).
rotation: g (3, 3), the environment rotation of eq. (1) (default identity); L is rotated to
          L(g x) internally.
lobe, exponent: "lambert", or "phong" with σ in [0, MAX_PHONG_EXPONENT].
ambient_occlusion (N,), transfer (N, (s+1)**2), visibility (N, (s'+1)**2),
product_matrices (N, (s+1)**2, (s'+1)**2), design_offsets int64 (N+1,), design_nodes (total, 3),
design_weights (total,): per-vertex data as returned by bake_transfer.
Returns (N, 3) linear RGB: the raw formula, not clamped (a truncated L rings below zero next to a
bright light, and the formulas' exactness tests compare the raw values); the add-on displays
max(B, 0) per channel, and windows L against ringing first (Environment.ringing_window).
Releases the GIL while it computes.)doc");
}

}  // namespace sdpy
