"""The predicted bake time of the panel's settings and selection (plan/bake_time.py), for the
panel and the bake operator's confirmation.

A prediction is kept per settings key (the panel's bake settings, the environment and the selected
meshes with their sizes). The panel only asks for it: the bake's inputs are gathered by
bake/prepare.py in a timer (never in a draw), and the sample bakes run in a worker thread.
"""

import os
import time

from .. import methods, native, redraw
from ..bake import geometry as geometry_module, job as job_module, least_squares, lightmap, prepare
from ..bake import task as task_module
from ..errors import BakeError
from ..plan import analysis, bake_time, cost
from ..scene import environment
from ..store.record import BakeRecord

CHECKED_VERTICES = 20_000   # a script's bake of more mesh vertices waits for its predicted time
_predictors = {}          # settings key -> BakeTimePredictor (the latest few)
_KEPT = 8
_requested = None         # the key a timer will start, if any


def settings_key(context):
    """What the bake's time depends on: the bake settings, the environment (automatic s) and the
    selected meshes (names, sizes and overrides); None without a selected mesh."""
    scene = context.scene
    settings = scene.sd_lighting
    meshes = tuple(sorted((o.name, len(o.data.vertices), len(o.data.polygons), len(o.modifiers),
                           tuple(sorted(o.sd_lighting.fixed().items())))
                          for o in context.selected_objects if o.type == 'MESH'))
    if not meshes:
        return None
    names = ("method", "material_source", "phong_exponent", "automatic_orders", "target_error",
             "max_automatic_order", "light_order", "visibility_order", "rays", "environment_source",
             "environment_path", "least_squares", "texture_space", "lightmap_size", "refine",
             "refine_max_vertices")
    world = scene.world.name if scene.world is not None else ""
    try:   # the world's own image: another HDRI in its Environment Texture is another choice and refinement
        light = environment.source(scene).key
    except environment.Unavailable:
        light = None
    return tuple(getattr(settings, name) for name in names) + (world, light, meshes)


def sample_jobs(tasks):
    """The sampling jobs of prepare.prepare's tasks: each object's own mesh joins its occluders,
    so that a sampled triangle's vertices see the rest of the object. First, in the predictor's
    worker, an automatic task chooses its settings (its reasons are then in task.settings) and
    a chosen method's are measured: either way task.predicted_error, for the panel. Texels are
    baked like vertices: a texture-space bake counts its expected texels as vertices."""
    choices = task_module.SharedChoices()

    def arguments(task, stop):
        if task.automatic:
            choices.choose(task, stop)
        else:
            task.predict(stop)
        kwargs = task.bake_arguments()
        kwargs["occluder_vertices"], kwargs["occluder_triangles"] = geometry_module.join(
            [(task.geometry.vertices, task.geometry.triangles)] + task.occluder_parts())
        return kwargs

    def traced(task):
        """The mesh the bake traces (computed in the worker: the corner split, and with Least
        Squares on a method it fits, each triangle split at its centroid: bake/least_squares.py)."""
        geometry = task.geometry
        mesh = (geometry.vertices, geometry.normals, geometry.triangles)
        return least_squares.centroid_split(*mesh) if task.fits_least_squares else mesh

    def fit_seconds(task, sd, result, growth):
        if not task.fits_least_squares or len(task.geometry.vertices) * growth > least_squares.MAX_VERTICES:
            return 0.0   # the bake skips the fit over its limit
        return least_squares.predicted_seconds(sd, len(task.geometry.vertices) * growth,
                                               least_squares.channels(result))

    refinements = {}   # share key -> the first such task's estimate: copies refine alike

    def refinement(task, index, sd, stop):
        known = refinements.get(task.share_key) if task.share_key is not None else None
        if known is None:
            known = task.refinement_estimate(sd, stop, seed=index)
            if task.share_key is not None:
                refinements[task.share_key] = known
        task.predicted_refinement = known   # for its memory
        return known

    return [bake_time.SampleJob(lambda task=task: traced(task), lambda stop, task=task: arguments(task, stop), task,
                                lambda sd, result, growth, task=task: fit_seconds(task, sd, result, growth),
                                lambda task=task: lightmap.expected_texels(task.lightmap_size),
                                lambda sd, stop, task=task, index=index: refinement(task, index, sd, stop),
                                lambda task=task: (task.predicted_bytes(), task.object_name))
            for index, task in enumerate(tasks)]


def start(context):
    """Starts predicting the bake of the selection under the scene's settings (main thread);
    returns the predictor, or None when the bake could not start (the bake says why)."""
    key = settings_key(context)
    if key is None:
        return None
    predictor = _predictors.get(key)
    if predictor is not None:
        return predictor
    try:
        # skipped objects: the bake warns; texels: estimated, not unwrapped in a timer
        tasks, _ = prepare.prepare(context, context.selected_objects, unwrap=False)
    except BakeError:
        return None
    predictor = bake_time.BakeTimePredictor(native.get(), sample_jobs(tasks), os.cpu_count() or 1,
                                            cost.available_bytes)
    for old in list(_predictors)[:max(len(_predictors) - _KEPT + 1, 0)]:
        _predictors.pop(old).cancel()
    _predictors[key] = predictor
    predictor.start()
    return predictor


