"""Live shading: the viewport's POST_VIEW draw handler, and drawing baked objects for any view.

Every baked, visible object is drawn with its baked mesh's geometry times the object's world
matrix, with the shader variant of its bake (gpu_shading.py), depth-tested against the scene.
Per frame and object, the environment's coefficients are rotated on the CPU to those of
x -> L(g R x): g the environment rotation (environment.py), R the rotation of the object's matrix
(the bake's directions are in the object's bake space: bake/geometry.py). The eye is the viewport's own
camera.

What takes longer than a frame is computed in worker threads (background.py): the lobe
designs of MSD (12) (gpu_shading.lobe_designs; the Gauss rule shades meanwhile) and the choice of
the ringing window (environment.window_choices; no window meanwhile). The interactive draw never
waits for them; while one is pending, a timer redraws the viewports when it is done. What is not
interactive - a preview render, cpu_reference and gpu_vertex_values for the tests - waits for the
ringing window (wait=True), so that its result does not depend on timing.

Colour: the shader writes scene-linear radiance times 2^exposure (the scene's Film/colour
management exposure); the viewport shows what a POST_VIEW handler draws with the sRGB curve
only, i.e. the Standard view transform, whatever the scene's view transform is.
"""

import logging

import numpy as np

from .. import background, methods, native, redraw
from ..scene import environment, light_sources, materials, transforms
from ..scene.view import View
from ..store import attributes, baked
from ..store.record import RecordError
from . import gpu_shading, ray_bvh, source_shadows, staleness
from .shader_variant import (BAND_LIMITED_TEXTURE_SAMPLER, PREFILTERED_SAMPLER, RAY_BVH_SAMPLER, REFLECTION_RAYS,
                             SHADOW_MAP_SAMPLER)

log = logging.getLogger(__name__)

DEPTH_BIAS = 2e-6     # clip-space pull towards the eye, so the overlay wins over Blender's own draw

_handler = None
_objects = {}         # object name -> (key, ObjectData)
_generations = ()     # the background work's generations the viewports last showed
_instances = (None, [])   # (key, baked_instances' result) of the last depsgraph looked through
last_error = ""
# Why the last interactive draw went without what the scene asks for (the panel shows it), or "":
# "sources": the bright sources shaded through SH; "rays": no reflection rays traced.
errors = {"sources": "", "rays": ""}


def clear_cache():
    global _instances
    _objects.clear()
    _instances = (None, [])
    source_shadows.clear_cache()
    ray_bvh.clear_cache()


def object_data(obj, per_pixel=False, vertex_target=False, band_limited_texture=False, prefiltered=False):
    """The GPU data of the object's bake (cached until the bake or the mode changes), or None."""
    mesh = baked.baked_mesh(obj)
    if mesh is None:
        return None
    key = (mesh.name, baked.mesh_record(mesh).bake_id, per_pixel, vertex_target, band_limited_texture, prefiltered)
    cache_key = (obj.name, vertex_target)
    cached = _objects.get(cache_key)
    if cached is not None and cached[0] == key:
        return cached[1]
    data = gpu_shading.ObjectData(mesh, per_pixel=per_pixel, vertex_target=vertex_target,
                                  band_limited_texture=band_limited_texture, prefiltered=prefiltered)
    _objects[cache_key] = (key, data)
    return data


def baked_objects(scene, view_layer=None):
    """Visible objects with a bake whose record can be read and which fits their evaluated mesh
    (staleness.py); the panel says to bake the others again. view_layer: an evaluated one (default:
    the context's)."""
    import bpy
    depsgraph = (view_layer or bpy.context.view_layer).depsgraph
    out = []
    for obj in scene.objects:
        try:
            visible = obj.visible_get(view_layer=view_layer) if view_layer else obj.visible_get()
        except (RuntimeError, TypeError):
            visible = False
        if visible and _readable(obj) and not staleness.stale(obj, depsgraph):
            out.append(obj)
    return out


def _instances_something(scene):
    """Whether some object of the scene instances others (collections, vertices or faces, particles,
    geometry nodes): only then are the depsgraph's instances looked through."""
    return any(obj.is_instancer or len(obj.particle_systems) or any(m.type == 'NODES' for m in obj.modifiers)
               for obj in scene.objects)


