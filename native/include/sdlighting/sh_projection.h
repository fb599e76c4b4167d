// The SH side of an environment map (environment.h): its projection to real spherical harmonics
// (eq. (1)'s L_lm), the band energies of its high-order reference projection, and band-limited
// textures L̃ (eqs. (12), (13)), windowed against ringing (ringing.h).
//
// SH convention: spherical_harmonics.h (y_00 = 1, orthonormal for dμ). RGB coefficient arrays
// are coefficient-major, channel-minor: c[3 i + ch] is coefficient i = l² + l + m of channel ch,
// as ShRotation::apply(in, out, 3) and the shading evaluators (shading.h) expect.
#pragma once

#include "sdlighting/environment.h"
#include "sdlighting/limits.h"
#include "sdlighting/ringing.h"

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace sd {

/// What band_limited reports about L̃ (all in linear radiance).
struct BandLimitedReport {
  std::array<double, 3> min_value{};  // per channel; negative = ringing below zero
  std::array<double, 3> max_value{};  // per channel
  int64_t negative_texels = 0;        // output texels with at least one channel < 0
  double negative_fraction = 0.0;     // negative_texels / (width * height)
  double negative_solid_angle = 0.0;  // μ-measure (dx/4π) covered by those texels, in [0, 1]
};

/// L_lm = ∫ L y_lm dμ = Σ_texels L(texel) ∫_texel y_lm dμ for l <= order (0..kMaxProjectionOrder,
/// else std::invalid_argument): the exact coefficients of the piecewise-constant map, each texel
/// integral by a Gauss–Legendre rule sized to the texel (within 1e-5 of max |y_lm| × the mass; a
/// constant map of any size, down to 1 × 1, gives L_00 = the constant and every other
/// coefficient below that bound). Returns sh_count(order) × 3 doubles, out[3 i + c].
/// Multi-threaded on `threads` threads (0: every hardware thread); the result is bit-identical
/// for every thread count (per-row partial sums reduced in a fixed order). Equirect maps use the
/// row structure: the azimuthal integrals exactly (sinc factors) once per column, the θ rule
/// once per row (cost ∝ W H (order+1)); cube maps evaluate y_lm at each texel's rule points
/// (cost ∝ texels × points × (order+1)², 4 points per texel from face 128 on).
std::vector<double> sh(const Environment& environment, int order, int threads = 0);

/// Band-limited L̃(d) = Σ_{l<=order} σ_l L_lm y_lm(d) (the seed's partial sum of order s, windowed
/// by σ_l against ringing) — the L̃ that eqs. (12) and (13) look up, stored as a texture as comment 1
/// to Theorem 2.1 suggests — sampled at the centres of a width × height equirectangular texture in
/// the map's orientation, rows top-first: 3 floats per texel, rgb[3 (j width + i) + c] — ready
/// for a float texture (L̃ is not clamped: negative lobes are kept and reported).
/// order 0..kMaxEnergyOrder; coefficients from sh(order) for order <= kMaxProjectionOrder,
/// otherwise from the reference projection (see band_energies); then band_limited_texture.
/// If `report` is non-null it receives the minima/maxima and the negative texels of L̃.
/// Throws std::invalid_argument for an order out of range or a size < 1 (or above 16384).
std::vector<float> band_limited(const Environment& environment, int order, int width, int height,
                                const RingingWindowSpec& window = {}, BandLimitedReport* report = nullptr);

/// Per-band energies E_l = Σ_m L_lm² for l = 0..lmax (lmax in 0..kMaxEnergyOrder), channels
/// R, G, B and the luminance: out[4 l + c]. Rotation invariant. Computed once (lazily, cached)
/// from the reference projection of order kMaxEnergyOrder: of the map itself when it has at
/// most 4096 × 2048 texels (equirect) or a face of at most 128 (cube); of an area_averaged copy
/// reduced to that otherwise. Box-filtering over texels of angular width h attenuates band l by
/// about l(l+1)h²/12 in energy: < 1e-3 at l = 64 for the 4096-wide equirect copy, about 2 % at
/// l = 32 for the face-128 cube copy — negligible in the lobe-filtered errors, whose factors ŵ_l²
/// are below 1e-7 (Lambert) and 1e-17 (Phong σ = 32) from l = 32 on.
std::vector<double> band_energies(const Environment& environment, int lmax);

/// The texture of band_limited from given RGB coefficients (layout as sh(), e.g. already rotated
/// by rotated_sh): L̃(d) = Σ_{l<=order} σ_l c_lm y_lm(d) at the texel centres of a width × height
/// equirect image in environment.h's orientation, rows top-first, 3 floats per texel; `report` (if
/// non-null) as for band_limited. order in 0..kMaxEnergyOrder, sizes in [1, 16384], coefficients
/// finite and sh_count(order) × 3 of them, and every value within the float32 range of the texture
/// (huge coefficients overflow it); std::invalid_argument otherwise. Multi-threaded over rows; cost
/// ∝ width × height × (order+1).
std::vector<float> band_limited_texture(const std::vector<double>& coefficients, int order, int width, int height,
                                        const RingingWindowSpec& window = {},
                                        BandLimitedReport* report = nullptr);

/// Σ_{l<=order} Σ_m c_lm y_lm(dir) for the three channels of RGB coefficients (layout as sh()).
/// `dir` must be unit.
glm::dvec3 evaluate_sh_rgb(const std::vector<double>& coeffs, int order, const glm::dvec3& dir);

}  // namespace sd
