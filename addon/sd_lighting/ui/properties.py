"""The add-on's settings, per scene (`scene.sd_lighting`): what the next bake uses and how the
live shading draws. What a bake actually used is stored per object (custom property `sd_bake`).
Upper limits come from sdnative (ui/limits.py), read when the add-on registers.
"""

import logging

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty,
                       IntProperty, PointerProperty, StringProperty)

from .. import methods, native, redraw
from ..live import live_rebake, shader_variant
from ..plan import analysis
from ..scene import environment, ringing
from ..bake import lightmap, refine
from . import limits

log = logging.getLogger(__name__)


def _limits():
    try:
        return limits.from_module(native.get())
    except (ImportError, AttributeError) as exc:   # AttributeError: an sdnative of another version
        log.warning("settings without upper limits: %s", exc)
        return limits.Limits()


LIMITS = _limits()


def _redraw(self, context):
    redraw.viewports()


# The rotation's getter and setter keep the value in the hidden property `stored_rotation` when
# there is no Mapping node, by attribute access, not dict-style self["..."]: Blender 5.0 stores
# bpy.props values apart from custom (dict) properties - on IDs, id["prop"] no longer reaches a
# bpy.props property there (5.0.1 still lets a PropertyGroup's self["prop"] through).
def _get_rotation(self):
    mapping = environment.mapping_node(self.id_data)
    if mapping is not None:
        return tuple(mapping.inputs["Rotation"].default_value)
    return tuple(self.stored_rotation)


def _set_rotation(self, value):
    mapping = environment.mapping_node(self.id_data)
    if mapping is not None:
        mapping.inputs["Rotation"].default_value = value
    else:
        self.stored_rotation = tuple(value)


def _sync_live_rebake(self, context):
    live_rebake.sync()


_AUTOMATIC_ITEM = [(analysis.AUTOMATIC, "Automatic",
                    "Per object, the method, s, s' and rays of the lowest frame cost whose error, "
                    "measured on sampled vertices before the bake, is within the target error")]


class ObjectOverrides(bpy.types.PropertyGroup):
    """An object's own bake settings, each used instead of the scene's (and of the automatic
    choice) when its `use_` box is ticked; kept with the object."""
    use_method: BoolProperty(name="Method", default=False)
    method: EnumProperty(name="Method", items=methods.enum_items(), default='prt_diffuse')
    use_light_order: BoolProperty(name="s", default=False)
    light_order: IntProperty(name="s", default=4, min=0, **limits.maximum(LIMITS.light_order))
    use_visibility_order: BoolProperty(name="s'", default=False)
    visibility_order: IntProperty(name="s'", default=2, min=0,
                                  **limits.maximum(LIMITS.visibility_order))
    use_rays: BoolProperty(name="Rays", default=False)
    rays: IntProperty(name="Rays", default=256, min=16, **limits.maximum(LIMITS.rays))

    def fixed(self):
        """The overridden settings: plan/accuracy.Setting field -> value."""
        return {name: getattr(self, name) for name in
                ("method", "light_order", "visibility_order", "rays") if getattr(self, "use_" + name)}