def baked_instances(scene, objects, view_layer=None):
    """(object, world matrix) of each instance of one of `objects` (baked_objects: drawn, fresh) that
    the depsgraph makes - in a collection instance, on vertices or faces, from particles or
    geometry nodes' Object Info - to draw its bake there."""
    import bpy
    global _instances
    if not objects:
        return []
    drawn = {obj.name_full: obj for obj in objects}
    key = (staleness.generation, scene.name_full, tuple(sorted(drawn)))
    if _instances[0] == key:   # the same depsgraph as the last draw: the same instances
        return _instances[1]
    out = []
    instances = (view_layer or bpy.context.view_layer).depsgraph.object_instances if _instances_something(scene) else ()
    for instance in instances:
        if not instance.is_instance:
            continue
        original = instance.object.original
        if original.name_full in drawn and original != instance.parent.original:
            out.append((drawn[original.name_full], instance.matrix_world.copy()))
    _instances = (key, out)
    return out


def placed_elsewhere(scene, view_layer=None):
    """What is drawn elsewhere than its bake was made while other objects occluded it
    (store.baked.placed_elsewhere), for the preview's report: ["Ball", "2 instances of Box", ...]."""
    objects = baked_objects(scene, view_layer)
    out = [obj.name for obj in objects if baked.placed_elsewhere(obj)]
    counts = {}
    for obj, matrix in baked_instances(scene, objects, view_layer):
        if baked.placed_elsewhere(obj, matrix):
            counts[obj.name] = counts.get(obj.name, 0) + 1
    return out + ["%d instance%s of %s" % (n, "" if n == 1 else "s", name) for name, n in sorted(counts.items())]


def _readable(obj):
    try:
        return baked.record(obj) is not None
    except RecordError:
        return False


def ringing_setting(scene):
    """The scene's ringing window setting, as scene/ringing.WINDOWS names it."""
    settings = getattr(scene, "sd_lighting", None)
    return settings.ringing_window.lower() if settings is not None else "automatic"


def shading_light(scene, source, lobe_set, order, wait, remainder=False):
    """The unrotated L of order s the live shading uses for a bake's lobes (scene/lobes.Lobes):
    windowed against ringing with the scene's setting for the lobe its SH shows
    (Lobes.window_lobe; environment.windowed_light; wait=False: without a window until it is
    chosen); remainder: of the map without the bright sources that light the object on their own
    (source_lighting). [(s+1)^2, 3] float64."""
    return environment.windowed_light(source, *lobe_set.window_lobe(use_prefiltered_glossy(scene)), order,
                                      ringing_setting(scene), wait, remainder)


def ringing_choice(scene, obj, wait=False):
    """The ringing window the live shading uses for the object's bake (its choice dict), or None
    without a bake or (wait=False) while it is chosen. Raises environment.Unavailable without an
    environment."""
    record = baked.record(obj)
    if record is None:
        return None
    source = environment.source(scene)
    try:   # the remainder's window where the sources light the lobes on their own, once found
        glossy = record.lobes.prefiltered_glossy(use_prefiltered_glossy(scene))
        split = _shading_split(scene, source, wait=False) if gpu_shading.takes_sources(record, False, glossy) else None
        prefiltered = split is not None and glossy and environment.prefiltered_atlas(
            source, *gpu_shading.prefiltered_layout(), wait=False, remainder=True) is not None
        remainder = split is not None and gpu_shading.takes_sources(record, False, prefiltered)
    except background.Failed:
        remainder = False
    lobe, exponent = record.lobes.window_lobe(use_prefiltered_glossy(scene))
    return environment.ringing_window(source, lobe, exponent, record.light_order,
                                      ringing_setting(scene), wait, remainder=remainder)


def _shading_split(scene, source, wait):
    """environment.source_split's split where the scene's bright sources light the lobes that take
    them on their own (Sharp Source Shadows on, the map has some), else None (also while being found,
    wait=False)."""
    settings = getattr(scene, "sd_lighting", None)
    if settings is None or not settings.source_shadows:
        return None
    split = environment.source_split(source, wait)
    return split if split and split["sources"] else None


def local_light(scene, obj, data, wait, source=None, rotation=None, matrix=None, remainder=False):
    """Coefficients of x -> L(g R x) for the object's data (ObjectData) drawn with `matrix` (default:
    its own world matrix), windowed (shading_light; remainder: as there): [(s+1)^2, 3] float64;
    and g R."""
    source = source or environment.source(scene)
    g = environment.rotation_matrix(scene) if rotation is None else rotation
    gr = g @ transforms.rotation_part(np.array(obj.matrix_world if matrix is None else matrix))
    light = shading_light(scene, source, data.lobes, data.light_order, wait, remainder)
    return native.get().rotated_environment_sh(light, gr), gr


def use_band_limited_texture(scene):
    """The scene's option: methods that can look L~ up in the band-limited texture do."""
    settings = getattr(scene, "sd_lighting", None)
    return bool(settings is not None and settings.band_limited_texture)


