"""The BRDF lobes of a material: Lambert, Phong with exponent sigma, or both (msd-notes, "The
problem"), and the weights that give each lobe its colour for a Principled BSDF.

- A metal (metallic 1) is Phong alone; a smooth dielectric (roughness below 0.5) or a partly
  metallic surface is Lambert and Phong, both read from the same per-vertex data; a dielectric
  whose specular layer reflects nothing (F0 = 0, metallic 0) is Lambert alone.
- A rough dielectric (roughness >= 0.5, metallic 0; Blender's default material) is Lambert with its
  specular layer (Lobes.layer): the bake has the Lambert lobe alone, as cheap as a diffuse one,
  and the live shading lights the layer - a few percent of the light at normal incidence, which
  brightens every rim - by the environment prefiltered by its GGX lobe, shadowed by the traced
  reflection rays (with the rays off by the Lambert lobe's own visibility ratio); without the
  prefiltered light the layer is folded into Lambert (msd-notes, "Glossy light", measures both).
- The lobes' colours, per pixel, as the Principled BSDF splits its energy: Phong times the
  specular layer's directional albedo E = F0 A + B, with (A, B) the split-sum scale and bias of a
  GGX lobe at the view's n.v and the roughness (sdnative.environment_brdf_table, integrated
  natively), times the light that multiple scattering adds as Cycles computes it (Kulla and
  Conty's F_ms with E_avg from `average_albedo`: a metal keeps its energy, a rough plastic's layer
  gains hardly any) where the node's distribution is Multiscatter GGX (the default from 4.0; GGX,
  3.x's default, scatters once). As in Cycles, the
  dielectric layer's Fresnel is the real one (of IOR DIELECTRIC_SHAPE_IOR; the slot's F0) remapped
  to F0..1, which rises earlier than Schlick's; from 4.0 the metal is Schlick's of the base
  colour, mixed with the dielectric by metallic, before 4.0 one lobe of F0' = mix(F0, base colour,
  metallic) with the dielectric's shape. Lambert times (1 - metallic) x base colour, less the
  dielectric layer's E where the layer lies over the diffuse and takes its energy from it (the
  Principled BSDF of Blender 4.0 and later; before 4.0 the layer adds to the diffuse)
  (shaders/sd_shading_frag.glsl, sd_surface). Per slot that is `principled_weights`: (metallic,
  F0, roughness, layer), layer 0 for a slot without a specular layer (Diffuse BSDF, F0 = 0),
  LAYER_OVER or LAYER_ADDED, negated where the lobe scatters once (GGX, not Multiscatter GGX).
- The Phong exponent is sigma = 1 / (2 alpha^2) - 1/2, alpha = roughness^2 (Blender's GGX alpha):
  the Beckmann-equivalent Blinn-Phong exponent 2/alpha^2 - 2 divided by 4, the usual factor
  between a half-vector lobe and a lobe around the mirrored view; clamped to [1, 1000]
  (roughness 0.5 -> 7.5, 0.3 -> 61, 0.2 -> 312).
"""

from dataclasses import dataclass

import numpy as np

LUMINANCE = (0.2126, 0.7152, 0.0722)   # of linear Rec. 709 RGB (Blender's default scene-linear)
MIN_EXPONENT = 1.0
MAX_EXPONENT = 1000.0
LAYER_MIN_ROUGHNESS = 0.5     # a dielectric this rough is Lambert with its specular layer
DIELECTRIC_SHAPE_IOR = 1.5   # the dielectric layer's Fresnel shape (its F0 is the slot's own)
LAYER_OVER = 1.0     # the specular layer takes its energy from the diffuse under it (4.0+)
LAYER_ADDED = 2.0    # the specular layer adds to the diffuse (before 4.0)
DIFFUSE_ONLY = (0.0, 0.0, 1.0, 0.0)   # principled_weights of a slot without a specular layer


@dataclass(frozen=True)
class Lobes:
    """The lobes an object is baked and shaded with: `lobe` ("lambert" or "phong") with its
    exponent; for "phong", whether a Lambert lobe is shaded besides it (`diffuse`); whether the
    slots' Principled weights colour the lobes (`weighted`; else the albedo alone does) - for
    "lambert", that its slots' specular layers are lit by the prefiltered environment (`layer`);
    `diffuse_share`: the Lambert lobe's share of the light the surface reflects, which weighs the
    two lobes' errors when the automatic mode measures them (plan/accuracy.py)."""
    lobe: str = "lambert"
    exponent: float = 1.0
    diffuse: bool = False
    weighted: bool = False
    diffuse_share: float = 0.0

    @classmethod
    def of_bake(cls, bake):
        """The Lobes a bake's record (sd_bake) names; records made before the two-lobe shading
        have neither "diffuse_lobe" nor "lobe_weights"."""
        return cls(str(bake["lobe"]), float(bake["exponent"]), bool(bake.get("diffuse_lobe", False)),
                   bool(bake.get("lobe_weights", False)), float(bake.get("diffuse_share", 0.0)))

    @property
    def layer(self):
        """Whether this is a Lambert lobe whose slots' specular layers the live shading adds."""
        return self.lobe == "lambert" and self.weighted

    def prefiltered_glossy(self, option):
        """Whether lobe 0 is a glossy lobe the live shading lights by the prefiltered environment:
        the slots' Principled weights colour it and the scene's Prefiltered Glossy (`option`) is on."""
        return bool(option) and self.lobe != "lambert" and self.weighted

    def window_lobe(self, prefiltered_option):
        """(lobe, exponent) the ringing window of L is chosen for: the lobe whose SH the live
        shading shows. With the prefiltered glossy light (prefiltered_glossy) lobe 0's SH only
        gives its visibility ratio and the SH shows the Lambert lobe: a window that suits a sharp
        Phong lobe's truncation lit a red plastic's ground 25 % too brightly under sunrise.exr."""
        return ("lambert", 1.0) if self.prefiltered_glossy(prefiltered_option) else (self.lobe, self.exponent)

    def shaded(self):
        """(lobe, exponent) of lobe 0 and, with a Lambert lobe besides it, of lobe 1 (the
        shader's order)."""
        return [(self.lobe, self.exponent)] + ([("lambert", 1.0)] if self.diffuse else [])

    @property
    def label(self):
        if self.layer:
            return "Lambert + specular layer"
        return ("Lambert + " if self.diffuse else "") + label(self.lobe, self.exponent)


