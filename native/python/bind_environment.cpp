// Bindings of environment maps (sdlighting/environment.h): the class sdnative.Environment with the
// map's own members (size, layout, texels, masses and norms, lookups, area-averaged copies) and maps
// from pixels. The class's other methods are bound beside their headers: bind_sh_projection,
// bind_environment_error, bind_ringing, bind_channel_design (registered after this one); loading
// files, in the test module only, by bind_image_files.
//
// Errors: bad arguments and bad image data (NaN or infinite pixels, empty images, wrong shapes,
// orders out of range) raise ValueError. Heavy work runs without the GIL.
#include "array_checks.h"
#include "bindings.h"
#include "environment_class.h"
#include "sdlighting/environment.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <glm/vec3.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sdpy {
namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// Copies the first three channels of an (..., 3) or (..., 4) float array.
std::vector<float> rgb_from_array(const FloatArray& a, py::ssize_t pixels) {
  const py::ssize_t channels = a.shape(a.ndim() - 1);
  std::vector<float> rgb(static_cast<size_t>(pixels) * 3);
  const float* data = a.data();
  for (py::ssize_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < 3; ++c) rgb[3 * p + c] = data[p * channels + c];
  }
  return rgb;
}

sd::Environment environment_from_pixels(const FloatArray& rgb) {
  if (rgb.ndim() != 3 || (rgb.shape(2) != 3 && rgb.shape(2) != 4)) {
    value_error("rgb must have shape (height, width, 3) or (height, width, 4), got " + shape_string(rgb));
  }
  const py::ssize_t h = rgb.shape(0), w = rgb.shape(1);
  if (h > std::numeric_limits<int>::max() || w > std::numeric_limits<int>::max()) value_error("rgb is too large");
  std::vector<float> pixels = rgb_from_array(rgb, h * w);
  py::gil_scoped_release release;
  return sd::Environment::from_equirect_pixels(static_cast<int>(w), static_cast<int>(h), std::move(pixels));
}

sd::Environment environment_from_cube_pixels(const FloatArray& rgb) {
  if (rgb.ndim() != 4 || rgb.shape(0) != 6 || rgb.shape(1) != rgb.shape(2) ||
      (rgb.shape(3) != 3 && rgb.shape(3) != 4)) {
    value_error("rgb must have shape (6, N, N, 3) or (6, N, N, 4), got " + shape_string(rgb));
  }
  const py::ssize_t n = rgb.shape(1);
  if (n > std::numeric_limits<int>::max()) value_error("rgb is too large");
  std::vector<float> pixels = rgb_from_array(rgb, 6 * n * n);
  py::gil_scoped_release release;
  return sd::Environment::from_cube_pixels(static_cast<int>(n), std::move(pixels));
}

// A per-channel measure of the map for R, G, B and the luminance, shape (4,).
py::array_t<double> per_channel(const sd::Environment& e, double (sd::Environment::*measure)(int) const) {
  py::array_t<double> out(4);
  for (int c = 0; c < 4; ++c) out.mutable_data()[c] = (e.*measure)(c);
  return out;
}

py::array_t<double> py_radiance(const sd::Environment& env, const DoubleArray& dirs) {
  const bool single = dirs.ndim() == 1;
  const std::vector<glm::dvec3> d = read_directions("dirs", dirs, true);
  const auto n = static_cast<py::ssize_t>(d.size());
  py::array_t<double> out = single ? py::array_t<double>(3) : py::array_t<double>({n, py::ssize_t(3)});
  double* data = out.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const glm::dvec3 l = env.radiance(d[i]);
    data[3 * i] = l.x, data[3 * i + 1] = l.y, data[3 * i + 2] = l.z;
  }
  return out;
}

py::tuple py_texels(const sd::Environment& env) {
  const auto t = static_cast<py::ssize_t>(env.texel_count());
  py::array_t<double> dirs({t, py::ssize_t(3)}), solid_angles(t), rgb({t, py::ssize_t(3)});
  double* d = dirs.mutable_data();
  double* s = solid_angles.mutable_data();
  double* c = rgb.mutable_data();
  const float* px = env.pixels().data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < t; ++i) {
      const glm::dvec3 dir = env.texel_direction(i);
      d[3 * i] = dir.x, d[3 * i + 1] = dir.y, d[3 * i + 2] = dir.z;
      s[i] = env.texel_solid_angle(i);
      for (int k = 0; k < 3; ++k) c[3 * i + k] = px[3 * i + k];
    }
  }
  return py::make_tuple(std::move(dirs), std::move(solid_angles), std::move(rgb));
}

py::array_t<float> py_pixels(const sd::Environment& env) {
  const bool cube = env.layout() == sd::EnvironmentLayout::Cube;
  std::vector<py::ssize_t> shape = {py::ssize_t(env.height()), py::ssize_t(env.width()), py::ssize_t(3)};
  if (cube) shape.insert(shape.begin(), 6);
  py::array_t<float> out(shape);
  std::copy(env.pixels().begin(), env.pixels().end(), out.mutable_data());
  return out;
}

}  // namespace