def use_prefiltered_glossy(scene):
    """The scene's option: glossy Principled lobes are lit by the prefiltered environment."""
    settings = getattr(scene, "sd_lighting", None)
    return bool(settings is None or settings.prefiltered_glossy)


def use_reflection_rays(scene):
    """The scene's option: the prefiltered glossy lobes and specular layers trace their visibility
    per pixel."""
    settings = getattr(scene, "sd_lighting", None)
    return bool(settings is None or settings.reflection_rays)


def reflection_ray_count(scene):
    """The scene's rays per pixel of a traced lobe (shader_variant.REFLECTION_RAYS where it has no
    settings)."""
    settings = getattr(scene, "sd_lighting", None)
    return REFLECTION_RAYS if settings is None else int(settings.reflection_ray_count)


def reflection_rays(scene, wait, view_layer=None):
    """The scene's ray BVH (ray_bvh.scene_bvh), or None where building it failed (errors["rays"]
    says why; wait=True raises): the glossy lobes and layers keep the baked visibility ratio."""
    import bpy
    view_layer = view_layer or bpy.context.view_layer
    return _unless_failed("rays", "the glossy lobes keep the baked visibility", wait,
                          lambda: ray_bvh.scene_bvh(scene, view_layer.depsgraph, view_layer))


def _unless_failed(what, instead, wait, work):
    """work(), or None where it raises: wait=True raises it on; else errors[what] keeps why, and it
    is logged once, saying what is drawn `instead`."""
    try:
        result = work()
    except Exception as exc:
        if wait:
            raise
        message = "%s: %s" % (type(exc).__name__, exc)
        if message != errors[what]:
            log.error("%s: %s", instead, message)
        errors[what] = message
        return None
    errors[what] = ""
    return result


def _frame(scene, obj, data, view, scale, wait, source=None, rotation=None, matrix=None, sources=None, rays=None,
           **kwargs):
    """(uniform block, {sampler: texture} of the environment textures it reads) of one draw of the
    object's data with `matrix` (default: its world matrix; an instance's). wait: as
    shading_light; without waiting, what is still pending is watched (watch_background).
    sources: source_lighting's, for data that takes them (ObjectData.takes_sources), or None.
    rays: the scene's ray BVH (ray_bvh.scene_bvh) for data whose glossy lobe traces its
    visibility, or None.
    The sources' shadow rows are made relative to the object's origin here, in float64 (the
    shader has the pixel's position relative to it)."""
    matrix = np.array(obj.matrix_world if matrix is None else matrix)
    source = source or environment.source(scene)
    prefiltered = None
    if data.prefiltered:
        # the remainder's atlas where the sources light the glossy lobe on their own; while it is
        # made, the whole map's without them
        prefiltered = gpu_shading.prefiltered_texture(source, wait, sources is not None and data.takes_sources(True))
        if prefiltered is None and sources is not None:
            prefiltered, sources = gpu_shading.prefiltered_texture(source, wait), None
    sources = sources if data.takes_sources(prefiltered is not None) else None
    remainder = sources is not None
    light, gr = local_light(scene, obj, data, wait, source, rotation, matrix, remainder)
    textures = {}
    if data.uses_band_limited_texture:
        textures[BAND_LIMITED_TEXTURE_SAMPLER[1]], kwargs["band_limited_scale"] = gpu_shading.band_limited_texture(
            source, shading_light(scene, source, data.lobes, data.light_order, wait, remainder))
    if sources is not None:
        kwargs["sources"] = (sources[0], light_sources.rows_from(sources[2], matrix[:3, 3]))
        textures[SHADOW_MAP_SAMPLER[1]] = sources[1]
    if rays is not None:
        kwargs["rays"] = ray_bvh.block_rows(rays, matrix, data.radius)
        kwargs["ray_count"] = reflection_ray_count(scene)
        textures[RAY_BVH_SAMPLER[1]] = rays[0]
    block = data.frame_block(matrix, view.view_projection, view.camera, light, gr, scale,
                             albedos=materials.object_albedos(obj), prefiltered=prefiltered is not None,
                             strength=source.strength, **kwargs)
    if data.variant.prefiltered_lookup:
        textures[PREFILTERED_SAMPLER[1]] = prefiltered
    if not wait:
        watch_background()
    return block, textures


def exposure_scale(scene):
    return 2.0 ** float(scene.view_settings.exposure)


