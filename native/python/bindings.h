// One registration function per concept, in the order of the pipeline; sdnative_module.cpp calls
// them all.
#pragma once

#include <pybind11/pybind11.h>

namespace sdpy {

/// Spherical harmonics: basis, recurrence constants, rotation, lobes' factors, Legendre, Gaunt.
void bind_sh(pybind11::module_& m);

/// Weighted spherical designs of lobes, tabulated zonal weights and discrete measures.
void bind_designs(pybind11::module_& m);

/// Environment maps: the class Environment (size, texels, masses, area-averaged copies), from pixels.
void bind_environment(pybind11::module_& m);

/// load_environment and load_cube_environment: image files (the test module only; after bind_environment).
void bind_image_files(pybind11::module_& m);

/// Environment.sh, .band_limited, .band_energies and band_limited_texture (after bind_environment).
void bind_sh_projection(pybind11::module_& m);

/// Environment.low_frequency_error, .lobe_filtered_error, .smallest_order (after bind_environment).
void bind_environment_error(pybind11::module_& m);

/// Environment.ringing_window and .displayed_error (after bind_environment).
void bind_ringing(pybind11::module_& m);

/// Environment.channel_design (after bind_environment).
void bind_channel_design(pybind11::module_& m);

/// Environment.prefiltered_ggx and environment_brdf: the split sum of glossy light (after bind_environment).
void bind_glossy_prefilter(pybind11::module_& m);

/// Environment.light_sources: the bright sources split off a map (after bind_environment).
void bind_light_sources(pybind11::module_& m);

/// Importance sampling of environment maps.
void bind_environment_sampler(pybind11::module_& m);

/// Per-vertex visibility and transfer baking with Embree.
void bind_visibility(pybind11::module_& m);

/// The shading formulas (unshadowed, AO, PRT (2), (8)-(9), (10), MSD (12), (13)).
void bind_shading(pybind11::module_& m);

/// The Monte Carlo reference of eq. (1).
void bind_reference(pybind11::module_& m);

/// The flat BVH of the live shading's per-pixel rays, and its walk.
void bind_ray_bvh(pybind11::module_& m);

}  // namespace sdpy
