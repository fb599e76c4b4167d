// Bindings of the windows against ringing (sdlighting/ringing.h): Environment.ringing_window and
// .displayed_error.
//
// Errors: bad arguments (orders out of range, unknown lobes or windows, bad factors) raise
// ValueError. Heavy work runs without the GIL.
#include "array_checks.h"
#include "bindings.h"
#include "environment_class.h"
#include "sdlighting/environment.h"
#include "sdlighting/ringing.h"
#include "sdlighting/zonal_lobe.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <string>
#include <vector>

namespace sdpy {
namespace {

py::dict choice_dict(const sd::RingingWindowChoice& c) {
  py::dict d;
  d["window"] = sd::ringing_window_name(c.window.window);
  d["sloan_lambda"] = c.window.sloan_lambda;
  py::array_t<double> factors(py::ssize_t(c.factors.size()));
  std::copy(c.factors.begin(), c.factors.end(), factors.mutable_data());
  d["factors"] = factors;
  d["error"] = c.error;
  d["unwindowed_error"] = c.unwindowed_error;
  d["l2_error"] = c.l2_error;
  d["unwindowed_l2_error"] = c.unwindowed_l2_error;
  d["min_over_max"] = c.min_over_max;
  d["unwindowed_min_over_max"] = c.unwindowed_min_over_max;
  return d;
}

}  // namespace

void bind_ringing(py::module_& m) {
  py::class_<sd::Environment> env = environment_class(m);
  env.def(
          "ringing_window",
          [](const sd::Environment& e, const std::string& lobe, double exponent, int s, const std::string& window) {
            check_order("s", s, sd::kMaxShadingOrder);
            const sd::ZonalLobe z = sd::ZonalLobe::from_name(lobe, exponent);
            const bool automatic = window == "automatic";
            const sd::RingingWindow w = automatic ? sd::RingingWindow::None : sd::ringing_window_from_name(window);
            sd::RingingWindowChoice c;
            {
              py::gil_scoped_release release;
              c = automatic ? sd::automatic_ringing_window(e, z, s) : sd::ringing_window(e, z, s, w);
            }
            return choice_dict(c);
          },
          py::arg("lobe"), py::arg("exponent"), py::arg("s"), py::arg("window") = "automatic",
          R"doc(The window against ringing for a lobe and order s (0 .. MAX_SHADING_ORDER), and what it does to
the displayed radiance: a dict with 'window' ('none', 'hanning', 'lanczos' or 'sloan'),
'sloan_lambda', 'factors' (sigma_0 .. sigma_s: multiply band l of L_lm by sigma_l, before or after
rotating), 'error' and 'unwindowed_error' (the displayed error with the window and with none),
'l2_error' and 'unwindowed_l2_error' (the plain relative RMS of the clamped B), 'min_over_max' and
'unwindowed_min_over_max' (min / max of B~ over axes and channels, not clamped: negative =
ringing below zero).

The displayed error: unshadowed B~(a) = sum_{l<=s} sigma_l w_l L_lm y_lm(a) (Funk-Hecke) against the
full B of order 64, per RGB channel over a 256 x 128 grid of lobe axes a, both clamped at 0 (as the
live shading shows them) and through Reinhard's tone curve x / (x + mean B): the relative RMS of
the difference. (In plain L2 the truncation is the best approximation of order s and every window
loses, clamped or not; the tone curve measures the dark side that ringing spoils.)
window: 'automatic' (default: the one of 'none', 'hanning', 'lanczos', 'sloan' with the smallest
error, 'none' unless another lowers none's by more than 1 % of it) or one of them; 'sloan' takes the lambda that
minimises the error (lambda = t / (s(s+1))^2 for t = 10^(k/4), k = -16 .. 12). Releases the GIL.)doc")
      .def(
          "displayed_error",
          [](const sd::Environment& e, const std::string& lobe, double exponent, int s, const DoubleArray& factors) {
            check_order("s", s, sd::kMaxShadingOrder);
            if (factors.ndim() != 1 || factors.shape(0) != s + 1) {
              value_error("factors must have shape (s+1,), got " + shape_string(factors));
            }
            check_finite("factors", factors.data(), static_cast<size_t>(s + 1));
            const sd::ZonalLobe z = sd::ZonalLobe::from_name(lobe, exponent);
            const std::vector<double> f(factors.data(), factors.data() + s + 1);
            sd::RingingWindowChoice c;
            {
              py::gil_scoped_release release;
              c = sd::displayed_error(e, z, s, f);
            }
            py::dict d = choice_dict(c);
            d.attr("pop")("window");
            d.attr("pop")("sloan_lambda");
            return d;
          },
          py::arg("lobe"), py::arg("exponent"), py::arg("s"), py::arg("factors"),
          R"doc(ringing_window's errors for given window factors sigma_0 .. sigma_s (shape (s+1,)): the same dict
without 'window' and 'sloan_lambda'.)doc");
}

}  // namespace sdpy
