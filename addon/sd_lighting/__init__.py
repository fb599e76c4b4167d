"""SD Lighting: live environment lighting with soft self-shadows by the method of spherical
designs (MSD) and precomputed radiance transfer (PRT).

Use: 3D viewport > sidebar (N) > SD Lighting. What a bake stores and where (the baked mesh, its
attributes, the `sd_bake` settings) is described in the repository's README.md.

Importing this package needs no Blender: the modules that use bpy are imported by register(), so
the pure logic beside them in each sub-package (and the sdnative loader, native.py) is importable
and tested with plain Python (tests/addon/).
"""

import importlib

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

# Every submodule, dependencies first: F3 > Reload Scripts re-runs this file, which then reloads
# those already imported, in this order. The sub-packages follow the pipeline: scene (what the
# scene gives: environment, materials, view), plan (the automatic mode's error and cost
# predictions), bake, store (the baked meshes and their records), live (the shading), ui.
_SUBMODULES = ("background", "compat", "errors", "native", "redraw",
               "scene.lobes", "scene.materials", "scene.ringing", "scene.transforms", "scene.world_render",
               "scene.light_sources",
               "scene.environment",
               "scene.view",
               "plan.bake_time", "plan.cost", "plan.budget", "store.bake_data", "methods", "plan.accuracy",
               "store.record", "store.attributes", "store.source",
               "bake.corners", "bake.refine", "bake.least_squares", "plan.automatic", "plan.analysis", "bake.lightmap",
               "store.baked", "bake.sides", "bake.geometry", "bake.task", "bake.job", "bake.unwrap",
               "bake.prepare",
               "live.gpu_context", "live.lobe_designs", "live.rebake_schedule", "live.band_limited_map",
               "live.shader_variant",
               "live.gpu_shading", "live.staleness", "live.source_shadows", "live.ray_bvh", "live.drawing", "live.live_rebake", "live.preview",
               "ui.limits", "ui.prediction", "ui.operators", "ui.panels", "ui.properties", "registration")

if "registration" in locals():
    import sys
    for _name in _SUBMODULES:
        if __name__ + "." + _name in sys.modules:
            importlib.reload(sys.modules[__name__ + "." + _name])


def register():
    importlib.import_module(".registration", __name__).register()


def unregister():
    importlib.import_module(".registration", __name__).unregister()
