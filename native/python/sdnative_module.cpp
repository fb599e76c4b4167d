// The Python module `sdnative`: the sdlighting library for the Blender add-on and for tests. Built
// twice: for the add-on, and with SD_IMAGE_FILES (load_environment, load_cube_environment:
// OpenImageIO) for the tests and tools.
//
// Every array argument is accepted as anything numpy can convert to a C-contiguous float64 array;
// every array result is a fresh float64 (or int32 for index tables) numpy array. Shapes, finiteness
// and ranges are checked so that bad input raises ValueError with a message naming the argument;
// the library's own std::invalid_argument also surfaces as ValueError and its std::runtime_error
// ("no certified design") as RuntimeError. Long computations release the GIL.
#include "bindings.h"
#include "sdlighting/glossy_prefilter.h"
#include "sdlighting/limits.h"

#include <string>

namespace {

constexpr const char* kModuleDoc = R"doc(
Native core of sd-lighting: real spherical harmonics, SH rotation, zonal BRDF lobes, real Gaunt
coefficients, weighted spherical designs, environment maps, the Embree visibility bake and every
shading formula of the method of spherical designs (MSD) and of PRT, with the Monte Carlo
reference they are measured against.

Spherical-harmonic convention (the same in C++, Python and GLSL):
  Real SH y_lm orthonormal for the normalised measure dmu = dx / (4 pi) on the unit sphere, so
  y_00 = 1 (y_lm = sqrt(4 pi) times the usual unit-sphere-normalised Y_lm), and
      y_l0   = sqrt(2l+1) P_l(z)
      y_l,+m = Q_lm(z) Re (x + i y)^m,   y_l,-m = Q_lm(z) Im (x + i y)^m   (m > 0)
  with Q_lm(z) = sqrt(2 (2l+1) (l-m)!/(l+m)!) P_l^m(z) / sin^m(theta), P_l^m WITHOUT the
  Condon-Shortley phase. Hence y_1,-1 = sqrt(3) y, y_10 = sqrt(3) z, y_11 = sqrt(3) x,
  y_2,-2 = sqrt(15) x y. Flat index of (l, m) is l^2 + l + m; an expansion of order lmax holds
  (lmax+1)^2 coefficients. Coefficients of f are f_lm = integral of f y_lm dmu.

Lobes (zonal around an axis a, normalised to integral w(a.x) dmu(x) = 1):
  "lambert": w(t) = 4 max(0, t);  "phong": w(t) = (2 sigma + 2) max(0, t)^sigma, sigma in [0, MAX_PHONG_EXPONENT].

A weighted spherical design of degree k for a weight w >= 0 is a set of nodes x_v on the sphere
with weights lambda_v > 0 such that integral f w dmu = sum_v lambda_v f(x_v) for every polynomial
f of degree <= k. Designs are certified: their moment residual is at most DESIGN_TOLERANCE times
the weight's mass; a builder that cannot certify one raises RuntimeError.

Functions:
  sh_basis(lmax, dirs)                  y_lm at directions
  sh_recurrence_constants(order)        the constants of sh_basis's recurrences (for GLSL)
  rotate_sh(coeffs, rotation)           coefficients of x -> f(R^T x)
  zonal_coefficients(lobe, exponent, lmax)  Funk-Hecke factors of a lobe
  legendre(lmax, t)                     P_0(t) .. P_lmax(t)
  gaunt_coefficients(a, b, c)           real Gaunt coefficients (sparse)
  zonal_design(...), zonal_design_tabulated(...), weighted_design(...)   -> (nodes, weights)
  zonal_design_report(...), weighted_design_report(...)   -> dict with residual and method
  Environment.prefiltered_ggx(...)     the map prefiltered by the GGX lobe per roughness (split sum); prefilter_atlas_shape
  Environment.light_sources(order)     its compact bright sources split off, and the remainder
  environment_brdf(n_dot_v, roughness)  the GGX lobe's directional albedo (A, B); environment_brdf_table
  environment_from_pixels(rgb), load_environment(path), load_cube_environment(faces)
                                        -> Environment (the last two not in the add-on's module): .sh(lmax), .band_limited(...), errors, designs
  rotated_environment_sh(coeffs, g)     coefficients of x -> L(g x)
  bake_transfer(vertices, normals, triangles, rays, ...)   per-vertex AO, Ṽ, M, T, V designs
  bake_visibility(vertices, normals, triangles, order, rays, ...)   Ṽ only
  shade(method, light, normals, ...)    eqs. (2), (8)-(9), (10), (12), (13), unshadowed, AO
  reference(environment, vertices, normals, triangles, ...)   eq. (1) by Monte Carlo

Limits (module attributes, from one C++ header): MAX_SH_ORDER, MAX_LEGENDRE_ORDER,
MAX_DESIGN_DEGREE, MAX_PHONG_EXPONENT, MAX_PROJECTION_ORDER, MAX_ENERGY_ORDER, MAX_TEXTURE_SIDE,
MAX_VISIBILITY_ORDER, MAX_TRANSFER_ORDER, MAX_RAYS_PER_VERTEX, MAX_SHADING_ORDER, MAX_CALL_BYTES (the
bytes one call may allocate for arrays its arguments size: a call that would need more raises
ValueError before allocating).

Arrays are accepted in any form numpy converts to float64 (C-contiguous copies are made when
needed) and returned as float64 numpy arrays. Bad shapes, NaN or infinity, negative weights and
out-of-range orders or degrees raise ValueError.
)doc";

// pybind11 before 2.12 reads NumPy 2's dtype descriptors with the NumPy 1 layout: every array the
// module returns gets strides of 0 and silently repeats its first element (seen with Debian's
// pybind11 2.10 under NumPy 2.4). Refuse to load there rather than return wrong results.
namespace py = pybind11;

void check_numpy_abi() {
#if PYBIND11_VERSION_HEX < 0x020C0000
  const std::string version = py::module_::import("numpy").attr("__version__").cast<std::string>();
  if (std::stoi(version) >= 2) {  // the major version: stoi stops at the first '.'
    throw py::import_error("sdnative was built with pybind11 " PYBIND11_TOSTRING(PYBIND11_VERSION_MAJOR) "." PYBIND11_TOSTRING(
        PYBIND11_VERSION_MINOR) ", which does not support NumPy " + version +
                           " (its arrays would come back wrong): use NumPy 1.x, or rebuild sdnative with pybind11 >= 2.12");
  }
#endif
}

}  // namespace