def source_lighting(scene, source, g, wait, view_layer=None):
    """(scene/light_sources.Source list, their shadow maps' texture, the maps' shader rows) of the
    map's bright sources that light objects on their own (the scene's Sharp Source Shadows;
    gpu_shading.takes_sources says which), or None: the option is off, the map has none, or
    (wait=False) they are still being found (the whole map through SH meanwhile), or their search
    or their shadow maps failed (the whole map through SH; errors["sources"] says why; wait=True
    raises). The maps are rendered now when the sources or the casters changed (source_shadows.py)."""
    import bpy

    def work():
        split = _shading_split(scene, source, wait)
        if split is None:
            return None
        layer = view_layer or bpy.context.view_layer
        texture, rows = source_shadows.shadow_maps(split["sources"], g, scene, layer.depsgraph, layer)
        return split["sources"], texture, rows

    return _unless_failed("sources", "the bright sources are shaded through SH", wait, work)


def draw_objects(scene, objects, view, scale, per_pixel=False, depth_bias=0.0, wait=False, instances=(),
                 view_layer=None):
    """Draws the baked objects, and the instances (baked_instances: (object, matrix)) of them, into
    the bound framebuffer with the current GPU state. per_pixel: every object per pixel (the
    panel's Per Pixel), else those whose automatic choice says so. wait=False (the interactive
    draw) shades with no ringing window until it is chosen; True waits for it. view_layer: an
    evaluated one whose visible geometry casts the sources' shadows (default: the context's)."""
    source = environment.source(scene)
    g = environment.rotation_matrix(scene)
    band_limited_texture = use_band_limited_texture(scene)
    prefiltered = use_prefiltered_glossy(scene)
    sources = source_lighting(scene, source, g, wait, view_layer) if objects or instances else None
    traced = prefiltered and use_reflection_rays(scene)
    rays = []   # the ray BVH, built when the first object that traces is drawn
    for obj, matrix in [(obj, None) for obj in objects] + list(instances):
        record = baked.record(obj)
        data = object_data(obj, per_pixel=per_pixel or bool(record and record.per_pixel),
                           band_limited_texture=band_limited_texture, prefiltered=prefiltered)
        if data is None:
            continue
        if traced and data.traces_reflections and not rays:
            rays.append(reflection_rays(scene, wait, view_layer))
        block, textures = _frame(scene, obj, data, view, scale, wait, source, g, matrix, sources,
                                 rays[0] if rays and data.traces_reflections else None, depth_bias=depth_bias)
        data.draw(block, textures)


def draw_background(scene, view, scale):
    """The scene's environment behind what is drawn (the World Background option): L(g d) in the
    direction d of each empty pixel, g the environment rotation, times scale."""
    gpu_shading.draw_background(environment.source(scene), view, environment.rotation_matrix(scene), scale)


def _background_work():
    """What the draw and the panel ask worker threads for: the lobe designs, the ringing window
    choices, the prefiltered environments and the maps' bright sources."""
    return (gpu_shading.lobe_designs(), environment.window_choices(), environment.prefiltered_atlases(),
            environment.bright_source_searches())


def _poll_background():
    """Timer while background work is pending: redraws the viewports (and the panel's status)
    when some of it is done; ends when none is pending."""
    global _generations
    work = _background_work()
    generations = tuple(w.generation for w in work)
    if generations != _generations:
        _generations = generations
        redraw.viewports()
    return 0.25 if any(w.pending() for w in work) else None


def watch_background():
    """Redraws the viewports and the panel once what is asked of the worker threads is done."""
    import bpy
    if any(w.pending() for w in _background_work()) and not bpy.app.timers.is_registered(_poll_background):
        bpy.app.timers.register(_poll_background, first_interval=0.25)


def _draw_handler():
    global last_error
    import bpy
    import gpu
    context = bpy.context
    scene = context.scene
    settings = getattr(scene, "sd_lighting", None)
    if settings is None or not settings.live_shading or context.region_data is None:
        return
    try:
        with baked.records_once():
            objects = baked_objects(scene, context.view_layer)
            if not objects and not settings.world_background:
                return
            view = View.from_region(context.region_data)
            gpu.state.depth_test_set('LESS_EQUAL')
            gpu.state.depth_mask_set(True)
            gpu.state.blend_set('NONE')
            draw_objects(scene, objects, view, exposure_scale(scene), settings.per_pixel, DEPTH_BIAS,
                         instances=baked_instances(scene, objects, context.view_layer), view_layer=context.view_layer)
            if settings.world_background:
                draw_background(scene, view, exposure_scale(scene))
        gpu.state.depth_mask_set(False)
        gpu.state.depth_test_set('NONE')
        last_error = ""
    except Exception as exc:  # never raise into Blender's draw loop; the panel shows it
        message = "%s: %s" % (type(exc).__name__, exc)
        if message != last_error:
            log.error("live shading failed: %s", message)
        last_error = message


