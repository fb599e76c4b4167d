"""The BRDF lobe of a Principled BSDF: Lambert, or Phong with exponent sigma (msd-notes, "The
problem").

- A rough dielectric (roughness >= 0.5 and metallic < 0.5) is Lambert.
- Otherwise it is Phong with sigma = 1 / (2 alpha^2) - 1/2, alpha = roughness^2 (Blender's GGX
  alpha). That is the Beckmann-equivalent Blinn-Phong exponent 2/alpha^2 - 2 divided by 4, the
  usual factor between a half-vector lobe and a lobe around the mirrored view; clamped to
  [1, 1000] (roughness 0.5 -> 7.5, 0.3 -> 61, 0.2 -> 312).
"""

MIN_EXPONENT = 1.0
MAX_EXPONENT = 1000.0
LAMBERT_MIN_ROUGHNESS = 0.5
LAMBERT_MAX_METALLIC = 0.5


def exponent_from_roughness(roughness):
    """Phong sigma for a Principled roughness."""
    alpha = max(float(roughness), 1e-3) ** 2
    sigma = 1.0 / (2.0 * alpha * alpha) - 0.5
    return min(max(sigma, MIN_EXPONENT), MAX_EXPONENT)


def lobe_from_principled(roughness, metallic):
    """(("lambert", 1.0) or ("phong", sigma)) for a Principled BSDF's inputs, and why."""
    if roughness >= LAMBERT_MIN_ROUGHNESS and metallic < LAMBERT_MAX_METALLIC:
        return ("lambert", 1.0), "rough dielectric -> Lambert"
    sigma = exponent_from_roughness(roughness)
    return ("phong", sigma), "roughness %.2f -> Phong sigma %.1f" % (roughness, sigma)


def label(lobe, exponent):
    """The lobe as the panel names it: "Lambert" or "Phong sigma 61"."""
    return "Lambert" if lobe == "lambert" else "Phong sigma %.3g" % exponent
