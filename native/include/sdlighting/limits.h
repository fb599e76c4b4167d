// Every order, degree and size limit of the library, stated once. sdnative exports each one as a
// module attribute of the same name without the k and in capitals (kMaxShOrder: MAX_SH_ORDER),
// and every "out of range" message is built from these constants by check_range / check_order.
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>

namespace sd {

/// Highest SH order of the basis, the rotation (ShRotation) and the Gaunt coefficients.
constexpr int kMaxShOrder = 64;
/// Highest order of the one-dimensional tables (Legendre polynomials, Funk–Hecke factors): a guard
/// against absurd allocations, not a limit of the recurrences.
constexpr int kMaxLegendreOrder = 100000;
/// Highest degree k of a weighted spherical design (eq. 11).
constexpr int kMaxDesignDegree = 30;
/// Largest Phong exponent σ: the factor recurrence stays exact far beyond, but designs and
/// textures for narrower lobes are meaningless in float32 shading.
constexpr double kMaxPhongExponent = 1e4;
/// Highest order of Environment::sh (the full-resolution projection used for shading).
constexpr int kMaxProjectionOrder = 16;
/// Highest order of the band energies, the error measures and the band-limited textures: the "high
/// order" to which lobe-filtered errors are summed (sh_projection.h, band_energies).
constexpr int kMaxEnergyOrder = 64;
/// Largest width and height of a band-limited texture.
constexpr int kMaxTextureSide = 16384;
/// Highest order s' of the baked visibility Ṽ (and the column order of M, the design's s').
constexpr int kMaxVisibilityOrder = 8;
/// Highest order s of the baked transfer vector T and the row order of M (the design's s).
constexpr int kMaxTransferOrder = 16;
/// Most rays per vertex a bake accepts (a guard against absurd allocations).
constexpr int kMaxRaysPerVertex = 1 << 24;
/// Highest order of L and of V the shading evaluators accept (the product formulas grow as s⁴).
constexpr int kMaxShadingOrder = 16;
/// Most bytes one call may allocate for the arrays its arguments size (a bake's per-vertex results
/// and per-thread ray matrices, a weighted design's dense matrices, Gaunt tables, band-limited
/// textures, decoded images): 4 GiB, above every size the add-on offers (a bake of 65536 rays per
/// vertex with a degree-24 design on two threads needs 2.6 GB). check_allocation refuses more
/// before anything is allocated, instead of the kernel killing the process (and Blender with it).
constexpr double kMaxCallBytes = 4.0 * (1 << 30);

/// Throws std::invalid_argument "<what> must be in [lo, hi], got <value>" unless lo <= value <= hi.
inline void check_range(const std::string& what, int value, int lo, int hi) {
  if (value < lo || value > hi) {
    throw std::invalid_argument(what + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                                std::to_string(value));
  }
}

/// Throws std::invalid_argument "<what> would need <bytes> GB, more than the 4.29 GB one call may
/// allocate" unless bytes <= kMaxCallBytes. Sizes are counted in double, so absurd ones cannot
/// overflow the count.
inline void check_allocation(const std::string& what, double bytes) {
  if (!(bytes <= kMaxCallBytes)) {
    char text[96];
    std::snprintf(text, sizeof text, " would need %.3g GB, more than the %.3g GB one call may allocate", bytes / 1e9,
                  kMaxCallBytes / 1e9);
    throw std::invalid_argument(what + text);
  }
}

/// An order or degree in [0, max_value]: check_range(what, value, 0, max_value).
inline void check_order(const std::string& what, int value, int max_value) { check_range(what, value, 0, max_value); }

}  // namespace sd