# --------------------------------------------------------------------------------------------
# Checks against the CPU evaluator (for the tests)

def cpu_reference(scene, obj, view, texels=False):
    """B at every vertex of the object's bake by sdnative.shade (float64), for the same view,
    environment (windowed against ringing: waits for the window's choice) and rotation the live
    shading uses, clamped at 0 per channel as the shader shows it (displayed radiance is never
    negative; sdnative.shade itself is the raw formula); with a Lambert lobe besides the Phong one,
    the sum of the two, as the shader's vertex target shows it; exposure not applied. [N, 3].
    texels: at every texel its texture-space data store instead (each with its own normal and
    view), in the order of attributes.read_texels_entries. [K, 3]."""
    mesh = baked.baked_mesh(obj)
    record = baked.mesh_record(mesh)
    method = methods.get(record.method)
    if texels:
        mesh = baked.lightmap_mesh(mesh)
        if mesh is None:
            raise ValueError("%s's bake has no texture-space data" % obj.name)
    data = attributes.read(mesh, record)
    data["visibility_order"] = record.visibility_order
    matrix = np.array(obj.matrix_world, dtype=np.float64)
    world = transforms.transform_points(matrix, attributes.read_positions(mesh))
    source = environment.source(scene)
    light = shading_light(scene, source, record.lobes, record.light_order, True)
    g = environment.rotation_matrix(scene)
    r = transforms.rotation_part(matrix)
    kwargs = {key: data[key] for key in method.shade_inputs}
    return sum(np.maximum(native.get().shade(method.id, light, data["normals"],
                                             views=view.view_directions(world, r.T), rotation=g @ r,
                                             lobe=lobe, exponent=exponent, **kwargs), 0.0)
               for lobe, exponent in record.lobes.shaded())


def gpu_vertex_values(scene, obj, view, per_pixel=False, wait=True):
    """B at every vertex as the shader computes it (exposure not applied): each vertex is drawn
    as one pixel of an RGBA32F target and read back. wait: as draw_objects (True: with the ringing
    window cpu_reference uses; False: as the interactive draw). Needs a GPU context. [N, 3]
    float32."""
    import gpu
    data = object_data(obj, per_pixel=per_pixel, vertex_target=True,
                       band_limited_texture=use_band_limited_texture(scene))
    n = data.vertex_count
    width = min(n, 1024)
    height = (n + width - 1) // width
    block, textures = _frame(scene, obj, data, view, 1.0, wait, target=(width, height))
    offscreen = gpu.types.GPUOffScreen(width, height, format='RGBA32F')
    try:
        values = draw_offscreen(offscreen, lambda: data.draw(block, textures), depth_test=False)
    finally:
        offscreen.free()
    return values.reshape(-1, 4)[:n, :3]


def draw_offscreen(offscreen, draw, depth_test=True, region=None):
    """Clears the offscreen target (colour 0, depth 1), calls draw() into it - depth-tested
    (LESS_EQUAL, written) or not, no blending, no culling - and reads back the region
    (x, y, width, height; default: all) as float32 [height, width, 4], rows bottom-first."""
    import gpu
    x, y, width, height = region or (0, 0, offscreen.width, offscreen.height)
    with offscreen.bind():
        framebuffer = gpu.state.active_framebuffer_get()
        framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
        gpu.state.depth_test_set('LESS_EQUAL' if depth_test else 'NONE')
        gpu.state.depth_mask_set(depth_test)
        gpu.state.blend_set('NONE')
        gpu.state.face_culling_set('NONE')
        gpu.state.point_size_set(1.0)
        draw()
        pixels = framebuffer.read_color(x, y, width, height, 4, 0, 'FLOAT')
        gpu.state.depth_mask_set(False)
        gpu.state.depth_test_set('NONE')
    pixels.dimensions = width * height * 4
    return np.array(pixels, dtype=np.float32).reshape(height, width, 4)


def register():
    global _handler
    import bpy
    if _handler is None:
        _handler = bpy.types.SpaceView3D.draw_handler_add(_draw_handler, (), 'WINDOW', 'POST_VIEW')


def unregister():
    global _handler
    import bpy
    if _handler is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handler, 'WINDOW')
        _handler = None
    if bpy.app.timers.is_registered(_poll_background):
        bpy.app.timers.unregister(_poll_background)
    clear_cache()
