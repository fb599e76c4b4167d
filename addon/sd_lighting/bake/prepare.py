"""What to bake (main thread): for every selected object that can be baked, its Geometry, its
occluders and its settings as BakeTasks; nothing in the .blend changes."""

import time

import numpy as np

from .. import methods, native
from ..errors import BakeError
from ..plan import analysis, automatic, budget
from ..scene import environment, lobes, materials, transforms
from ..scene.view import View
from ..store import baked
from ..store.record import RecordError
from . import geometry as geometry_module, lightmap
from .task import BakeTask
from .unwrap import lightmap_uvs


def bake_settings(scene, obj, env_source):
    """The settings dict of a bake of `obj` under the scene's panel settings and the object's
    overrides (properties.ObjectOverrides). The automatic mode's dict says method "automatic":
    the bake's worker fills in the choice (analysis.choose), with the lines saying why."""
    settings = scene.sd_lighting
    fixed = obj.sd_lighting.fixed() if hasattr(obj, "sd_lighting") else {}
    method_id = fixed.get("method", settings.method)
    lobe_set = materials.lobe_for(obj, settings)
    lobe, exponent = lobe_set.lobe, lobe_set.exponent
    common = {"lobe": lobe, "exponent": float(exponent), "diffuse_lobe": lobe_set.diffuse,
              "lobe_weights": lobe_set.weighted, "diffuse_share": lobe_set.diffuse_share,
              "seed": int(settings.seed),
              "environment": env_source.description, "refine": bool(settings.refine),
              "refine_target": float(settings.target_error),
              "refine_max_vertices": int(settings.refine_max_vertices),
              "least_squares": bool(settings.least_squares),
              "lightmap": int(settings.lightmap_size) if settings.texture_space else 0}
    if method_id == analysis.AUTOMATIC:
        return dict(common, method=analysis.AUTOMATIC, light_order=0, visibility_order=0,
                    rays=int(fixed.get("rays", settings.rays)))
    method = methods.get(method_id)
    if method.lambert_only and lobe != "lambert":
        raise BakeError("%s needs a Lambert material; %s is %s"
                        % (method.label, obj.name, lobe_set.label))
    if "light_order" in fixed:
        order = fixed["light_order"]
    elif settings.automatic_orders:
        try:
            order = environment.smallest_order(env_source, lobe, exponent, settings.target_error,
                                               settings.max_automatic_order)
        except Exception as exc:
            raise BakeError("cannot choose s automatically: %s" % exc) from exc
    else:
        order = settings.light_order
    v_order = fixed.get("visibility_order", settings.visibility_order) if method.uses_visibility_order else 0
    return dict(common, method=method.id, light_order=int(order), visibility_order=int(v_order),
                rays=int(fixed.get("rays", settings.rays)))


def _analysis_inputs(scene, obj, geometry, env_source, settings, to_bake_space, depsgraph):
    """What the object's error is measured with (analysis.Inputs), in its bake space."""
    matrix = np.array(obj.matrix_world, dtype=np.float64)
    rotation = environment.rotation_matrix(scene) @ transforms.rotation_part(matrix)
    eye = triangle_pixels = None
    if scene.camera is not None:
        eye = transforms.transform_points(to_bake_space, np.array([scene.camera.matrix_world.translation]))[0]
        render = scene.render
        width = render.resolution_x * render.resolution_percentage // 100
        height = render.resolution_y * render.resolution_percentage // 100
        if settings["method"] == analysis.AUTOMATIC:   # only its choice reads the mesh on screen
            view = View.from_camera(scene.camera, depsgraph, width, height, scene)
            triangle_pixels = automatic.projected_triangle_pixels(
                transforms.transform_points(matrix, geometry.mesh_positions), geometry.mesh_triangles,
                view.view_projection, width, height)
    fixed = obj.sd_lighting.fixed() if hasattr(obj, "sd_lighting") else {}
    fixed.pop("method", None)
    panel = scene.sd_lighting
    return analysis.gather(env_source, lobes.Lobes.of_bake(settings), rotation, eye,
                           panel.target_error, panel.max_automatic_order, fixed,
                           panel.ringing_window.lower(), triangle_pixels, panel.source_shadows,
                           panel.prefiltered_glossy, panel.reflection_rays)


def recorded_settings(scene, obj, env_source):
    """The settings the object's bake recorded - what it was asked for and, from the automatic
    mode, what was chosen - for a re-bake (not the panel's); BakeError without a bake."""
    try:
        record = baked.record(obj)
    except RecordError as exc:
        raise BakeError("%s: %s" % (obj.name, exc)) from exc
    if record is None:
        raise BakeError("%s has no bake" % obj.name)
    return record.settings()


def _refusal(obj):
    """Why the object cannot be baked (a message for the user), or None."""
    if obj.type != 'MESH':
        return "%s is not a mesh (%s)" % (obj.name, obj.type.lower())
    if obj.library is not None:
        return ("%s is linked from %s, which keeps no change made here: make it local (Object > "
                "Relations > Make Local) to bake it" % (obj.name, obj.library.filepath))
    if obj.override_library is not None:
        return ("%s is a library override, whose bake Blender would drop when the file is "
                "reopened: make it local to bake it" % obj.name)
    return None


def _may_bake_lightmap(method_id):
    """Whether a bake of this method (or the automatic mode's choice) may hold texels."""
    return method_id == analysis.AUTOMATIC or lightmap.applies(methods.get(method_id))


