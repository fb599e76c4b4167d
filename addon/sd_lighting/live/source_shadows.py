"""The bright sources' shadow maps (issue 29): per source, an orthographic view from its direction
of everything visible that casts shadows (the geometry the bake's rays see: bake/geometry.py's
scene_parts), storing the distance towards the source of the nearest caster per texel (float, not
depth: the shader compares distances). The shading reads them per pixel
(shaders/sd_source_shadows.glsl).

The maps are rendered again only when the sources' world directions change (the environment
turns) or what casts does (staleness.shape_generation: a move, an edit, an undo; or which objects
are visible - hiding one updates only the scene in the depsgraph); otherwise a draw costs their
lookups alone. The caster geometry is read again only on the second kind of change.
"""

import numpy as np

from .. import compat
from ..bake import geometry
from ..scene import light_sources
from . import gpu_shading, staleness

_mesh = [None, None]      # [key, (world vertices float64 or None, triangles, centre, radius)]
_casters = [None, None]   # [key, (GPUBatch or None, centre, radius)]
_maps = [None, None]      # [key, (texture, shader rows)]
_targets = {}             # source count -> (colour GPUTexture, depth GPUTexture)
_shader = []              # (GPUShader, interface, create-info), compiled once

EMPTY = -1.0e30           # what a texel holds where nothing casts


def clear_cache():
    _mesh[:] = [None, None]
    _casters[:] = [None, None]
    _maps[:] = [None, None]
    _targets.clear()
    _shader.clear()


def _caster_shader():
    if not _shader:
        import gpu
        info = gpu.types.GPUShaderCreateInfo()
        info.push_constant('MAT4', "sd_light_clip")
        info.push_constant('VEC4', "sd_light_t")
        info.vertex_in(0, 'VEC3', "pos")
        interface = gpu.types.GPUStageInterfaceInfo("sd_caster_interface")
        interface.smooth('FLOAT', "sd_t")
        _shader.append((gpu_shading.create(info, interface, gpu_shading.CASTER_FILES), interface, info))
    return _shader[0][0]


def _visible(scene, view_layer):
    """The names of the scene's visible objects that can cast (bake/geometry.casts)."""
    out = []
    for obj in scene.objects:
        if geometry.casts(obj):
            try:
                if obj.visible_get(view_layer=view_layer):
                    out.append(obj.name_full)
            except (RuntimeError, TypeError):
                pass
    return tuple(out)


def caster_mesh(scene, depsgraph, view_layer):
    """(key, world vertices float64 [V, 3] or None, triangles [T, 3], centre, radius of their
    bounding sphere) of every visible triangle that casts, read again when something moved,
    changed, appeared or was hidden since the last call - exactly when the key changes. The
    shadow maps draw them; the reflection rays trace them (ray_bvh.py)."""
    key = (staleness.shape_generation, scene.name_full, _visible(scene, view_layer))
    if _mesh[0] != key:
        vertices, triangles = geometry.join([(part.vertices, part.triangles)
                                             for part in geometry.scene_parts(depsgraph, view_layer)])
        if vertices is None:
            _mesh[1] = (None, None, np.zeros(3), 1.0)
        else:
            low, high = vertices.min(axis=0), vertices.max(axis=0)
            _mesh[1] = (vertices, triangles, (low + high) / 2.0,
                        max(float(np.linalg.norm(high - low)) / 2.0, 1e-6))
        _mesh[0] = key
    return (_mesh[0],) + _mesh[1]


def casters(scene, depsgraph, view_layer):
    """(batch of caster_mesh's triangles or None, centre, radius of their bounding sphere)."""
    key, vertices, triangles, centre, radius = caster_mesh(scene, depsgraph, view_layer)
    if _casters[0] != key:
        batch = None if vertices is None else \
            compat.make_batch('TRIS', {"pos": vertices.astype(np.float32)}, indices=triangles)
        _casters[:] = [key, (batch, centre, radius)]
    return _casters[1]


def _target(count):
    """(colour, depth) textures holding `count` maps side by side. Textures are shared between
    Blender's windows (GPU contexts); a framebuffer is not - bound in another window's context it
    binds nothing, and the clear and the casters would go into that window's viewport -, so
    shadow_maps makes its framebuffer each time it draws."""
    if count not in _targets:
        import gpu
        size = light_sources.SHADOW_MAP_SIZE
        if count * size > gpu.capabilities.max_texture_size_get():
            raise ValueError("%d shadow maps of %d texels are wider than this GPU's textures (%d)"
                             % (count, size, gpu.capabilities.max_texture_size_get()))
        _targets.clear()   # one set at a time: the scene's sources
        _targets[count] = (gpu.types.GPUTexture((count * size, size), format='R32F'),
                           gpu.types.GPUTexture((count * size, size), format='DEPTH_COMPONENT32F'))
    return _targets[count]


def shadow_maps(sources, to_environment, scene, depsgraph, view_layer):
    """(the maps' R32F texture, the shader's rows: light_sources.shadow_rows) of `sources`
    (light_sources.Source, not empty) with the environment rotation g = `to_environment`, rendered
    when the sources' directions or the casters changed. Draws into its own framebuffer, puts the
    viewport back as it was, and leaves depth testing (LESS_EQUAL) and writing on, blending and
    culling off: the state the live shading draws with (its callers set the same). Needs a GPU
    context."""
    import gpu
    from mathutils import Matrix
    batch, centre, radius = casters(scene, depsgraph, view_layer)
    g = np.asarray(to_environment, dtype=np.float64)
    key = (_casters[0], tuple(sources), g.tobytes())
    if _maps[0] == key:
        return _maps[1]
    rows, projections = light_sources.shadow_rows(sources, g, centre, radius)
    colour, depth = _target(len(sources))
    framebuffer = gpu.types.GPUFrameBuffer(depth_slot=depth, color_slots=colour)
    size = light_sources.SHADOW_MAP_SIZE
    viewport = gpu.state.viewport_get()
    try:
        with framebuffer.bind():
            framebuffer.clear(color=(EMPTY, 0.0, 0.0, 0.0), depth=1.0)
            if batch is not None:
                gpu.state.depth_test_set('LESS_EQUAL')
                gpu.state.depth_mask_set(True)
                gpu.state.blend_set('NONE')
                gpu.state.face_culling_set('NONE')
                shader = _caster_shader()
                for i, projection in enumerate(projections):
                    gpu.state.viewport_set(i * size, 0, size, size)
                    gpu_shading.bind(shader)
                    shader.uniform_float("sd_light_clip", Matrix(projection.tolist()))
                    shader.uniform_float("sd_light_t", rows[light_sources.SOURCE_ROWS * i + 2].tolist())
                    batch.draw(shader)
    finally:
        gpu.state.viewport_set(*viewport)
    _maps[:] = [key, (colour, rows)]
    return _maps[1]
