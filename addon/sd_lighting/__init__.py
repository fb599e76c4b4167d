"""SD Lighting: live environment lighting with soft self-shadows by the method of spherical
designs (MSD) and precomputed radiance transfer (PRT).

Use: 3D viewport > sidebar (N) > SD Lighting. Select meshes, press Bake; baked objects are then
drawn live with the chosen formula while the environment turns (the world's Mapping node, or the
panel's Rotation). Render Preview writes what the live shading shows from the scene camera.

Where the results live: baking an object creates a mesh datablock "SD <object>" - a copy of the
object's evaluated mesh (modifiers applied), with a fake user - linked from the object's custom
property `sd_baked_mesh`; the object's own mesh is never touched. Bake settings are in the custom
property `sd_bake` of the object and of the baked mesh (method, lobe, exponent, light_order s,
visibility_order s', rays, seed, seconds, vertices, floats_per_vertex, bytes_per_vertex,
design_nodes_max, design_nodes_mean, environment, bake_id). All survive save and reload.

Attributes of the baked mesh (POINT domain, prefix `sd_`, 1-4 floats each; NNN = 000, 001, ...):
  sd_normal             FLOAT_VECTOR  unit normal the vertex was baked and is shaded with
  sd_ambient_occlusion  FLOAT         V~_00, the visible fraction of the sphere (every bake)
  sd_visibility_NNN     FLOAT_COLOR   SH coefficients 4N..4N+3 of V~, order s' (PRT (10), MSD 2.1)
  sd_transfer_NNN       FLOAT_COLOR   coefficients 4N..4N+3 of the transfer T, order s (PRT (2))
  sd_matrix_NNN         FLOAT_COLOR   entries 4N..4N+3 of the product matrix M, row-major,
                                      (s+1)^2 x (s'+1)^2 (PRT (8))
  sd_design_NNN         FLOAT_COLOR   node N of the vertex's design of V: x, y, z, lambda
                                      (lambda = 0: padding) (MSD Theorem 2.2, eq. 13)
Directions are in the object's local frame; SH follow sdnative's convention (index l^2 + l + m).

Modules: properties (settings), operators, panels, drawing (draw handler), gpu_shading (shader
variants, GPU data), baking, attributes, environment (world nodes, rotation), materials (lobe),
methods, preview (stills), gpu_context (background GPU), native (the sdnative loader), compat (what
differs between Blender versions).
"""

bl_info = {
    "name": "SD Lighting",
    "author": "sd-lighting",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "3D Viewport > Sidebar > SD Lighting",
    "description": "Live environment lighting with soft self-shadows: method of spherical designs "
                   "and PRT, baked per vertex, shaded in the viewport",
    "category": "Lighting",
}

if "bpy" in locals():  # script reload (F3 > Reload Scripts)
    import importlib
    for _name in ("compat", "native", "methods", "materials", "environment", "attributes", "baking",
                  "gpu_context", "gpu_shading", "drawing", "preview", "properties", "operators",
                  "panels"):
        if _name in locals():
            importlib.reload(locals()[_name])

import bpy  # noqa: E402
from bpy.app.handlers import persistent  # noqa: E402

from . import (attributes, baking, compat, drawing, environment, gpu_context,  # noqa: E402,F401
               gpu_shading, materials, methods, native, operators, panels, preview, properties)


@persistent
def _on_load(_dummy):
    """A new file: GPU data and environments belong to the old one."""
    drawing.clear_cache()
    gpu_shading.clear_cache()
    environment.clear_cache()


def register():
    properties.register()
    operators.register()
    panels.register()
    drawing.register()
    if _on_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_on_load)


def unregister():
    if _on_load in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_on_load)
    drawing.unregister()
    gpu_shading.clear_cache()
    environment.clear_cache()
    panels.unregister()
    operators.unregister()
    properties.unregister()
