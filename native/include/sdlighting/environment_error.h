// The error measures of an environment map (environment.h) that choose the order s of its
// truncated expansion L̃_s: the seed's ε(s), the lobe-filtered error of B, and the smallest s that
// reaches a target. All from the band energies E_l of the map's reference projection
// (band_energies, sh_projection.h).
#pragma once

#include "sdlighting/environment.h"
#include "sdlighting/zonal_lobe.h"

namespace sd {

/// The seed's low-frequency measure ε(s) = ‖L − L̃_s‖ / ‖L‖ in L²(dμ) (the condition stated before
/// Theorem 1.1, whose bound |B − B̄| <= ε ‖L‖ ‖ρ̂‖ uses eqs. (6)–(7)) for one channel (0..2 or
/// kLuminance), exact via Parseval: ‖L − L̃_s‖² = ‖L‖² − Σ_{l<=s} E_l, with ‖L‖² = Σ L² Δμ over
/// the texels of the map the energies were projected from. order in 0..kMaxEnergyOrder.
/// Returns 0 for a black channel.
double low_frequency_error(const Environment& environment, int order, int channel = kLuminance);

/// The error that really decides s (msd-notes, "Facts worth knowing"): the relative RMS over
/// lobe axes a ∈ S² of the truncation error B − B̄ of eq. (6) for V = 1, i.e. of the unshadowed
/// B(a) = Σ_lm ŵ_l L_lm y_lm(a) (Funk–Hecke) cut at l <= s, on luminance:
///     sqrt( Σ_{order<l<=64} ŵ_l² E_l / Σ_{l<=64} ŵ_l² E_l ),
/// since ∫ (B − B̃_s)² dμ(a) = Σ_{l>s} ŵ_l² E_l. order in 0..kMaxEnergyOrder. 0 for a black map.
/// The neglected tail Σ_{l>64} ŵ_l² E_l has factors ŵ_l² < 1e-19 for Phong σ <= 100 (< 2e-13 for
/// σ = 150, < 3e-9 for Lambert); for much narrower lobes the error is underestimated (it is then
/// close to 1 anyway).
double lobe_filtered_error(const Environment& environment, const ZonalLobe& lobe, int order);

/// The smallest s in [0, max_order] with lobe_filtered_error(environment, lobe, s) <= target_error,
/// or −1 if none reaches it. max_order in 0..kMaxEnergyOrder; target_error finite and >= 0.
int smallest_order(const Environment& environment, const ZonalLobe& lobe, double target_error, int max_order);

}  // namespace sd
