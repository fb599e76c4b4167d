"""The BRDF lobe of an object: Lambert, or Phong with exponent sigma (msd-notes, "The problem").

By default the lobe is read from the object's first material with a Principled BSDF:
- a rough dielectric (roughness >= 0.5 and metallic < 0.5) is Lambert;
- otherwise it is Phong with sigma = 1 / (2 alpha^2) - 1/2, alpha = roughness^2 (Blender's
  GGX alpha). That is the Beckmann-equivalent Blinn-Phong exponent 2/alpha^2 - 2 divided by 4, the
  usual factor between a half-vector lobe and a lobe around the mirrored view; clamped to
  [1, 1000] (roughness 0.5 -> 7.5, 0.3 -> 61, 0.2 -> 312).
An object without such a material is Lambert.
"""

from . import compat

MIN_EXPONENT = 1.0
MAX_EXPONENT = 1000.0


def exponent_from_roughness(roughness):
    """Phong sigma for a Principled roughness."""
    alpha = max(float(roughness), 1e-3) ** 2
    sigma = 1.0 / (2.0 * alpha * alpha) - 0.5
    return min(max(sigma, MIN_EXPONENT), MAX_EXPONENT)


def _principled(material):
    if not compat.uses_nodes(material):
        return None
    for node in material.node_tree.nodes:
        if node.type == 'BSDF_PRINCIPLED':
            return node
    return None


def _input_value(node, name, default):
    socket = node.inputs.get(name)
    if socket is None or not hasattr(socket, "default_value"):
        return default
    return float(socket.default_value)


def lobe_from_material(obj):
    """("lambert", 1.0) or ("phong", sigma) for the object's material, and a short explanation."""
    for slot in getattr(obj, "material_slots", ()):
        node = _principled(slot.material)
        if node is None:
            continue
        roughness = _input_value(node, "Roughness", 0.5)
        metallic = _input_value(node, "Metallic", 0.0)
        if roughness >= 0.5 and metallic < 0.5:
            return ("lambert", 1.0), "%s: rough dielectric -> Lambert" % slot.material.name
        sigma = exponent_from_roughness(roughness)
        return ("phong", sigma), "%s: roughness %.2f -> Phong sigma %.1f" % (
            slot.material.name, roughness, sigma)
    return ("lambert", 1.0), "no Principled BSDF -> Lambert"


def lobe_for(obj, settings):
    """The lobe to bake and shade `obj` with under the scene's settings: (name, exponent)."""
    if settings.material_source == 'LAMBERT':
        return "lambert", 1.0
    if settings.material_source == 'PHONG':
        return "phong", float(settings.phong_exponent)
    return lobe_from_material(obj)[0]
