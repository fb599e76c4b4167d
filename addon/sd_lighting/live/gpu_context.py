"""A GPU context when Blender runs without a window (`blender -b`).

Blender creates no GPU context in background mode (`blender -b`, and Blender as a Python module,
bpy): `gpu` raises "not available in background mode". Rendering one small frame with the
Workbench engine creates one (OpenGL through EGL, or Vulkan where that is the default backend -
5.3 -; Mesa's llvmpipe/lavapipe without a GPU), after which the `gpu` module works - seen on 3.4.1
and on bpy 4.2.23, 4.5.15, 5.0.1 and 5.3.0, none of which has a `gpu.init()` (used if a later
version brings one). The render leaves depth testing enabled, so every draw of
this add-on sets the GPU state it needs itself.
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
