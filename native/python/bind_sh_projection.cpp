// Bindings of the SH side of environment maps (sdlighting/sh_projection.h): Environment.sh,
// .band_limited, .band_energies and the module function band_limited_texture.
//
// Errors: bad arguments (orders or sizes out of range, bad shapes, NaN or infinity, unknown
// windows) raise ValueError. Heavy work runs without the GIL.
#include "array_checks.h"
#include "bindings.h"
#include "environment_class.h"
#include "sdlighting/environment.h"
#include "sdlighting/ringing.h"
#include "sdlighting/sh_projection.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace sdpy {
namespace {

// (K, 3) float64 from coefficient-major RGB.
py::array_t<double> rgb_coefficients(const std::vector<double>& c) {
  const auto k = static_cast<py::ssize_t>(c.size() / 3);
  py::array_t<double> out({k, py::ssize_t(3)});
  std::copy(c.begin(), c.end(), out.mutable_data());
  return out;
}

py::dict report_dict(const sd::BandLimitedReport& r) {
  py::dict d;
  d["min"] = py::make_tuple(r.min_value[0], r.min_value[1], r.min_value[2]);
  d["max"] = py::make_tuple(r.max_value[0], r.max_value[1], r.max_value[2]);
  d["negative_texels"] = r.negative_texels;
  d["negative_fraction"] = r.negative_fraction;
  d["negative_solid_angle"] = r.negative_solid_angle;
  return d;
}

// A window by name and Sloan's lambda (finite, >= 0; only the 'sloan' window reads it).
sd::RingingWindowSpec window_spec(const std::string& window, double sloan_lambda) {
  if (!std::isfinite(sloan_lambda) || sloan_lambda < 0.0) value_error("sloan_lambda must be finite and >= 0");
  return sd::RingingWindowSpec(sd::ringing_window_from_name(window), sloan_lambda);
}

// A band-limited texture as float32 (height, width, 3), with report_dict(*report) if non-null.
py::object texture(const std::vector<float>& rgb, int width, int height, const sd::BandLimitedReport* report) {
  py::array_t<float> image({py::ssize_t(height), py::ssize_t(width), py::ssize_t(3)});
  std::copy(rgb.begin(), rgb.end(), image.mutable_data());
  if (report == nullptr) return std::move(image);
  return py::make_tuple(std::move(image), report_dict(*report));
}

py::object py_band_limited(const sd::Environment& env, int lmax, int width, int height, const std::string& window,
                           bool report, double sloan_lambda) {
  check_order("lmax", lmax, sd::kMaxEnergyOrder);
  check_range("width", width, 1, sd::kMaxTextureSide);
  check_range("height", height, 1, sd::kMaxTextureSide);
  const sd::RingingWindowSpec w = window_spec(window, sloan_lambda);
  sd::BandLimitedReport r;
  std::vector<float> rgb;
  {
    py::gil_scoped_release release;
    rgb = sd::band_limited(env, lmax, width, height, w, &r);
  }
  return texture(rgb, width, height, report ? &r : nullptr);
}

py::object py_band_limited_texture(const DoubleArray& coeffs, int width, int height, const std::string& window,
                                   bool report, double sloan_lambda) {
  if (coeffs.ndim() != 2 || coeffs.shape(1) != 3) {
    value_error("coeffs must have shape (K, 3), got " + shape_string(coeffs));
  }
  const py::ssize_t k = coeffs.shape(0);
  const int order = sh_order_from_count("coeffs", k, sd::kMaxEnergyOrder);
  check_range("width", width, 1, sd::kMaxTextureSide);
  check_range("height", height, 1, sd::kMaxTextureSide);
  check_finite("coeffs", coeffs.data(), static_cast<size_t>(3 * k));
  const sd::RingingWindowSpec w = window_spec(window, sloan_lambda);
  std::vector<double> c(coeffs.data(), coeffs.data() + 3 * k);
  sd::BandLimitedReport r;
  std::vector<float> rgb;
  {
    py::gil_scoped_release release;
    rgb = sd::band_limited_texture(c, order, width, height, w, &r);
  }
  return texture(rgb, width, height, report ? &r : nullptr);
}

}  // namespace

