// Bindings of the weighted designs of an environment's channel (sdlighting/channel_design.h):
// Environment.channel_design.
//
// Errors: a bad channel or degree, or a black channel, raises ValueError; a design that cannot be
// certified raises RuntimeError. Heavy work runs without the GIL.
#include "array_checks.h"
#include "bindings.h"
#include "design_arrays.h"
#include "environment_class.h"
#include "sdlighting/channel_design.h"
#include "sdlighting/environment.h"
#include "sdlighting/spherical_design.h"

#include <pybind11/pybind11.h>

namespace sdpy {

void bind_channel_design(py::module_& m) {
  py::class_<sd::Environment> env = environment_class(m);
  env.def(
          "channel_design",
          [](const sd::Environment& e, const py::object& channel, int degree) {
            check_design_degree(degree);
            const int c = parse_channel(channel);
            sd::SphericalDesign design;
            {
              py::gil_scoped_release release;
              design = sd::channel_design(e, c, degree);
            }
            return design_tuple(design);
          },
          py::arg("channel"), py::arg("degree"),
          R"doc(A weighted spherical design of the given degree (0 .. MAX_DESIGN_DEGREE) for the measure
L_c dmu of one channel (0, 1, 2 or 'luminance'): the seed's comment 3 / Table 2. Built with
weighted_design on an area-averaged copy of about 2000 texels (equirect 64 x 32, cube faces 18),
nodes at texel centres and weights L_c * solid angle; certified against that copy's moments, which
match the full map's L_lm up to the box filter (about 1 % at l = 4).
Returns (nodes (N, 3), weights (N,)), weights positive, summing to mass[c]. ValueError for a black
channel; RuntimeError if no design certifies. Releases the GIL.)doc");
}

}  // namespace sdpy
