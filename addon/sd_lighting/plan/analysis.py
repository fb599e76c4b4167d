"""The automatic mode in a bake: what `bake/prepare.py` gathers on the main thread for each object's
measurement (plan/accuracy.ErrorTable), and the choice (plan/automatic.choose) made in the bake's
worker before the object is baked with it. The worker touches no bpy: the environment is read and
cached by prepare, and the light of each order comes from environment.py's caches."""

import os
from dataclasses import dataclass, field

import numpy as np

from .. import background, methods, native
from ..scene import environment, lobes
from . import accuracy, automatic, bake_time, cost

AUTOMATIC = "automatic"     # the scene's and an object's method setting for the automatic mode
MEASURED_RAYS = 256         # rays per vertex of the measurement (the error at others follows)


@dataclass
class Inputs:
    """One object's measurement inputs (main thread), in its bake space."""
    environment: object          # sdnative.Environment
    light: object                # order -> unrotated L of that order, as the live shading uses it
    rotation: np.ndarray         # g R
    eye: object                  # the camera's position in the bake space, or None
    target_error: float
    max_order: int
    fixed: dict = field(default_factory=dict)   # the object's overrides (automatic.choose)
    triangle_pixels: object = None   # its triangles' mean area on screen (None: no camera)
    remainder: object = None     # accuracy.Remainder where the map's bright sources may be shaded
                                 # on their own, else None
    prefiltered: bool = False    # the scene's Prefiltered Glossy (glossy lobes measured as drawn)
    traced: bool = False         # and its Reflection Rays (their visibility traced when drawn)


def gather(src, lobe_set, rotation, eye, target_error, max_order, fixed, ringing_setting,
           triangle_pixels, sources=False, prefiltered=False, traced=False):
    """Inputs for an object: src an environment.Source, lobe_set its scene/lobes.Lobes (L is
    windowed as the live shading windows it, Lobes.window_lobe), rotation g R, eye in the bake space;
    sources: whether the map's bright sources may be shaded on their own (the scene's Sharp Source
    Shadows): for a Lambert lobe with sources in the map, or a glossy one the prefiltered light
    draws where every source is a highlight of its own (a sun; the atlas holds the wider ones,
    whose reflection the measurement would take as exact: a steel spider under studio.exr's
    softboxes was then chosen unshadowed, 21.5 % off Cycles against 16.4 %), the measurement then
    weighs them (accuracy.Remainder; found here, on the main thread, when not yet); prefiltered:
    the scene's Prefiltered Glossy; traced: its Reflection Rays."""
    if src.kind == "uniform":
        pixels = np.broadcast_to(np.asarray(src.colour, dtype=np.float32), (2, 4, 3)).copy()
        env = native.get().environment_from_pixels(pixels)

        def light(order):
            return np.asarray(env.sh(order), dtype=np.float64).reshape(-1, 3)
    else:
        env = environment.environment(src)
        scale = 1.0 / src.strength if src.strength > 0.0 else 0.0

        def light(order, remainder=False):   # the reference reads the map without the strength: so does this
            return scale * environment.windowed_light(src, *lobe_set.window_lobe(prefiltered), order,
                                                      ringing_setting, True, remainder)
    remainder = None
    glossy = lobe_set.prefiltered_glossy(prefiltered)
    if sources and src.kind != "uniform" and (lobe_set.lobe == "lambert" or glossy):
        try:
            split = environment.source_split(src, wait=True)
        except background.Failed:   # the draw shades them through SH then (and the panel says why)
            split = {"sources": []}
        if split["sources"] and (not glossy or all(source.highlight for source in split["sources"])):
            remainder = accuracy.Remainder(split["remainder"], lambda order: light(order, remainder=True))
    max_order = max(int(max_order), int(fixed.get("light_order", 0)))
    return Inputs(env, light, rotation, eye, float(target_error), max_order, dict(fixed),
                  triangle_pixels, remainder, bool(prefiltered), bool(prefiltered and traced))


def _table(inputs, geometry, occluders, lobe_set, method_ids, max_order, rays, stop, progress=None):
    """The ErrorTable of the object's sample (also measured with the bright sources on their own,
    where inputs.remainder has them)."""
    eye = inputs.eye

    def views(points):
        if eye is None:
            return None
        towards = eye[None, :] - points
        return towards / np.maximum(np.linalg.norm(towards, axis=1, keepdims=True), 1e-300)

    sample = accuracy.Sample.of_mesh(geometry.vertices, geometry.normals, geometry.triangles,
                                     occluders, views)
    return accuracy.ErrorTable(native.get(), sample, inputs.environment, inputs.light, lobe_set.lobe,
                               lobe_set.exponent, inputs.rotation, method_ids, max_order, rays,
                               stop=stop, diffuse_share=lobe_set.diffuse_share, progress=progress,
                               remainder=inputs.remainder,
                               prefiltered=lobe_set.prefiltered_glossy(inputs.prefiltered),
                               traced=inputs.traced)


def choose(inputs, geometry, occluders, lobe_set, stop, fitted=False, texels=0, progress=None,
           bake_budget=bake_time.CONFIRM_SECONDS):
    """The automatic.Choice for one object (any thread): geometry a bake/geometry.Geometry, occluders
    bake_transfer's occluder keywords (or {}), lobe_set its scene/lobes.Lobes, fitted: whether the
    bake fits least squares (its rays then start at the face centres too); texels: the texels a
    texture-space bake adds for the methods they hold (which then fit no least squares);
    bake_budget: the seconds its rays may take (its share of the selection's, plan/budget.py);
    stop() True cancels (InterruptedError)."""
    sd = native.get()
    table = _table(inputs, geometry, occluders, lobe_set, [m.id for m in methods.METHODS],
                   inputs.max_order, int(inputs.fixed.get("rays", MEASURED_RAYS)), stop, progress)
    return automatic.choose(table, inputs.target_error, lambda s, sv: cost.gaunt_terms(sd, s, sv),
                            len(geometry.vertices), os.cpu_count() or 1, bake_budget,
                            inputs.fixed,
                            len(geometry.vertices) + texels if texels else
                            len(geometry.vertices) + len(geometry.triangles) if fitted else None)


def predict(inputs, geometry, occluders, settings, stop):
    """The predicted relative RMS error of a bake's chosen settings (its `sd_bake` dict; any
    thread), measured as the automatic mode measures every setting (with the bright sources on their
    own where the draw takes them)."""
    setting = accuracy.Setting(settings["method"], int(settings["light_order"]),
                               int(settings["visibility_order"]), int(settings["rays"]))
    table = _table(inputs, geometry, occluders, lobes.Lobes.of_bake(settings), [setting.method],
                   setting.light_order, setting.rays, stop)
    # None (a method picked, or none measured): the draw takes the sources where the map has them
    return table.error(setting, settings.get("sources") is not False and table.measured_sources is not None)