PYBIND11_MODULE(sdnative, m) {
  check_numpy_abi();
  m.doc() = kModuleDoc;
  // sdlighting/limits.h, each limit once.
  m.attr("MAX_SH_ORDER") = sd::kMaxShOrder;
  m.attr("MAX_LEGENDRE_ORDER") = sd::kMaxLegendreOrder;
  m.attr("MAX_DESIGN_DEGREE") = sd::kMaxDesignDegree;
  m.attr("MAX_PHONG_EXPONENT") = sd::kMaxPhongExponent;
  m.attr("MAX_PROJECTION_ORDER") = sd::kMaxProjectionOrder;
  m.attr("MAX_ENERGY_ORDER") = sd::kMaxEnergyOrder;
  m.attr("MAX_TEXTURE_SIDE") = sd::kMaxTextureSide;
  m.attr("MAX_VISIBILITY_ORDER") = sd::kMaxVisibilityOrder;
  m.attr("MAX_TRANSFER_ORDER") = sd::kMaxTransferOrder;
  m.attr("MAX_RAYS_PER_VERTEX") = sd::kMaxRaysPerVertex;
  m.attr("MAX_SHADING_ORDER") = sd::kMaxShadingOrder;
  m.attr("MAX_CALL_BYTES") = sd::kMaxCallBytes;
  m.attr("PREFILTER_WIDTH") = sd::PrefilterLayout().width0;
  m.attr("PREFILTER_LEVELS") = sd::PrefilterLayout().levels;
  sdpy::bind_sh(m);
  sdpy::bind_designs(m);
  sdpy::bind_environment(m);  // the class first: the next four add its methods
#ifdef SD_IMAGE_FILES
  sdpy::bind_image_files(m);
#endif
  sdpy::bind_sh_projection(m);
  sdpy::bind_environment_error(m);
  sdpy::bind_ringing(m);
  sdpy::bind_channel_design(m);
  sdpy::bind_glossy_prefilter(m);
  sdpy::bind_light_sources(m);
  sdpy::bind_environment_sampler(m);
  sdpy::bind_visibility(m);
  sdpy::bind_shading(m);
  sdpy::bind_reference(m);
  sdpy::bind_ray_bvh(m);
}
