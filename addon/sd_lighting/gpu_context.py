"""A GPU context when Blender runs without a window (`blender -b`).

Blender 3.4 creates no GPU context in background mode; rendering one small frame with the
Workbench engine creates one, after which the `gpu` module works (Blender 4.x has `gpu.init()`
for this, used when present). The render leaves depth testing enabled, so every draw of this
add-on sets the GPU state it needs itself.
"""

_ready = False


def ensure():
    """Makes `gpu` usable; a no-op with a window or once done."""
    global _ready
    import bpy
    if _ready or not bpy.app.background:
        _ready = True
        return
    import gpu
    if hasattr(gpu, "init"):
        gpu.init()
        _ready = True
        return
    scene = bpy.context.scene
    render = scene.render
    saved = (render.engine, render.resolution_x, render.resolution_y, render.resolution_percentage,
             scene.camera)
    camera = scene.camera
    temporary = None
    try:
        if camera is None:
            data = bpy.data.cameras.new("sd_lighting gpu init")
            temporary = bpy.data.objects.new("sd_lighting gpu init", data)
            scene.collection.objects.link(temporary)
            scene.camera = temporary
        render.engine = 'BLENDER_WORKBENCH'
        render.resolution_x, render.resolution_y, render.resolution_percentage = 8, 8, 100
        bpy.ops.render.render()
    finally:
        (render.engine, render.resolution_x, render.resolution_y, render.resolution_percentage,
         scene.camera) = saved
        if temporary is not None:
            data = temporary.data
            bpy.data.objects.remove(temporary)
            bpy.data.cameras.remove(data)
    _ready = True