def for_confirmation(context, wait=3.0):
    """The prediction the bake operator asks with (main thread): waits up to `wait` seconds (None:
    until it is final) for the sample, less once a lower bound says that the bake takes over a
    minute (an estimate from the first round alone may still come down); None when unknown."""
    predictor = start(context)
    if predictor is None:
        return None
    deadline = time.perf_counter() + (float("inf") if wait is None else wait)
    while _sampling(predictor) and time.perf_counter() < deadline:
        predicted = predictor.prediction()
        if predicted is not None and predicted.lower_bound and predicted.needs_confirmation:
            break
        predictor.join(0.05)
    return predictor.prediction()


def memory(context):
    """(the object of the selection whose bake needs the most memory, its predicted peak bytes,
    the free bytes), or None when unknown (plan/cost.bake_bytes: before the choice, of the meshes
    as they are, grown as the refinement is predicted to grow them once it is)."""
    predictor = start(context)
    free = cost.available_bytes()
    if predictor is None or free is None or not predictor.jobs:
        return None
    needed, name = max((job.task.predicted_bytes(), job.task.object_name) for job in predictor.jobs)
    return name, needed, free


def refusal(context):
    """Why a script's bake of the selection must be told to go ahead (None: it may run): memory
    predicted over the free memory, or a time over CONFIRM_SECONDS - predicted by sampling only where
    the selection is large (CHECKED_VERTICES) or the method builds designs, so that small bakes
    start at once."""
    predicted_memory = memory(context)
    if predicted_memory is not None and predicted_memory[1] > predicted_memory[2]:
        return job_module.memory_refusal(*predicted_memory)
    predictor = start(context)
    if predictor is None:
        return None
    settings = context.scene.sd_lighting
    vertices = sum(len(job.task.geometry.mesh_positions) for job in predictor.jobs)
    designs = settings.method != analysis.AUTOMATIC and methods.get(settings.method).designs_per_vertex
    if vertices <= CHECKED_VERTICES and not designs:
        return None
    predicted = for_confirmation(context, wait=None)
    predicted_memory = memory(context)   # now with the refinement's predicted growth
    if predicted_memory is not None and predicted_memory[1] > predicted_memory[2]:
        return job_module.memory_refusal(*predicted_memory)
    if predicted is not None and predicted.needs_confirmation:
        return ("the bake is predicted to take %s, over %s: go_ahead=True bakes anyway"
                % (predicted.text(), bake_time.format_duration(bake_time.CONFIRM_SECONDS)))
    return None


def current(context):
    """The prediction for the panel's settings and selection, or None while unknown; asks a timer
    to start one when there is none (a panel's draw must not evaluate the depsgraph)."""
    global _requested
    import bpy
    key = settings_key(context)
    predictor = _predictors.get(key) if key is not None else None
    if predictor is None:
        if key is not None and _requested != key:
            _requested = key
            bpy.app.timers.register(_start_requested, first_interval=0.0)
        return None
    if _sampling(predictor) and not bpy.app.timers.is_registered(_redraw_while_sampling):
        bpy.app.timers.register(_redraw_while_sampling, first_interval=0.5)
    return predictor.prediction()


def predicted_errors(context):
    """[(object name, its task's settings as a BakeRecord, predicted error)] for the panel's
    selection, as the predictor has measured them (empty before)."""
    predictor = _predictors.get(settings_key(context))
    if predictor is None:
        return []
    return [(job.task.object_name, BakeRecord.from_dict(job.task.settings), job.task.predicted_error)
            for job in predictor.jobs if job.task.predicted_error is not None]


def automatic_choices(context):
    """{object name: (settings dict, predicted error)} of the automatic choices the prediction for
    the panel's settings and selection has made, for the bake to take over (the
    environment's rotation and the camera they were measured at may have changed since: what
    they change is small next to a second measurement's seconds)."""
    predictor = _predictors.get(settings_key(context))
    if predictor is None:
        return {}
    return {job.task.object_name: (dict(job.task.settings), job.task.predicted_error)
            for job in predictor.jobs if "automatic" in job.task.settings}


def _start_requested():
    global _requested
    import bpy
    _requested = None
    start(bpy.context)
    redraw.viewports('UI')


def _sampling(predictor):
    return not predictor.finished and predictor.error is None


def _redraw_while_sampling():
    redraw.viewports('UI')
    return 0.5 if any(_sampling(p) for p in _predictors.values()) else None


def error(context):
    """Why the prediction for the panel's settings failed, or None."""
    predictor = _predictors.get(settings_key(context))
    return predictor.error if predictor is not None else None


def stop_sampling():
    """Cancels and forgets the predictions still sampling: a bake about to start needs the cores."""
    for key in [k for k, p in _predictors.items() if _sampling(p)]:
        _predictors.pop(key).cancel()


def clear():
    """Cancels and forgets every prediction (unregister, a new file)."""
    import bpy
    global _requested
    for predictor in _predictors.values():
        predictor.cancel()
    _predictors.clear()
    _requested = None
    for timer in (_start_requested, _redraw_while_sampling):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)
