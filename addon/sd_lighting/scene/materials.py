"""What an object's materials give the shading: the BRDF lobes (the rule is scene/lobes.py) and
the albedo and lobe weights B is multiplied by.

A material's surface BSDF is the Principled or Diffuse BSDF feeding its active Material Output's
Surface, else the first such node in its tree. Its albedo is the BSDF's base colour: a constant,
or an Image Texture plugged straight into it (read through the UV map the node's Vector input
names, or the mesh's active render UV map). A Principled BSDF's metallic, roughness and specular
inputs split it between a Lambert and a Phong lobe (scene/lobes.py); an object's Phong exponent is
that of its first glossy slot. What Lambert and Phong with an albedo cannot express (GGX's shape,
colour computed by other nodes, a second image texture on one object, another slot's roughness)
is approximated, and `Albedo.note` says how; so do the layers it leaves out (transmission, coat,
sheen, subsurface, emission, specular tint, anisotropy, alpha). A material
without such a BSDF uses its viewport colour; a face without a material has Blender's default
surface, a 0.8 grey diffuse (as Cycles renders it).
"""

import dataclasses
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .. import compat
from . import lobes

WHITE = (1.0, 1.0, 1.0)
DEFAULT_SURFACE = (0.8, 0.8, 0.8)   # what Cycles and EEVEE shade a face without a material with


@dataclass(frozen=True)
class Albedo:
    """A material slot's albedo: a linear RGB colour, or an image read through a UV map."""
    colour: tuple = DEFAULT_SURFACE
    image: object = None            # bpy.types.Image, or None
    uv_map: Optional[str] = None    # the image's UV map ("": the active render one)
    note: str = ""                  # what is approximated, for the panel
    weights: tuple = lobes.DIFFUSE_ONLY   # scene/lobes.principled_weights
    bsdf_lobes: lobes.Lobes = lobes.Lobes()
    why: str = "Lambert"            # how the lobes follow from the BSDF, for the panel


def _bsdf_nodes(material):
    return [n for n in material.node_tree.nodes if n.type in ('BSDF_PRINCIPLED', 'BSDF_DIFFUSE')]


def surface_bsdf(material):
    """The material's Principled or Diffuse BSDF node (see the module's doc), or None."""
    if material is None or not compat.uses_nodes(material):
        return None
    candidates = _bsdf_nodes(material)
    for node in material.node_tree.nodes:
        if node.type == 'OUTPUT_MATERIAL' and node.is_active_output:
            surface = node.inputs.get("Surface")
            if surface is not None and surface.is_linked and surface.links[0].from_node in candidates:
                return surface.links[0].from_node
    return candidates[0] if candidates else None


def _input_value(node, name, default):
    socket = node.inputs.get(name)
    if socket is None or not hasattr(socket, "default_value"):
        return default
    return float(socket.default_value)


def _colour_socket(node):
    return node.inputs.get("Base Color" if node.type == 'BSDF_PRINCIPLED' else "Color")


def _uv_map(image_node):
    vector = image_node.inputs.get("Vector")
    if vector is not None and vector.is_linked and vector.links[0].from_node.type == 'UVMAP':
        return vector.links[0].from_node.uv_map
    return ""


def _dielectric_reflectance(node):
    if compat.principled_layered(node):
        return lobes.dielectric_reflectance(_input_value(node, "IOR", 1.5),
                                            _input_value(node, "Specular IOR Level", 0.5))
    return lobes.dielectric_reflectance(specular=_input_value(node, "Specular", 0.5))


def _first_input(node, names):
    return next((node.inputs[name] for name in names if node.inputs.get(name) is not None), None)


def _left_out(node):
    """What of a Principled BSDF the lobes do not show: its other layers where they are on (or
    driven by nodes), emission, a specular tint, anisotropy, alpha below 1, and lobe inputs driven
    by nodes (their default values are used)."""
    notes = []
    for layer, names in compat.PRINCIPLED_LAYERS:
        socket = _first_input(node, names)
        if socket is not None and (socket.is_linked or socket.default_value > 0.0):
            notes.append("%s left out" % layer)
    strength = _first_input(node, ("Emission Strength",))
    colour = _first_input(node, ("Emission Color", "Emission"))
    if strength is not None and colour is not None and (
            (strength.is_linked or strength.default_value > 0.0)
            and (colour.is_linked or max(tuple(colour.default_value)[:3]) > 0.0)):
        notes.append("emission left out")
    # Specular Tint: a colour from 4.0 (white shows nothing: the metal's F82 edge tint is then
    # Schlick's), a share of the base colour before (0 shows nothing).
    tint = node.inputs.get("Specular Tint")
    if tint is not None and (tint.is_linked or (min(tuple(tint.default_value)[:3]) < 1.0 if tint.type == 'RGBA'
                                                else tint.default_value > 0.0)):
        notes.append("specular tint left out")
    anisotropic = node.inputs.get("Anisotropic")
    if anisotropic is not None and (anisotropic.is_linked or anisotropic.default_value > 0.0):
        notes.append("anisotropy left out")
    alpha = node.inputs.get("Alpha")
    if alpha is not None and (alpha.is_linked or alpha.default_value < 1.0):
        notes.append("shown opaque")
    # Before 4.0, IOR reaches only the transmission (noted above); F0 came from Specular.
    for name in ("Metallic", "Roughness") + (("IOR", "Specular IOR Level") if compat.principled_layered(node) else ("Specular",)):
        socket = node.inputs.get(name)
        if socket is not None and socket.is_linked:
            notes.append("%s from node %s shown as the input's default" % (name, socket.links[0].from_node.name))
    return notes