void bind_sh_projection(py::module_& m) {
  py::class_<sd::Environment> env = environment_class(m);
  env.def(
          "sh",
          [](const sd::Environment& e, int lmax, int threads) {
            check_order("lmax", lmax, sd::kMaxProjectionOrder);
            check_range("threads", threads, 0, 1024);
            std::vector<double> c;
            {
              py::gil_scoped_release release;
              c = sd::sh(e, lmax, threads);
            }
            return rgb_coefficients(c);
          },
          py::arg("lmax"), py::arg("threads") = 0,
          R"doc(SH coefficients L_lm = integral L y_lm dmu of the piecewise-constant map: the sum over texels
of L times the integral of y_lm over the texel's area (a Gauss-Legendre rule per texel, within 1e-5
of max |y_lm| times the mass), for l <= lmax (0 .. MAX_PROJECTION_ORDER). A constant map of any
size, down to 1 x 1, gives the constant in L_00 and nothing else.

threads: worker threads, 0 = all cores; the result does not depend on it (bit-identical).
Returns shape ((lmax+1)**2, 3). Releases the GIL.)doc")
      .def("band_limited", &py_band_limited, py::arg("lmax"), py::arg("width"), py::arg("height"),
           py::arg("window") = "none", py::arg("report") = false, py::arg("sloan_lambda") = 0.0,
           R"doc(The band-limited map L~(d) = sum_{l<=lmax} sigma_l L_lm y_lm(d) sampled at the texel centres of a
width x height equirectangular image (same orientation, rows top-first), as float32 of shape
(height, width, 3) — a float texture. Negative lobes are kept (not clamped).

lmax: 0 .. MAX_ENERGY_ORDER; coefficients from sh(lmax) up to MAX_PROJECTION_ORDER, above that from the cached
      high-order projection (see band_energies).
window: 'none' (sigma_l = 1), 'hanning' ((1 + cos(pi l/(lmax+1)))/2), 'lanczos'
        (sinc(l/(lmax+1))) or 'sloan' (1/(1 + sloan_lambda l^2 (l+1)^2)): windows against ringing
        (ringing_window chooses one).
report: if True, returns (image, report) where report is a dict with 'min' and 'max' (per-channel
        tuples of L~; a negative min is ringing), 'negative_texels' (texels with a channel < 0),
        'negative_fraction' (their share of the texels) and 'negative_solid_angle' (their share
        of the sphere). Releases the GIL.)doc")
      .def(
          "band_energies",
          [](const sd::Environment& e, int lmax) {
            check_order("lmax", lmax, sd::kMaxEnergyOrder);
            std::vector<double> energies;
            {
              py::gil_scoped_release release;
              energies = sd::band_energies(e, lmax);
            }
            py::array_t<double> out({py::ssize_t(lmax + 1), py::ssize_t(4)});
            std::copy(energies.begin(), energies.end(), out.mutable_data());
            return out;
          },
          py::arg("lmax"),
          R"doc(Band energies E_l = sum_m L_lm**2 for l = 0 .. lmax (lmax <= MAX_ENERGY_ORDER),
shape (lmax+1, 4): columns R, G, B, luminance. Rotation invariant. Computed once per map from an
order-64 projection (of the map itself up to 4096 x 2048 texels or cube faces of 128; of an
area-averaged copy above that: the box filter attenuates band l by about l(l+1)h^2/12 in
energy, h the texel's angular size). Releases the GIL.)doc");

  m.def("band_limited_texture", &py_band_limited_texture, py::arg("coeffs"), py::arg("width"), py::arg("height"),
        py::arg("window") = "none", py::arg("report") = false, py::arg("sloan_lambda") = 0.0,
        R"doc(The band-limited texture of given RGB coefficients (e.g. rotated_environment_sh of
Environment.sh): sum_{l<=lmax} sigma_l c_lm y_lm(d) at the texel centres of a width x height
equirectangular image (Blender's orientation, rows top-first), float32 of shape (height, width, 3).

coeffs: shape ((lmax+1)**2, 3), lmax <= MAX_ENERGY_ORDER. window, sloan_lambda and report as for
Environment.band_limited. Releases the GIL.)doc");
}

}  // namespace sdpy