// A channel given as 0, 1, 2 (R, G, B), 3 or "luminance" (also "r", "g", "b", "y").
int parse_channel(const py::object& channel) {
  if (py::isinstance<py::str>(channel)) {
    const std::string name = channel.cast<std::string>();
    if (name == "luminance" || name == "y" || name == "Y") return sd::kLuminance;
    if (name == "r" || name == "R" || name == "red") return 0;
    if (name == "g" || name == "G" || name == "green") return 1;
    if (name == "b" || name == "B" || name == "blue") return 2;
    value_error("channel must be 0, 1, 2 or 'luminance', got '" + name + "'");
  }
  if (py::isinstance<py::int_>(channel) && !py::isinstance<py::bool_>(channel)) {
    const long long value = channel.cast<long long>();
    if (value < 0 || value > sd::kLuminance) {
      value_error("channel must be 0, 1, 2 or 'luminance' (3), got " + std::to_string(value));
    }
    return static_cast<int>(value);
  }
  value_error("channel must be an int (0, 1, 2) or 'luminance'");
}

py::class_<sd::Environment> environment_class(py::module_& m) {
  return py::reinterpret_borrow<py::class_<sd::Environment>>(m.attr("Environment"));
}

void bind_environment(py::module_& m) {
  py::class_<sd::Environment> env(m, "Environment", R"doc(A distant environment map L (immutable).

Built by environment_from_pixels or environment_from_cube_pixels (and, in the tests' module,
load_environment or load_cube_environment). Orientation is Blender's world (Cycles' equirectangular mapping):
direction d is seen at u = 0.5 - atan2(d.y, d.x) / (2 pi), v = 1 - acos(d.z) / pi with v = 0 at
the image's bottom row, so in an image held rows top-first (as files are) the pixel in row j,
column i has centre theta = pi (j + 0.5) / H, phi = pi - 2 pi (i + 0.5) / W: +X looks at the
horizontal centre, +Y at column W/4, +Z at the top row. The map is piecewise constant over texels;
every texel has an exact solid angle in units of dmu = dx / (4 pi) (they sum to 1).

SH coefficients use the module's convention (y_00 = 1, orthonormal for dmu) and come as arrays of
shape ((lmax+1)**2, 3): row l*l + l + m, columns R, G, B.)doc");

  env.def_property_readonly("width", &sd::Environment::width, "Image width in pixels (cube: the face size).")
      .def_property_readonly("height", &sd::Environment::height, "Image height in pixels (cube: the face size).")
      .def_property_readonly(
          "layout",
          [](const sd::Environment& e) { return e.layout() == sd::EnvironmentLayout::Cube ? "cube" : "equirect"; },
          "'equirect' or 'cube'.")
      .def_property_readonly("texel_count", &sd::Environment::texel_count,
                             "Number of texels: width * height, or 6 * face**2 for a cube.")
      .def_property_readonly("clamped_negative_pixels", &sd::Environment::clamped_negative_pixels,
                             "Pixels that had a negative channel; they were clamped to 0 on load.")
      .def_property_readonly(
          "mass", [](const sd::Environment& e) { return per_channel(e, &sd::Environment::mass); },
          "integral L dmu (the average radiance) of R, G, B and the luminance Y = 0.2126 R + 0.7152 G + "
          "0.0722 B, shape (4,).")
      .def_property_readonly(
          "norm_squared", [](const sd::Environment& e) { return per_channel(e, &sd::Environment::norm_squared); },
          "integral L**2 dmu of R, G, B and the luminance, shape (4,).")
      .def("radiance", &py_radiance, py::arg("dirs"),
           R"doc(L(d) at directions of shape (N, 3) (or one of shape (3,)): the radiance of the texel that
contains d (nearest texel, no filtering). Directions need not be unit. Returns (N, 3) (or (3,)).)doc")
      .def("texels", &py_texels,
           R"doc(The texels as (dirs (T, 3) unit centre directions, solid_angles (T,) in units of dmu summing
to 1, rgb (T, 3) linear radiance): every sum over the map (and a brute-force integral) runs over
these. Texel order: row-major rows top-first (cube: face +X, -X, +Y, -Y, +Z, -Z, then rows).)doc")
      .def("pixels", &py_pixels,
           "The stored linear RGB (after sRGB decoding and clamping) as float32 (height, width, 3), or "
           "(6, N, N, 3) for a cube; rows top-first.")
      .def(
          "area_averaged",
          [](const sd::Environment& e, int width, int height) {
            py::gil_scoped_release release;
            return e.area_averaged(width, height);
          },
          py::arg("width"), py::arg("height"),
          R"doc(An area-averaged copy of the same layout (exact box filter of the piecewise-constant map;
masses are preserved). For a cube pass the new face size as width and height.)doc")
      .def("__repr__", [](const sd::Environment& e) {
        return std::string("<sdnative.Environment ") +
               (e.layout() == sd::EnvironmentLayout::Cube ? "cube " : "equirect ") + std::to_string(e.width()) + "x" +
               std::to_string(e.height()) + ">";
      });

  m.def("environment_from_pixels", &environment_from_pixels, py::arg("rgb"),
        R"doc(An equirectangular environment from linear RGB of shape (height, width, 3) (or (height, width, 4):
alpha ignored), rows top-first as in files. Blender's Image.pixels are bottom-up RGBA: reshape to
(height, width, 4) and flip with [::-1] first. Raises ValueError for NaN or infinite values or an
empty image; negative values are clamped to 0 and counted.)doc");

  m.def("environment_from_cube_pixels", &environment_from_cube_pixels, py::arg("rgb"),
        R"doc(A cube-map environment from linear RGB of shape (6, N, N, 3) (or (6, N, N, 4)): faces +X, -X,
+Y, -Y, +Z, -Z, rows top-first (see load_cube_environment for the orientation).)doc");
}

}  // namespace sdpy
