// What the bindings of environment maps share: the class sdnative.Environment, registered by
// bind_environment and given the methods of the other environment headers by their own bindings
// (bind_sh_projection, bind_environment_error, bind_ringing, bind_channel_design), and the channel
// argument. Defined in bind_environment.cpp.
#pragma once

#include "sdlighting/environment.h"

#include <pybind11/pybind11.h>

namespace sdpy {

namespace py = pybind11;

/// The already registered class sdnative.Environment of module m, to add methods to.
py::class_<sd::Environment> environment_class(py::module_& m);

/// A channel given as 0, 1, 2 (R, G, B), 3 or "luminance" (also "r", "g", "b", "y"); ValueError otherwise.
int parse_channel(const py::object& channel);

}  // namespace sdpy
