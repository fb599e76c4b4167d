// Bindings of the split sum (sdlighting/glossy_prefilter.h): Environment.prefiltered_ggx,
// environment_brdf, environment_brdf_table, glossy_bend and glossy_bend_table.
//
// Errors: a bad layout, sample count, n·v or roughness raises ValueError. The prefilter runs
// without the GIL.
#include "bindings.h"
#include "environment_class.h"
#include "sdlighting/glossy_prefilter.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <vector>

namespace sdpy {
namespace {

/// A table made without the GIL (make() -> std::vector<float>), as float64 of `shape`.
template <typename F>
py::array_t<double> table_array(std::vector<py::ssize_t> shape, F make) {
  std::vector<float> table;
  {
    py::gil_scoped_release release;
    table = make();
  }
  py::array_t<double> out(shape);
  std::copy(table.begin(), table.end(), out.mutable_data());
  return out;
}

}  // namespace

void bind_glossy_prefilter(py::module_& m) {
  py::class_<sd::Environment> env = environment_class(m);
  env.def(
      "prefiltered_ggx",
      [](const sd::Environment& e, int width0, int levels, int samples) {
        const sd::PrefilterLayout layout{width0, levels};
        layout.check();
        std::vector<float> atlas;
        {
          py::gil_scoped_release release;
          atlas = sd::prefilter_ggx(e, layout, samples);
        }
        py::array_t<double> out({layout.atlas_height(), layout.atlas_width(), 3});
        std::copy(atlas.begin(), atlas.end(), out.mutable_data());
        return out;
      },
      py::arg("width0") = sd::PrefilterLayout().width0, py::arg("levels") = sd::PrefilterLayout().levels, py::arg("samples") = 64,
      R"doc(The map prefiltered by the GGX lobe per roughness level (the split sum's first factor):
the atlas, float64 [width0 + width0 / 4, width0, 3] (width0 + width0 / 2 rows for 3 levels) with rows
bottom-first as GPU textures hold them, laid out as sdlighting/glossy_prefilter.h's PrefilterLayout
says: level 0 the map itself, level k >= 1 GGX alpha = 2^(k - (levels - 1)) (alpha doubles from
level to level up to 1), equirect images of Blender's orientation. The defaults are PREFILTER_WIDTH
and PREFILTER_LEVELS. `samples` GGX directions per texel on level 1, twice as many per level after
it, near each texel's direction (filtered importance sampling); the lobe's tail beyond, exactly. ValueError for a width0 that is not a power of two in [4,
MAX_TEXTURE_SIDE], levels < 3 or with width0 >> (levels - 3) < 4, samples outside [1, 4096].)doc");
  m.def(
      "prefilter_atlas_shape",
      [](int width0, int levels) {
        const sd::PrefilterLayout layout{width0, levels};
        layout.check();
        return py::make_tuple(layout.atlas_height(), layout.atlas_width());
      },
      py::arg("width0") = sd::PrefilterLayout().width0, py::arg("levels") = sd::PrefilterLayout().levels,
      R"doc((rows, columns) of Environment.prefiltered_ggx's atlas for that layout. ValueError where
prefiltered_ggx refuses the layout.)doc");
  m.def(
      "environment_brdf",
      [](double n_dot_v, double roughness, int samples, double ior) {
        const auto ab = sd::environment_brdf(n_dot_v, roughness, samples, ior);
        return py::make_tuple(ab[0], ab[1]);
      },
      py::arg("n_dot_v"), py::arg("roughness"), py::arg("samples") = 1024, py::arg("ior") = 0.0,
      R"doc((A, B): the GGX lobe's directional albedo F0 A + B at n.v in (0, 1] and Principled
roughness in [0, 1] (single scattering, Smith height-correlated), by `samples` GGX half vectors, for
Schlick's Fresnel (ior 0) or the dielectric Fresnel of `ior` > 1 remapped to F0..1 (Cycles'
dielectric layer). ValueError outside those ranges.)doc");
  m.def(
      "environment_brdf_table",
      [](int size, int samples, double ior) {
        return table_array({size, size, 2}, [&] { return sd::environment_brdf_table(size, samples, ior); });
      },
      py::arg("size") = 32, py::arg("samples") = 1024, py::arg("ior") = 0.0,
      R"doc(environment_brdf tabulated: float64 [size, size, 2], (A, B) at n.v = (i + 0.5) / size (column
i) and roughness j / (size - 1) (row j), for `ior` as environment_brdf. ValueError for size outside
[2, 256], samples outside [1, 2^20] or a bad ior.)doc");
  m.def("glossy_bend", &sd::glossy_bend, py::arg("n_dot_v"), py::arg("roughness"), py::arg("samples") = 1024, py::arg("ior") = 0.0,
        R"doc(Where the prefiltered light is read for a view at n.v in (0, 1] and Principled roughness
in [0, 1]: at normalize(mix(n, r, bend)), the GGX lobe's mean direction (r the mirrored view),
its light weighted by the dielectric Fresnel of `ior` > 1 (a plastic's layer) or not (ior 0, a
metal). ValueError outside those ranges, for samples outside [1, 2^20] or a bad ior.)doc");
  m.def(
      "glossy_bend_table",
      [](int size, int samples, double ior) {
        return table_array({size, size}, [&] { return sd::glossy_bend_table(size, samples, ior); });
      },
      py::arg("size") = 32, py::arg("samples") = 1024, py::arg("ior") = 0.0,
      R"doc(glossy_bend tabulated as environment_brdf_table is: float64 [size, size], the bend at
n.v = (i + 0.5) / size (column i) and roughness j / (size - 1) (row j), for `ior` as glossy_bend.
ValueError for size outside [2, 256], samples outside [1, 2^20] or a bad ior.)doc");
}

}  // namespace sdpy
