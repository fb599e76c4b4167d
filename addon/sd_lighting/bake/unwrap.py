"""The lightmap unwrap of a texture-space bake (lightmap.py holds the bpy-free rest): Blender's
Smart UV Project of the baked copy, on the main thread, leaving nothing of the user's changed."""

import numpy as np

from .. import background
from ..errors import BakeError
from ..store import attributes
from . import lightmap

QUIET_SECONDS = 30.0   # how long the unwrap waits for the add-on's threads (background.quiet)


def lightmap_uvs(context, geometry, size):
    """Each loop's lightmap UV of the geometry (float32 [L, 2]): Blender's Smart UV Project of a
    copy in the bake space scaled to unit area (texel density follows the scaled surface), its
    charts at least lightmap.MARGIN_TEXELS texels of a size x size map apart. The margin is
    'ADD'ed in the copy's units around each chart before the charts are scaled into the map, so it
    is chosen from the scale they get (lightmap.add_margin; at unit area it stays far below the
    operator's cap of 1), and the unwrap repeated, up to lightmap.UNWRAP_TRIES times, while the
    scale came out smaller than that margin needs (the last is kept): the default 'SCALED'
    margin shrinks with few charts (to about a texel on a cube), and the exact 'FRACTION' one
    packs ten times slower (13 s on the 85k-vertex engine). The copy is of the split vertices, so
    its charts also end at sharp edges, material borders and albedo UV seams. It lives in a
    temporary scene, so that Edit Mode reaches it alone; nothing else changes. The operators run
    under a context override, so the add-on's threads are held out of Python meanwhile
    (background.quiet; the caller has cancelled those it may). Raises BakeError outside Object
    Mode (another object would share that Edit Mode), for a copy without area, when a thread of
    the add-on's still runs after QUIET_SECONDS, or when the unwrap fails."""
    import bpy
    if context.mode != 'OBJECT':
        raise BakeError("texture-space data are unwrapped in Object Mode (the mode is %s): switch "
                        "to Object Mode to bake them" % context.mode)
    corners = geometry.vertices[geometry.triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    if not area > 0.0:
        raise BakeError("the baked copy has no area to unwrap a lightmap over")
    mesh = attributes.new_mesh("sd_lightmap unwrap", geometry.vertices / np.sqrt(area), geometry.loop_vertices,
                               geometry.loop_starts, geometry.loop_totals)
    try:
        with background.quiet(QUIET_SECONDS):
            return _smart_project(context, geometry, size, mesh)
    except background.Busy as exc:
        raise BakeError("the lightmap's unwrap waited for the add-on's background work: %s; try "
                        "again" % exc) from exc
    finally:
        bpy.data.meshes.remove(mesh)


def _smart_project(context, geometry, size, mesh):
    """lightmap_uvs' unwrap of `mesh`, a copy of the geometry, in a temporary scene."""
    import bpy
    scene = obj = None
    try:
        scene = bpy.data.scenes.new("sd_lightmap unwrap")
        obj = bpy.data.objects.new(mesh.name, mesh)
        scene.collection.objects.link(obj)
        layer = scene.view_layers[0]
        layer.objects.active = obj
        obj.select_set(True, view_layer=layer)
        loops = len(mesh.loops)
        scale = lightmap.expected_scale(1.0)
        for _ in range(lightmap.UNWRAP_TRIES):
            margin = lightmap.add_margin(size, scale)
            try:
                with context.temp_override(scene=scene, view_layer=layer, active_object=obj, object=obj,
                                           selected_objects=[obj], selected_editable_objects=[obj]):
                    bpy.ops.object.mode_set(mode='EDIT')
                    try:
                        with context.temp_override(edit_object=obj):
                            bpy.ops.mesh.select_all(action='SELECT')
                            bpy.ops.uv.smart_project(angle_limit=np.radians(lightmap.ANGLE_LIMIT_DEGREES),
                                                     margin_method='ADD', island_margin=margin)
                    finally:
                        bpy.ops.object.mode_set(mode='OBJECT')
            except RuntimeError as exc:   # an operator's poll or report, e.g. from a timer's context
                raise BakeError("Smart UV Project failed: %s" % exc) from exc
            layer_uv = mesh.uv_layers.active
            if layer_uv is None or len(mesh.loops) != loops:
                raise BakeError("Smart UV Project gave no UV map of the baked copy's %d face corners" % loops)
            uvs = attributes.read_loop_uvs(mesh, layer_uv.name)
            scale = lightmap.uv_scale(uvs[geometry.triangle_loops], 1.0)
            if lightmap.gap_texels(margin, scale, size) >= lightmap.MARGIN_TEXELS:
                break
        return uvs
    finally:
        if obj is not None:
            bpy.data.objects.remove(obj)
        if scene is not None:
            bpy.data.scenes.remove(scene)