def _principled(node):
    """(weights, Lobes, why, note) of a Principled BSDF."""
    roughness, metallic = _input_value(node, "Roughness", 0.5), _input_value(node, "Metallic", 0.0)
    f0 = _dielectric_reflectance(node)
    weights = lobes.principled_weights(roughness, metallic, f0, compat.principled_layered(node),
                                       getattr(node, "distribution", 'MULTI_GGX') != 'GGX')
    found, why = lobes.lobes_from_principled(roughness, metallic, f0)
    notes = []
    if found.lobe == "phong":
        notes.append("GGX shown as Phong")
    elif found.layer:
        notes.append("specular layer shadowed as the diffuse (folded into Lambert without "
                     "Prefiltered Glossy)")
    return weights, found, why, notes + _left_out(node)


def albedo(material):
    """The Albedo of one material (None: an empty slot, Blender's default surface)."""
    if material is None:
        return Albedo()
    node = surface_bsdf(material)
    if node is None:
        return Albedo(tuple(material.diffuse_color)[:3], note="no Principled or Diffuse BSDF: "
                      "its viewport colour", why="no Principled or Diffuse BSDF -> Lambert")
    socket = _colour_socket(node)
    colour = tuple(socket.default_value)[:3]
    weights, found, why, notes = lobes.DIFFUSE_ONLY, lobes.Lobes(), "Diffuse BSDF -> Lambert", []
    if node.type == 'BSDF_PRINCIPLED':
        weights, found, why, notes = _principled(node)
    image = uv_map = None
    if socket.is_linked:
        source = socket.links[0].from_node
        if source.type == 'TEX_IMAGE' and source.image is not None:
            image, uv_map = source.image, _uv_map(source)
        else:
            notes.append("colour from node %s shown as the input's default" % source.name)
    return Albedo(colour, image, uv_map, "; ".join(notes), weights, found, why)


def object_albedos(obj):
    """One Albedo per material slot of the object (at least one). Only one image texture per
    object is shown: slots reading another image show their colour input's default value."""
    slots = list(getattr(obj, "material_slots", ()))
    out = [albedo(slot.material) for slot in slots] or [Albedo()]
    image = texture_image(out)
    return [a if a.image is None or a.image == image else
            dataclasses.replace(a, image=None, uv_map=None,
                                note="second image texture (%s) shown as a flat colour" % a.image.name)
            for a in out]


def texture_image(albedos):
    """The one image texture the object's albedos read, or None."""
    return next((a.image for a in albedos if a.image is not None), None)


def culls_back_faces(obj):
    """Whether every material slot of the object holds a material with Backface Culling on
    (Material > Settings): its faces are meant to be seen from the front only."""
    slots = list(getattr(obj, "material_slots", ()))
    return bool(slots) and all(slot.material is not None and slot.material.use_backface_culling for slot in slots)


def albedo_uv_map(obj):
    """The UV map the object's albedo texture is read through ("": the active render one), or None
    without a texture: the bake keeps these UVs per vertex."""
    return next((a.uv_map for a in object_albedos(obj) if a.image is not None), None)


def albedo_summary(obj):
    """Lines for the panel: each slot's albedo and what is approximated."""
    lines = []
    for slot, albedo in zip(list(getattr(obj, "material_slots", ())) or [None], object_albedos(obj)):
        name = slot.material.name if slot is not None and slot.material is not None else "no material"
        if albedo.image is not None:
            what = "image %s (UV map %s)" % (albedo.image.name, albedo.uv_map or "active render")
        else:
            what = "(%.2f, %.2f, %.2f)" % albedo.colour
        lines.append("%s: albedo %s" % (name, what) + ("; %s" % albedo.note if albedo.note else ""))
    return lines


def lobes_from_material(obj):
    """The object's Lobes from its materials, and a line saying why: Lambert when a slot needs a
    diffuse lobe, Phong with the first glossy slot's exponent when one needs a glossy lobe, and
    Lambert with specular layers when the slots have no glossy lobe but a rough dielectric's
    layer."""
    slots = list(getattr(obj, "material_slots", ()))
    if not slots:
        return lobes.Lobes(), "no material -> Lambert"
    albedos = [albedo(slot.material) for slot in slots]   # an empty slot: the diffuse default
    names = [slot.material.name if slot.material is not None else "an empty slot" for slot in slots]
    glossy = [(a, name) for a, name in zip(albedos, names) if a.bsdf_lobes.lobe == "phong"]
    if not glossy:
        layered = next(((a, name) for a, name in zip(albedos, names) if a.bsdf_lobes.layer), None)
        if layered is not None:
            return layered[0].bsdf_lobes, "%s: %s" % (layered[1], layered[0].why)
        return lobes.Lobes(), "%s: %s" % (names[0], albedos[0].why)
    first, name = glossy[0]
    diffuse = [n for a, n in zip(albedos, names) if a.weights[0] < 1.0]   # not wholly metal
    specular, lambert = np.sum([lobes.reflected(a.colour, a.weights) for a in albedos], axis=0)
    share = lambert / (specular + lambert) if diffuse and specular + lambert > 0.0 else 0.0
    found = lobes.Lobes("phong", first.bsdf_lobes.exponent, bool(diffuse), True, float(share))
    why = "%s: %s" % (name, first.why)
    if diffuse and not first.bsdf_lobes.diffuse:
        why += "; Lambert for %s" % diffuse[0]
    return found, why


def lobe_for(obj, settings):
    """The Lobes to bake and shade `obj` with under the scene's settings."""
    if settings.material_source == 'LAMBERT':
        return lobes.Lobes()
    if settings.material_source == 'PHONG':
        return lobes.Lobes("phong", float(settings.phong_exponent))
    return lobes_from_material(obj)[0]
