"""The scene's triangles as a ray BVH for the glossy lobe's traced visibility (the scene's
Reflection Rays; shaders/sd_ray_bvh.glsl walks it, sd_traced_visibility casts the rays): what
casts the sources' shadows (source_shadows.caster_mesh, world space), relative to its centre,
built by sdnative.ray_bvh (Embree's SAH builder) and laid out in a float texture as the per-vertex
data are (gpu_shading.float_texture). Built again only when the casters change; a draw costs the
rays alone.
"""

import numpy as np

from .. import native
from . import gpu_shading, source_shadows

# The rays start this share of the drawn object's radius off its triangle, plus RAY_ROUNDING of the
# casters' radius: float32 positions relative to the casters' centre round by about 6e-8 of it.
RAY_OFFSET = 1e-4
RAY_ROUNDING = 1e-6

_bvh = [None, None]   # [caster key, (GPUTexture, first triangle texel, centre, radius) or the error]


def clear_cache():
    _bvh[:] = [None, None]


def texels(bvh):
    """float32 [M, 4] texels of sdnative.ray_bvh's arrays as the shader reads them, and the first
    triangle's texel: each node's two (lower corner, a; upper corner, b), then each triangle's three
    (p0, p1 - p0, p2 - p0, each with a 0)."""
    nodes = np.asarray(bvh["nodes"], dtype=np.float32).reshape(-1, 4)
    triangles = np.asarray(bvh["triangles"], dtype=np.float32).reshape(-1, 4)
    return np.concatenate([nodes, triangles]), len(nodes)


def scene_bvh(scene, depsgraph, view_layer):
    """(texture, first triangle texel, centre, radius) of the visible casters' ray BVH; no casters
    give one empty texel and first texel 0 (the shader then traces nothing). Built again when the
    casters change (a move too: about 0.14 s for 200k triangles); a build that failed raises its
    error again, without another try, until they change. Needs a GPU context."""
    key, vertices, triangles, centre, radius = source_shadows.caster_mesh(scene, depsgraph, view_layer)
    if _bvh[0] != key:
        first = 0
        data = np.zeros((1, 4), dtype=np.float32)
        try:
            if vertices is not None:
                data, first = texels(native.get().ray_bvh(vertices - centre, triangles))
            _bvh[:] = [key, (gpu_shading.float_texture(data), first, centre, radius)]
        except Exception as exc:
            _bvh[:] = [key, exc]
    if isinstance(_bvh[1], Exception):
        raise _bvh[1]
    return _bvh[1]


def block_rows(bvh, model, object_radius):
    """The uniform block's ray_bvh and ray_offset rows for one object drawn with `model` (4x4
    object to world), whose mesh lies within `object_radius` of its origin: the first triangle's
    texel and the object's origin relative to the casters' centre (float64 differences), and how
    far off its triangles the rays start."""
    _, first, centre, radius = bvh
    model = np.asarray(model, dtype=np.float64)
    scale = float(np.max(np.linalg.norm(model[:3, :3], axis=0)))
    origin = model[:3, 3] - centre
    offset = RAY_OFFSET * object_radius * scale + RAY_ROUNDING * radius
    return {"ray_bvh": (float(first), origin[0], origin[1], origin[2]), "ray_offset": (offset,)}
