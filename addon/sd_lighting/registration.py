"""What enabling and disabling the add-on does: settings, operators, panel, the viewport's draw
handler, the live re-bake's handlers (live_rebake.py), and a load_post handler that drops the GPU
data, environments and re-bakes of the previous file."""

import bpy
from bpy.app.handlers import persistent

from .scene import environment
from .live import drawing, gpu_shading, live_rebake
from .ui import operators, panels, prediction, properties


@persistent
def _on_load(_dummy):
    drawing.clear_cache()
    gpu_shading.clear_cache()
    environment.clear_cache()
    prediction.clear()
    live_rebake.stop()
    live_rebake.sync()


def register():
    properties.register()
    operators.register()
    panels.register()
    drawing.register()
    live_rebake.register()
    if _on_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_on_load)


def unregister():
    if _on_load in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_on_load)
    live_rebake.unregister()
    drawing.unregister()
    prediction.clear()
    gpu_shading.clear_cache()
    environment.clear_cache()
    panels.unregister()
    operators.unregister()
    properties.unregister()