def unwrap_lightmap(context, task):
    """Gives a task whose settings ask for texture-space data its lightmap UVs (lightmap_uvs;
    main thread, BakeError as there); nothing for the others."""
    settings = task.settings
    if int(settings.get("lightmap", 0)) > 0 and _may_bake_lightmap(settings["method"]):
        start = time.perf_counter()
        task.geometry.lightmap_uvs = lightmap_uvs(context, task.geometry, int(settings["lightmap"]))
        task.geometry.unwrap_seconds = time.perf_counter() - start


def prepare(context, objects, rebake=False, unwrap=True):
    """What to bake (main thread): (BakeTasks, warnings). Objects that cannot be baked (not
    meshes, without faces, linked from a library) are left out, each with a warning; raises
    BakeError when none is left or the bake cannot start (no sdnative, no environment).
    rebake: each object is baked as its last bake was (recorded_settings, its share of the
    selection's budget included), not with the panel's settings shared out over `objects`
    (bake_settings, budget.shares). unwrap: False leaves texture-space
    bakes without their UVs (unwrap_lightmap: the bake-time prediction estimates the texels
    instead; a live re-bake unwraps only what it bakes)."""
    scene = context.scene
    settings_of = recorded_settings if rebake else bake_settings
    depsgraph = context.evaluated_depsgraph_get()
    view_layer = context.view_layer
    if not native.available():
        raise BakeError(native.error_message())
    try:
        env_source = environment.source(scene, render=True)
        if env_source.kind != "uniform":
            environment.environment(env_source)  # an unreadable file fails now, not at every frame
    except environment.Unavailable as exc:
        raise BakeError(str(exc)) from exc

    # Everything visible occludes, instances of objects (and of the object itself) included.
    parts = geometry_module.scene_parts(depsgraph, view_layer)

    def occluders_of(obj):
        return ((part.vertices, part.triangles) for part in parts
                if part.instance or part.name != obj.name_full)

    boxes = [(part, part.vertices.min(axis=0), part.vertices.max(axis=0)) for part in parts if len(part.vertices)]

    def surrounded(obj, world_positions):
        """Whether another object's box comes within the object's size of its box: the
        surroundings can shadow it (a lone object high above everything: no)."""
        lo, hi = world_positions.min(axis=0), world_positions.max(axis=0)
        reach = np.linalg.norm(hi - lo)
        return any(np.all(b_lo <= hi + reach) and np.all(b_hi >= lo - reach)
                   for part, b_lo, b_hi in boxes if part.instance or part.name != obj.name_full)

    tasks, skipped, areas = [], [], []
    for obj in objects:
        reason = _refusal(obj)
        if reason is None:
            placement = np.array(obj.evaluated_get(depsgraph).matrix_world)
            shape, to_bake_space = transforms.bake_space(placement)
            if np.linalg.matrix_rank(shape) < 3:
                reason = "%s has a zero scale" % obj.name
        if reason is None:
            geometry = geometry_module.evaluated_geometry(obj, depsgraph, shape)
            if geometry is None or geometry.triangle_count == 0:
                reason = "%s has no faces" % obj.name
        if reason is not None:
            skipped.append(reason)
            continue
        occluders = geometry_module.join((transforms.transform_points(to_bake_space, world), faces)
                                         for world, faces in occluders_of(obj))
        geometry.occluders = occluders
        geometry.backs = not materials.culls_back_faces(obj)
        settings = settings_of(scene, obj, env_source)
        settings["shape"] = [float(x) for x in shape.ravel()]
        settings["placement"] = [float(x) for x in placement.ravel()]
        inputs = _analysis_inputs(scene, obj, geometry, env_source, settings, to_bake_space, depsgraph)
        share_key = None
        if settings["method"] == analysis.AUTOMATIC:   # what the choice depends on (task.SharedChoices)
            lobe = tuple(settings[k] for k in ("lobe", "exponent", "diffuse_lobe", "lobe_weights", "diffuse_share"))
            share_key = (geometry.source, geometry.backs, np.round(inputs.rotation, 6).tobytes(),
                         np.round(shape, 6).tobytes(), lobe, tuple(sorted(inputs.fixed.items())),
                         surrounded(obj, transforms.transform_points(placement, geometry.mesh_positions)),
                         None if lobe[0] == "lambert" or inputs.eye is None else tuple(np.round(inputs.eye, 6)))
        tasks.append(BakeTask(obj.name, geometry, occluders, settings, inputs, share_key))
        areas.append(budget.surface_area(transforms.transform_points(placement, geometry.mesh_positions),
                                         geometry.mesh_triangles))
        if unwrap:
            unwrap_lightmap(context, tasks[-1])
    if not tasks:
        raise BakeError("nothing to bake: " + "; ".join(skipped) if skipped else
                        "select one or more mesh objects to bake")
    if not rebake:
        selection_vertices = int(scene.sd_lighting.refine_max_vertices)
        seconds = budget.selection_seconds(sum(task.budget_points() for task in tasks))
        for task, share in zip(tasks, budget.shares(areas)):
            task.settings.update(refine_max_vertices=max(int(share * selection_vertices), 1),
                                 bake_seconds_budget=float(share * seconds))
    warnings = ["skipped: " + reason for reason in skipped]
    if env_source.kind == "uniform":
        warnings.append("world '%s' has no Environment Texture: lit by its %s"
                        % (scene.world.name, env_source.description))
    return tasks, warnings