class SceneSettings(bpy.types.PropertyGroup):
    environment_source: EnumProperty(
        name="Environment",
        items=[('WORLD', "World", "The world's Environment Texture (times the Background strength)"),
               ('FILE', "File", "An equirectangular HDRI file")],
        default='WORLD', update=_redraw)
    environment_path: StringProperty(
        name="File", subtype='FILE_PATH', description="Equirectangular HDRI (EXR or HDR)",
        update=_redraw)
    environment_rotation: FloatVectorProperty(
        name="Rotation", subtype='EULER', size=3, get=_get_rotation, set=_set_rotation,
        description="Rotation g of the environment (XYZ Euler). Drives the world's Mapping node "
                    "in front of the Environment Texture when there is one")
    stored_rotation: FloatVectorProperty(
        name="Stored Rotation", subtype='EULER', size=3, options={'HIDDEN'},
        description="The environment rotation when no Mapping node holds it")

    automatic_orders: BoolProperty(
        name="Automatic s", default=True,
        description="For a chosen method, choose the environment's SH order s from the "
                    "lobe-filtered truncation error")
    target_error: FloatProperty(
        name="Target Error", default=0.02, min=0.001, max=1.0, subtype='FACTOR',
        description="Relative RMS error to aim for: of B against the reference of eq. (1), "
                    "measured on sampled vertices (Automatic method); of the lobe-filtered "
                    "environment (Automatic s of a chosen method); of the light between two "
                    "vertices against their interpolation (Refine)")
    max_automatic_order: IntProperty(
        name="Max s", default=8, min=1, **limits.maximum(LIMITS.light_order),
        description="Largest order automatic s may choose")
    light_order: IntProperty(
        name="s", default=4, min=0, **limits.maximum(LIMITS.light_order),
        description="SH order of the environment L~")
    visibility_order: IntProperty(
        name="s'", default=2, min=0, **limits.maximum(LIMITS.visibility_order),
        description="SH order of the visibility V~")

    material_source: EnumProperty(
        name="Material",
        items=[('MATERIAL', "From Material", "Principled BSDF: metals Phong (sigma from the roughness), glossy "
                "plastics Lambert and Phong, rough dielectrics Lambert with their specular layer"),
               ('LAMBERT', "Lambert", "Diffuse"),
               ('PHONG', "Phong", "Glossy lobe around the mirrored view, exponent sigma")],
        default='MATERIAL')
    phong_exponent: FloatProperty(
        name="Sigma", default=8.0, min=0.0, soft_max=200.0, **limits.maximum(LIMITS.phong_exponent),
        description="Phong exponent sigma")

    method: EnumProperty(name="Method", items=_AUTOMATIC_ITEM + methods.enum_items(),
                         default=analysis.AUTOMATIC)
    rays: IntProperty(name="Rays", default=256, min=16,
                      **limits.maximum(LIMITS.rays),
                      description="Rays traced per vertex for the visibility")
    seed: IntProperty(name="Seed", default=0, min=0, description="Seed of the ray directions")

    refine: BoolProperty(
        name="Refine", default=True,
        description="Before the bake, split the baked copy's triangles where the light between "
                    "their vertices is not linear (a shadow across a large face) by more than the "
                    "target error, up to the vertex budget. The object's own mesh is not changed")
    least_squares: BoolProperty(
        name="Least Squares", default=True,
        description="Fit the baked vertex values so that their interpolation across each face best "
                    "matches the light at the faces' centres as well as at the vertices (bakes about "
                    "3x the rays; all methods but MSD (13), whose designs are kept as baked)")
    refine_max_vertices: IntProperty(
        name="Max Verts", default=refine.DEFAULT_MAX_VERTICES, min=1, soft_max=2_000_000,
        description="Most vertices the refined copies of the objects baked together may have "
                    "(the bake's time and memory grow with them), shared by their surface areas; a "
                    "copy that has its share already is not refined")

    texture_space: BoolProperty(
        name="Texture Space", default=False,
        description="Also bake the light into a lightmap over the baked copy (Blender's Smart UV "
                    "Project), read per pixel by the live shading: shadows finer than the vertices "
                    "without more vertices. AO, PRT and MSD (12) (MSD (13) bakes per vertex); where it "
                    "applies, the vertices are baked without refinement and least squares. Baked in "
                    "Object Mode (a Live Re-bake waits for it)")
    lightmap_size: EnumProperty(
        name="Lightmap", items=[(str(size), "%d x %d" % (size, size), "A lightmap of %d x %d texels: its "
                                 "bake time and memory grow with them" % (size, size)) for size in lightmap.SIZES],
        default=str(lightmap.DEFAULT_SIZE))

    live_rebake: BoolProperty(
        name="Live Re-bake", default=False, update=_sync_live_rebake,
        description="While you edit a baked object (edit mode, modifiers), bake it again in the "
                    "background with the settings of its bake, and show the new bake when done")

    live_shading: BoolProperty(
        name="Live Shading", default=True, update=_redraw,
        description="Draw baked objects in the viewport with the chosen formula")
    per_pixel: BoolProperty(
        name="Per Pixel", default=False, update=_redraw,
        description="Evaluate the formula per pixel (the pixel's normal and view, the triangle's "
                    "per-vertex data blended) instead of per vertex (the seed's way)")
    world_background: BoolProperty(
        name="World Background", default=False, update=_redraw,
        description="Draw the environment behind the scene in the live shading and the preview "
                    "(turned with the environment, the exposure applied), as Cycles renders it "
                    "without a transparent film")
    band_limited_texture: BoolProperty(
        name="Band-Limited Texture", default=False, update=_redraw,
        description=", ".join(m.label for m in methods.METHODS if m.band_limited_texture) +
        ": look the environment L~ up in a band-limited equirect float texture (bilinear, about "
        "5e-4 relative) instead of summing its (s+1)^2 SH terms at every node (exact)")
    prefiltered_glossy: BoolProperty(
        name="Prefiltered Glossy", default=True, update=_redraw,
        description="Light glossy Principled materials with the environment prefiltered by their "
                    "GGX lobe (the split sum: sharp at any roughness, looked up per pixel), times "
                    "the share of the lobe's light that reaches the surface (traced: Reflection "
                    "Rays; else as the bake's visibility lets it through); off: the "
                    "seed's Phong lobe truncated at order s, and rough dielectrics' specular "
                    "layers folded into Lambert")
    reflection_rays: BoolProperty(
        name="Reflection Rays", default=True, update=_redraw,
        description="Trace the visibility of prefiltered glossy lobes and rough dielectrics' specular layers per pixel "
                    "through the scene's triangles (rays along the lobe, from each pixel), where the bake's "
                    "visibility is too smooth for a sharp reflection: a crease's reflection of the "
                    "object itself, a leg in front of a polished body. The automatic mode then "
                    "stores no visibility for a metal, whose bake is not drawn: bake again after "
                    "turning this off. Off: the share of the lobe's light the bake's visibility "
                    "lets through")
    reflection_ray_count: EnumProperty(
        name="Rays", default=str(shader_variant.REFLECTION_RAYS), update=_redraw,
        items=[(str(n), str(n), "%d reflection rays per pixel" % n) for n in shader_variant.RAY_COUNTS],
        description="Reflection rays per pixel of a glossy lobe rougher than a near-mirror (which "
                    "takes one): fewer draw faster; a rough lobe's partial shadow then changes "
                    "in steps from one small triangle to the next")
    source_shadows: BoolProperty(
        name="Sharp Source Shadows", default=True, update=_redraw,
        description="Light surfaces by the environment's bright compact sources (a sun, lamps, "
                    "windows: the Environment panel names them) on their own, each shadowed per "
                    "pixel through a shadow map from its direction with a penumbra as wide as the "
                    "source - their diffuse light, and their glossy light (a sun's highlight on its own, "
                    "a softbox's share of the prefiltered light) -, and by the rest of the map through SH; off: the whole map through SH, which "
                    "blurs their shadows. The automatic mode takes them per object where they lower "
                    "its error and then chooses the SH for the rest alone: bake again after turning "
                    "this off")
    ringing_window: EnumProperty(
        name="Ringing Window",
        items=[(name.upper(), ringing.LABELS[name], description) for name, description in (
            ("automatic", "Per lobe and s, the window that lowers the error of the displayed "
             "radiance the most (None when none lowers it)"),
            ("none", "The plain truncation of order s (rings below zero next to a sun)"),
            ("hanning", "sigma_l = (1 + cos(pi l/(s+1)))/2"),
            ("lanczos", "sigma_l = sinc(l/(s+1))"),
            ("sloan", "Sloan's sigma_l = 1/(1 + lambda l^2 (l+1)^2), lambda chosen per lobe"))],
        default='AUTOMATIC', update=_redraw,
        description="Window sigma_l on band l of the environment's SH coefficients against ringing, "
                    "for every method")


CLASSES = (ObjectOverrides, SceneSettings)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.sd_lighting = PointerProperty(type=SceneSettings)
    bpy.types.Object.sd_lighting = PointerProperty(type=ObjectOverrides)


def unregister():
    del bpy.types.Object.sd_lighting
    del bpy.types.Scene.sd_lighting
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
