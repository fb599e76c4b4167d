// Glossy light without SH truncation (issue 28): the split sum of Karis ("Real Shading in Unreal
// Engine 4", SIGGRAPH 2013 course notes). The light a GGX lobe reflects towards v is approximated by
//     ∫ L(l) f(l, v) (n·l) dl  ≈  [∫ L(l) D(h) (n·l) dl / ∫ D(h) (n·l) dl] · ∫ f(l, v) (n·l) dl,
// the first factor a map of the environment prefiltered by the lobe with n = v = r, per roughness
// (prefilter_ggx), the second the lobe's directional albedo F0·A + B over n·v and roughness
// (environment_brdf, tabulated for the shader by environment_brdf_table). Karis reads the first
// factor at the mirrored view r, as n = v = r has it; that holds at normal incidence only, and the
// map is read where the lobe a view reflects lies instead (glossy_bend). Baked
// visibility is applied to the first factor separately (the shader's visibility ratio, msd-notes
// "Glossy light").
//
// GGX (Trowbridge–Reitz) with Blender's parameterisation: α = r², r the Principled BSDF's
// roughness; D(h) = α² / (π ((α² − 1) (n·h)² + 1)²); Smith's height-correlated masking-shadowing
// (Heitz 2014), as Cycles' microfacet BSDF.
#pragma once

#include "sdlighting/environment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace sd {

/// Where the roughness levels of a prefiltered environment lie in one RGB atlas (rows bottom-first,
/// as GPU textures hold them; the shader's sd_prefiltered_light reads the same layout). Level 0
/// holds the map itself (r = 0), level k >= 1 the GGX α_k = 2^(k − (levels − 1)): α doubles from
/// level to level up to α = 1 on the last, so that the shader's blend of two neighbouring levels
/// stays close to the lobe between them (linear steps in r blend a sharp level with one several
/// times as wide: msd-notes, "Glossy light"). Each level is an equirect image of Blender's
/// orientation (environment.h), rows bottom-first (row 0 at the south pole), half as high as it is
/// wide: level 0 is width0 wide, level k >= 1 width0 >> (k − 1), its texels keeping pace with the
/// lobe, down to width0 >> (levels − 3) for the last two. Level 0 fills rows [0, width0 / 2), level
/// 1 rows [width0 / 2, width0), and levels k >= 2 lie side by side in the rows above from column
/// width0 − (width0 >> (k − 2)), filling the atlas's width.
struct PrefilterLayout {
  int width0 = 1024;  ///< width of level 0, a power of two <= kMaxTextureSide (limits.h)
  int levels = 9;     ///< roughness levels, >= 3, with width0 >> (levels − 3) >= 4

  int level_width(int k) const { return k == 0 ? width0 : width0 >> std::min(k - 1, levels - 3); }
  int level_height(int k) const { return level_width(k) / 2; }
  /// Column and row of level k's first texel in the atlas.
  std::array<int, 2> level_origin(int k) const {
    if (k < 2) return {0, k * width0 / 2};
    return {width0 - (width0 >> (k - 2)), width0};
  }
  int atlas_width() const { return width0; }
  int atlas_height() const { return width0 + level_height(2); }
  /// Perceptual roughness r of level k: 0, then √α_k.
  double roughness(int k) const { return k == 0 ? 0.0 : std::exp2(0.5 * (k - (levels - 1))); }
  /// Throws std::invalid_argument naming the field for a layout outside the limits above.
  void check() const;
};

/// The environment prefiltered by the GGX lobe per roughness level, in the atlas `layout`
/// describes: level k at direction r holds ∫ L(l) D(h) (r·l)⁺ dl / ∫ D(h) (r·l)⁺ dl with
/// n = v = r and α = r_k² (level 0: the map itself at the level's size). Within a few degrees of r
/// by GGX-distributed directions (Hammersley), `samples` per texel on level 1 and twice as many on
/// each level after it (a quarter of the texels; up to 4096), each read from
/// the map averaged over about the sample's solid angle (filtered importance sampling: Křivánek and
/// Colbert 2008); beyond, the exact sum over the texels of the map averaged to 256 texels wide.
/// Both cores. float RGB, atlas_width × atlas_height × 3, zero outside the levels. Throws
/// std::invalid_argument for a bad layout or samples outside [1, 4096].
std::vector<float> prefilter_ggx(const Environment& environment, const PrefilterLayout& layout, int samples = 64);

/// The lobe's directional albedo E(n·v, r) = F0·A + B of the split sum for a Fresnel term
/// F = F0 + (1 − F0) s(v·h): A = ∫ (1 − s) f₁ (n·l) dl, B = ∫ s f₁ (n·l) dl with f₁ the GGX BRDF of
/// F = 1 (single scattering, Smith height-correlated), by `samples` GGX-distributed half vectors
/// (Hammersley). s is Schlick's (1 − v·h)⁵ for ior = 0; for ior > 1 it is the dielectric Fresnel
/// of that IOR remapped to run from 0 at normal incidence to 1 at grazing, (F(v·h) − F(1)) /
/// (1 − F(1)), the shape Cycles' Principled BSDF gives its dielectric layer (its generalized
/// Schlick with the real Fresnel of the layer's own IOR: this shape is that IOR's). A + B is the
/// same for both. n_dot_v in (0, 1],
/// roughness in [0, 1] (clamped to α >= 1e-4). Returns {A, B}. Throws std::invalid_argument
/// outside those ranges or for an ior that is neither 0 nor in (1, 1e6].
std::array<double, 2> environment_brdf(double n_dot_v, double roughness, int samples = 1024, double ior = 0.0);

/// environment_brdf tabulated for the shader: (A, B) at n·v = (i + ½) / size (column i) and
/// roughness j / (size − 1) (row j), `samples` half vectors each, for `ior` (0: Schlick); float,
/// row-major, size × size × 2. Both cores. Throws std::invalid_argument for size outside [2, 256],
/// samples outside [1, 2^20] or an ior environment_brdf refuses.
std::vector<float> environment_brdf_table(int size = 32, int samples = 1024, double ior = 0.0);

/// Where the prefiltered light is read for a view at n·v (issue 28: the split sum's dark rims). The
/// lobe a view at n·v reflects, F f₁ (n·l) (single scattering, Smith height-correlated), leans from
/// the mirrored view r towards the normal as n·v falls, while a level of the prefiltered map is
/// centred on its lookup direction. F is 1 for ior = 0 (a metal: its Fresnel hardly varies), else
/// the dielectric Fresnel of that IOR at v·h, which weighs the grazing light more (a plastic's
/// layer). Returns the bend: the lobe's mean direction is normalize(mix(n, r, bend)) (it lies in
/// the plane of n and v; 1 at n·v = 1). `samples` GGX half vectors (Hammersley). n_dot_v in (0, 1],
/// roughness in [0, 1]; throws std::invalid_argument outside them, for samples outside [1, 2^20]
/// or an ior that is neither 0 nor in (1, 1e6].
double glossy_bend(double n_dot_v, double roughness, int samples = 1024, double ior = 0.0);

/// glossy_bend tabulated as environment_brdf_table is: at n·v = (i + ½) / size (column i) and
/// roughness j / (size − 1) (row j), for `ior` as glossy_bend; float, row-major, size × size. Both
/// cores. Throws std::invalid_argument for size outside [2, 256], samples outside [1, 2^20] or an
/// ior glossy_bend refuses.
std::vector<float> glossy_bend_table(int size = 32, int samples = 1024, double ior = 0.0);

}  // namespace sd
