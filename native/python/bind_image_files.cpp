// Bindings of Environment::load and load_cube (the library sdlighting_image_files, OpenImageIO): in the
// test module `sdnative` only. The add-on's module reads no files: Blender reads the image and passes
// its pixels (environment_from_pixels), so the module links no image library (issue 31).
//
// Errors: files that cannot be opened or decoded raise OSError whose message names the path and
// OpenImageIO's reason; bad image data (NaN or infinite pixels, empty images) ValueError.
#include "array_checks.h"
#include "bindings.h"
#include "environment_class.h"
#include "sdlighting/environment.h"

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sdpy {
namespace {

// Runs `load` without the GIL; std::runtime_error (unreadable file) becomes OSError.
template <typename Load>
sd::Environment load_or_os_error(Load&& load) {
  std::optional<sd::Environment> env;
  std::string failure;
  {
    py::gil_scoped_release release;
    try {
      env.emplace(load());
    } catch (const std::invalid_argument&) {
      throw;  // bad data: ValueError
    } catch (const std::runtime_error& error) {
      failure = error.what();
    }
  }
  if (!env) {
    PyErr_SetString(PyExc_OSError, failure.c_str());
    throw py::error_already_set();
  }
  return std::move(*env);
}

}  // namespace

void bind_image_files(py::module_& m) {
  m.def(
      "load_environment",
      [](const std::string& path) { return load_or_os_error([&] { return sd::Environment::load(path); }); },
      py::arg("path"),
      R"doc(Loads an equirectangular environment map with OpenImageIO (EXR, HDR, PFM, TIFF, PNG, JPEG, ...).

Float files are linear; 8/16-bit integer files are decoded from sRGB (unless the file declares a
linear colour space). Greyscale becomes RGB; alpha is ignored. Negative values are clamped to 0
(counted in clamped_negative_pixels).
Raises OSError (message with the path and OpenImageIO's reason) if the file cannot be opened or
read, or (without reading it) if it is a directory, a FIFO, a device file or empty; ValueError if
the image holds NaN or infinite values. Releases the GIL.)doc");

  m.def(
      "load_cube_environment",
      [](const std::vector<std::string>& faces) {
        if (faces.size() != 6) value_error("faces must list 6 paths (+X, -X, +Y, -Y, +Z, -Z), got " + std::to_string(faces.size()));
        std::array<std::string, 6> paths;
        std::copy(faces.begin(), faces.end(), paths.begin());
        return load_or_os_error([&] { return sd::Environment::load_cube(paths); });
      },
      py::arg("faces"),
      R"doc(Loads a cube map from 6 square images of one size, in the order +X, -X, +Y, -Y, +Z, -Z.

Face orientation: the OpenGL cube-map table applied to Blender's world axes (Z up). For a
direction d with major axis ma: +X: sc=-z, tc=-y; -X: sc=+z, tc=-y; +Y: sc=+x, tc=+z;
-Y: sc=+x, tc=-z; +Z: sc=+x, tc=-y; -Z: sc=-x, tc=-y; column s = (sc/|ma| + 1)/2 from the left,
row t = (tc/|ma| + 1)/2 from the top. Errors as load_environment; faces of different or
non-square sizes raise ValueError.)doc");
}

}  // namespace sdpy
