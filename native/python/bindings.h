// One registration function per concept; sdnative_module.cpp calls them all.
#pragma once

#include <pybind11/pybind11.h>

namespace sdpy {

/// Spherical harmonics, rotation, lobes, Gaunt coefficients, designs.
void bind_core(pybind11::module_& m);

/// Environment maps: loading, SH projection, band-limited textures, error measures, sampling.
void bind_environment(pybind11::module_& m);

/// Per-vertex visibility and transfer baking with Embree.
void bind_visibility(pybind11::module_& m);

/// The shading formulas (unshadowed, AO, PRT (2), (8)-(9), (10), MSD (12), (13)) and the reference.
void bind_shading(pybind11::module_& m);

}  // namespace sdpy
