// Bindings of the error measures that choose the order s (sdlighting/environment_error.h):
// Environment.low_frequency_error, .lobe_filtered_error and .smallest_order.
//
// Errors: bad arguments (orders out of range, unknown lobes or channels, a bad target) raise
// ValueError. Heavy work runs without the GIL.
#include "array_checks.h"
#include "bindings.h"
#include "environment_class.h"
#include "sdlighting/environment.h"
#include "sdlighting/environment_error.h"
#include "sdlighting/zonal_lobe.h"

#include <pybind11/pybind11.h>

#include <cmath>
#include <string>

namespace sdpy {

void bind_environment_error(py::module_& m) {
  py::class_<sd::Environment> env = environment_class(m);
  env.def(
          "low_frequency_error",
          [](const sd::Environment& e, int s, const py::object& channel) {
            check_order("s", s, sd::kMaxEnergyOrder);
            const int c = parse_channel(channel);
            py::gil_scoped_release release;
            return sd::low_frequency_error(e, s, c);
          },
          py::arg("s"), py::arg("channel") = "luminance",
          R"doc(The seed's epsilon(s) = ||L - L~_s|| / ||L|| in L2(dmu), exact via Parseval:
||L||^2 = sum L^2 * solid angle over the texels, ||L~_s||^2 = sum_{l<=s} E_l.
channel: 0, 1, 2 or 'luminance'. s: 0 .. MAX_ENERGY_ORDER. Returns 0 for a black channel.)doc")
      .def(
          "lobe_filtered_error",
          [](const sd::Environment& e, const std::string& lobe, double exponent, int s) {
            check_order("s", s, sd::kMaxEnergyOrder);
            const sd::ZonalLobe z = sd::ZonalLobe::from_name(lobe, exponent);
            py::gil_scoped_release release;
            return sd::lobe_filtered_error(e, z, s);
          },
          py::arg("lobe"), py::arg("exponent"), py::arg("s"),
          R"doc(The error that decides s: relative RMS over lobe axes a of the truncation error of the
unshadowed B(a) = sum_lm w_l L_lm y_lm(a), on luminance:
sqrt(sum_{s<l<=64} w_l^2 E_l / sum_{l<=64} w_l^2 E_l).
lobe: 'lambert' (exponent ignored) or 'phong' (exponent sigma in [0, MAX_PHONG_EXPONENT]); s: 0 .. MAX_ENERGY_ORDER.)doc")
      .def(
          "smallest_order",
          [](const sd::Environment& e, const std::string& lobe, double exponent, double target_error,
             int max_order) -> py::object {
            check_order("max_order", max_order, sd::kMaxEnergyOrder);
            if (!std::isfinite(target_error) || target_error < 0.0) {
              value_error("target_error must be finite and >= 0");
            }
            const sd::ZonalLobe z = sd::ZonalLobe::from_name(lobe, exponent);
            int s;
            {
              py::gil_scoped_release release;
              s = sd::smallest_order(e, z, target_error, max_order);
            }
            if (s < 0) return py::none();
            return py::int_(s);
          },
          py::arg("lobe"), py::arg("exponent"), py::arg("target_error"), py::arg("max_order") = 16,
          R"doc(The smallest s <= max_order whose lobe_filtered_error is <= target_error, or None if
no such s exists up to max_order (<= MAX_ENERGY_ORDER).)doc");
}

}  // namespace sdpy
