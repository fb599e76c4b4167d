"""What enabling and disabling the add-on does: settings, operators, panel, the viewport's draw
handler, and a load_post handler that drops the GPU data and environments of the previous file."""

import bpy
from bpy.app.handlers import persistent

from . import drawing, environment, gpu_shading, operators, panels, prediction, properties


@persistent
def _on_load(_dummy):
    drawing.clear_cache()
    gpu_shading.clear_cache()
    environment.clear_cache()
    prediction.clear()


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
    prediction.clear()
    gpu_shading.clear_cache()
    environment.clear_cache()
    panels.unregister()
    operators.unregister()
    properties.unregister()
