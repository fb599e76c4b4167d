"""The BRDF lobes of a material: Lambert, Phong with exponent sigma, or both (msd-notes, "The
problem"), and how a Principled BSDF's energy splits between them.

- A rough dielectric (roughness >= 0.5, metallic 0) is Lambert alone, with its base colour: the
  Principled BSDF takes its specular layer's energy from the diffuse layer under it, so the sum of
  a broad, 4 % lobe and the rest of the diffuse is close to the diffuse alone.
- A metal (metallic 1) is Phong alone, with its base colour.
- Anything else - a smooth dielectric, a partly metallic surface - is both: Lambert with
  (1 - metallic)(1 - F0) times the base colour, and Phong with metallic times the base colour
  plus (1 - metallic) F0 (white). F0 is the dielectric's reflectance at normal incidence, without
  Fresnel's rise towards grazing angles.
- The Phong exponent is sigma = 1 / (2 alpha^2) - 1/2, alpha = roughness^2 (Blender's GGX alpha):
  the Beckmann-equivalent Blinn-Phong exponent 2/alpha^2 - 2 divided by 4, the usual factor
  between a half-vector lobe and a lobe around the mirrored view; clamped to [1, 1000]
  (roughness 0.5 -> 7.5, 0.3 -> 61, 0.2 -> 312).
"""

from dataclasses import dataclass

MIN_EXPONENT = 1.0
MAX_EXPONENT = 1000.0
LAMBERT_MIN_ROUGHNESS = 0.5
DIFFUSE_ONLY = (1.0, 0.0, 0.0)


@dataclass(frozen=True)
class Lobes:
    """The lobes an object is baked and shaded with: `lobe` ("lambert" or "phong") with its
    exponent, and for "phong" whether a Lambert lobe is shaded besides it (`diffuse`)."""
    lobe: str = "lambert"
    exponent: float = 1.0
    diffuse: bool = False

    @classmethod
    def of_bake(cls, bake):
        """The Lobes a bake's record (sd_bake) names; records made before the two-lobe shading
        have no "diffuse_lobe"."""
        return cls(str(bake["lobe"]), float(bake["exponent"]), bool(bake.get("diffuse_lobe", False)))

    def shaded(self):
        """(lobe, exponent) of lobe 0 and, with a Lambert lobe besides it, of lobe 1 (the
        shader's order)."""
        return [(self.lobe, self.exponent)] + ([("lambert", 1.0)] if self.diffuse else [])

    @property
    def label(self):
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


def principled_weights(roughness, metallic, f0):
    """A Principled BSDF's split (see the module's doc): (diffuse, metal, dielectric) such that
    the Lambert lobe's colour is diffuse x base colour and the Phong lobe's is metal x base colour
    + dielectric (grey)."""
    metallic = min(max(float(metallic), 0.0), 1.0)
    if roughness >= LAMBERT_MIN_ROUGHNESS and metallic == 0.0:
        return DIFFUSE_ONLY
    return ((1.0 - metallic) * (1.0 - f0), metallic, (1.0 - metallic) * f0)


def lobes_from_principled(roughness, metallic, f0):
    """The Lobes of a Principled BSDF's inputs, and why (a line for the panel)."""
    diffuse, metal, dielectric = principled_weights(roughness, metallic, f0)
    if metal == 0.0 and dielectric == 0.0:
        return Lobes(), "rough dielectric -> Lambert"
    sigma = exponent_from_roughness(roughness)
    both = diffuse > 0.0
    return Lobes("phong", sigma, both), "%sroughness %.2f -> %sPhong sigma %.1f" % (
        "metallic %.2f, " % metal if metal > 0.0 else "", roughness, "Lambert + " if both else "", sigma)


def label(lobe, exponent):
    """The lobe as the panel names it: "Lambert" or "Phong sigma 61"."""
    return "Lambert" if lobe == "lambert" else "Phong sigma %.3g" % exponent
