"""SD Lighting: live environment lighting with soft self-shadows by the method of spherical
designs (MSD) and precomputed radiance transfer (PRT).

Use: 3D viewport > sidebar (N) > SD Lighting. What a bake stores and where (the baked mesh, its
attributes, the `sd_bake` settings) is described in the repository's README.md.

Importing this package needs no Blender: the modules that use bpy are imported by register(), so
the pure logic in utils/ (and the sdnative loader, native.py) is importable and tested with plain
Python (tests/addon/).
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
# those already imported, in this order.
_SUBMODULES = ("utils.bake_data", "utils.cost", "utils.methods", "utils.lobes", "utils.transforms",
               "utils.limits", "utils.shader_variant", "utils.background", "utils.lobe_designs",
               "utils.bake_time", "utils.corners", "utils.refine", "utils.least_squares", "utils.lightmap",
               "utils.ringing",
               "utils.accuracy", "utils.automatic", "utils.rebake_schedule", "compat", "native", "materials", "environment",
               "attributes", "view", "analysis", "baking", "prediction", "gpu_context", "gpu_shading", "drawing", "preview",
               "live_rebake",
               "properties", "operators", "panels", "registration")

if "registration" in locals():
    import sys
    for _name in _SUBMODULES:
        if __name__ + "." + _name in sys.modules:
            importlib.reload(sys.modules[__name__ + "." + _name])


def register():
    importlib.import_module(".registration", __name__).register()


def unregister():
    importlib.import_module(".registration", __name__).unregister()