def exponent_from_roughness(roughness):
    """Phong sigma for a Principled roughness."""
    alpha = max(float(roughness), 1e-3) ** 2
    sigma = 1.0 / (2.0 * alpha * alpha) - 0.5
    return min(max(sigma, MIN_EXPONENT), MAX_EXPONENT)


def dielectric_reflectance(ior=1.5, ior_level=None, specular=None):
    """F0 of a Principled BSDF's dielectric layer: ((ior - 1) / (ior + 1))^2 times 2 x Specular
    IOR Level (Blender 4.0 and later), or 0.08 x Specular (before 4.0: `specular` given)."""
    if specular is not None:
        return min(max(0.08 * float(specular), 0.0), 1.0)
    f0 = ((float(ior) - 1.0) / (float(ior) + 1.0)) ** 2
    return min(max(f0 * 2.0 * (0.5 if ior_level is None else float(ior_level)), 0.0), 1.0)


def principled_weights(roughness, metallic, f0, layer_over=True, multiscatter=True):
    """A Principled BSDF's weights for the shader (see the module's doc): (metallic, F0,
    roughness, layer); layer_over: the BSDF's specular layer takes its energy from the diffuse
    (Blender 4.0 and later); multiscatter: its distribution is Multiscatter GGX (else GGX)."""
    metallic = min(max(float(metallic), 0.0), 1.0)
    roughness = min(max(float(roughness), 0.0), 1.0)
    if metallic == 0.0 and float(f0) <= 0.0:
        return DIFFUSE_ONLY
    layer = LAYER_OVER if layer_over else LAYER_ADDED
    return (metallic, float(f0), roughness, layer if multiscatter else -layer)


def rough_layer(weights):
    """Whether principled_weights are a rough dielectric's: its specular layer is lit by the
    prefiltered environment only, and folded into Lambert without it."""
    metal, _, roughness, layer = weights
    return layer != 0.0 and metal == 0.0 and roughness >= LAYER_MIN_ROUGHNESS


def reflected(colour, weights):
    """(specular, diffuse): the luminance a slot of this linear RGB colour and principled_weights
    reflects in each lobe at normal incidence (F0 for the specular layer)."""
    metal, f0, _, layer = weights
    luminance = sum(w * c for w, c in zip(LUMINANCE, colour))
    if layer == 0.0:
        return 0.0, luminance
    over = f0 if abs(layer) == LAYER_OVER else 0.0
    return f0 + metal * (luminance - f0), (1.0 - metal) * (1.0 - over) * luminance


def lobes_from_principled(roughness, metallic, f0):
    """The Lobes of a Principled BSDF's inputs, and why (a line for the panel)."""
    weights = principled_weights(roughness, metallic, f0)
    metal, _, _, layer = weights
    if layer == 0.0:
        return Lobes(), "no specular layer (F0 = 0) -> Lambert"
    if rough_layer(weights):
        return Lobes("lambert", 1.0, False, True), "rough dielectric -> Lambert + specular layer"
    sigma = exponent_from_roughness(roughness)
    both = metal < 1.0
    return Lobes("phong", sigma, both, True), "%sroughness %.2f -> %sPhong sigma %.1f" % (
        "metallic %.2f, " % metal if metal > 0.0 else "", roughness, "Lambert + " if both else "", sigma)


def average_albedo(table):
    """E_avg per roughness row of sdnative.environment_brdf_table's (A, B) (rows: roughness, columns:
    n.v = (i + 1/2) / size): the cosine-weighted mean 2 integral_0^1 (A + B) mu dmu of the lobe's
    albedo with F0 = 1, by the midpoint rule over the columns. Cycles' multiple scattering scales
    the specular layer with it (shaders/sd_shading_frag.glsl, sd_specular_albedo)."""
    table = np.asarray(table, dtype=float)
    size = table.shape[1]
    mu = (np.arange(size) + 0.5) / size
    return 2.0 * (table[..., 0] + table[..., 1]) @ mu / size


def horizon_factors(order):
    """h_0 .. h_order: the Legendre coefficients of the half-space step H(t) = [t > 0] for the
    normalised measure, h_l = 1/2 integral_0^1 P_l(t) dt (h_0 = 1/2, h_1 = 1/4, h_l = 0 for even
    l > 0). By Funk-Hecke, a zonal lobe of factors w_l truncated at `order` has the share
    sum_l (2l+1) h_l w_l P_l(a.n) of itself above the plane of normal n (a: its axis), in a uniform
    world: the horizon factor of the prefiltered glossy light's visibility ratio
    (shaders/sd_shading_lib.glsl, sd_visibility_ratio)."""
    from numpy.polynomial import legendre
    factors = []
    for l in range(order + 1):
        integral = legendre.legint(np.eye(order + 1)[l], lbnd=0.0)
        factors.append(0.5 * legendre.legval(1.0, integral))
    return np.array(factors)


def label(lobe, exponent):
    """The lobe as the panel names it: "Lambert" or "Phong sigma 61"."""
    return "Lambert" if lobe == "lambert" else "Phong sigma %.3g" % exponent
