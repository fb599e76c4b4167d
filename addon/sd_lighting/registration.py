"""What enabling and disabling the add-on does: settings, operators, panel, the viewport's draw
handler, the handlers of stale bakes (staleness.py) and of the live re-bake (live_rebake.py), and a
load_post handler that drops the GPU data, environments and re-bakes of the previous file, and a
save_pre one that leaves deleted objects' bakes out of the file."""

import bpy
from bpy.app.handlers import persistent

from .scene import environment
from .live import drawing, gpu_shading, live_rebake, staleness
from .store import baked
from .ui import operators, panels, prediction, properties


@persistent
def _on_load(_dummy):
    drawing.clear_cache()
    gpu_shading.clear_cache()
    environment.clear_cache()
    prediction.clear()
    live_rebake.stop()
    live_rebake.sync()


@persistent
def _on_save(*_args):
    """save_pre: the baked meshes of deleted objects are not written (store.baked.remove_unlinked)."""
    baked.remove_unlinked()


HANDLERS = (("load_post", _on_load), ("save_pre", _on_save))


def register():
    properties.register()
    operators.register()
    panels.register()
    drawing.register()
    staleness.register()
    live_rebake.register()
    for name, handler in HANDLERS:
        if handler not in getattr(bpy.app.handlers, name):
            getattr(bpy.app.handlers, name).append(handler)


def unregister():
    for name, handler in HANDLERS:
        if handler in getattr(bpy.app.handlers, name):
            getattr(bpy.app.handlers, name).remove(handler)
    live_rebake.unregister()
    staleness.unregister()
    drawing.unregister()
    prediction.clear()
    gpu_shading.clear_cache()
    environment.clear_cache()
    panels.unregister()
    operators.unregister()
    properties.unregister()
