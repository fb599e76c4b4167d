"""The BRDF lobe of an object: read from its first material with a Principled BSDF (the rule is
utils/lobes.py), or forced by the panel's settings. An object without such a material is Lambert.
"""

from . import compat
from .utils import lobes


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
        lobe, why = lobes.lobe_from_principled(_input_value(node, "Roughness", 0.5),
                                               _input_value(node, "Metallic", 0.0))
        return lobe, "%s: %s" % (slot.material.name, why)
    return ("lambert", 1.0), "no Principled BSDF -> Lambert"


def lobe_for(obj, settings):
    """The lobe to bake and shade `obj` with under the scene's settings: (name, exponent)."""
    if settings.material_source == 'LAMBERT':
        return "lambert", 1.0
    if settings.material_source == 'PHONG':
        return "phong", float(settings.phong_exponent)
    return lobe_from_material(obj)[0]
