"""Work that must not freeze Blender: the lobe designs of MSD (12) and the predicted bake time.

Lobe designs: a bake with MSD (12) is drawn (each vertex as a pixel, the live shading's own
ObjectData and shader) while its lobe design's build is held back: the draw returns, shading with
the Gauss product rule, and agrees with sdnative.shade; the panel's status says the design builds.
Once the build is let go and done, the next draw uses the small design (fewer nodes, the same
result), stored on disk; a new session reads it from there without building.

Prediction: the panel shows a bake time for a 2562-vertex sphere (MSD 13, s = 4, s' = 2), printed
beside the bake's own time (a measurement, not a check: timings on a shared machine are noise); a
bake of hours (s = 12, s' = 4, 40962 vertices) asks at once and says it takes hours within a minute
- a minute of the predictor's own clock (FakeClock: plan/bake_time.py's `time`, advanced by the
test instead of waited for).
Run: xvfb-run -a blender --factory-startup --python-exit-code 1 --python blender_tests/test_background_builds.py -- --zip Z
"""

import os
import shutil
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402

TOLERANCE = 1e-3       # GPU float32 against sdnative.shade (test_gpu_matches_cpu)
SIGMA, S, SV = 20.0, 8, 2


class FakeClock:
    """The bake-time predictor's clock (plan/bake_time.py reads time.perf_counter() through its
    module's `time`): the real one plus `offset`, which the test advances instead of waiting."""

    def __init__(self):
        self.offset = 0.0

    def perf_counter(self):
        return time.perf_counter() + self.offset

    def __getattr__(self, name):
        return getattr(time, name)


class HeldNative:
    """sdnative whose lobe design builds (not the Gauss rule) wait until `release` is set."""

    def __init__(self, sd):
        self._sd = sd
        self.release = threading.Event()
        self.builds = 0

    def __getattr__(self, name):
        return getattr(self._sd, name)

    def zonal_design(self, lobe, exponent, degree, method="auto"):
        if method != "gauss":
            self.builds += 1
            self.release.wait(600)
        return self._sd.zonal_design(lobe, exponent, degree, method)

    def zonal_design_continued(self, *args):
        self.builds += 1
        self.release.wait(600)
        return self._sd.zonal_design_continued(*args)


def check_lobe_designs(checks, package, scene, ball, view, directory):
    drawing, gs = package.live.drawing, package.live.gpu_shading
    lobe_designs = package.live.lobe_designs
    sd = package.native.get()
    sdtest.bake_settings(scene, "msd_lobe", "PHONG", S, SV, rays=128, phong_exponent=SIGMA, select=[ball])
    if not checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake MSD (12)"):
        return
    key = lobe_designs.design_key("phong", SIGMA, S + SV)
    gauss = len(sd.zonal_design("phong", SIGMA, S + SV, "gauss")[1])
    shutil.rmtree(directory, ignore_errors=True)
    held = HeldNative(sd)
    gs.clear_cache()
    drawing.clear_cache()
    gs._lobe_designs = lobe_designs.LobeDesigns(held, directory)

    start = time.perf_counter()
    gpu = drawing.gpu_vertex_values(scene, ball, view)
    seconds = time.perf_counter() - start
    checks.check(gs.lobe_designs().pending() == [key], "the first draw returns while the lobe design builds",
                 "%.2f s" % seconds)
    data = drawing.object_data(ball, vertex_target=True)
    checks.check(not data.designs[0].final and data.variant.lobe_design_size == gauss,
                 "meanwhile the Gauss rule shades", "%d nodes" % data.variant.lobe_design_size)
    status = gs.lobe_design_status()
    checks.check(len(status) == 1 and "Building" in status[0] and "degree %d" % (S + SV) in status[0],
                 "the panel says which design builds", "; ".join(status))
    cpu = drawing.cpu_reference(scene, ball, view)
    relative, _ = sdtest.relative_error(gpu, cpu)
    checks.check(relative <= TOLERANCE, "the Gauss rule shades exactly (GPU = CPU)", "%.2e" % relative)

    held.release.set()
    checks.check(gs.lobe_designs().wait(600), "the lobe design is built")
    gpu = drawing.gpu_vertex_values(scene, ball, view)
    size = data.variant.lobe_design_size
    checks.check(data.designs[0].final and size < gauss, "then the small design shades",
                 "%d nodes, Gauss %d" % (size, gauss))
    relative, _ = sdtest.relative_error(gpu, cpu)
    checks.check(relative <= TOLERANCE, "the small design shades exactly (GPU = CPU)", "%.2e" % relative)
    checks.check(not gs.lobe_design_status(), "the panel's status is gone")
    checks.check(os.path.isfile(gs.lobe_designs().files.path(key)), "the design is stored on disk")

    again = HeldNative(sd)   # never released: a build would leave the Gauss rule shading
    gs.clear_cache()
    drawing.clear_cache()
    gs._lobe_designs = lobe_designs.LobeDesigns(again, directory)
    drawing.gpu_vertex_values(scene, ball, view)
    data = drawing.object_data(ball, vertex_target=True)
    checks.check(again.builds == 0 and data.designs[0].final and data.variant.lobe_design_size == size,
                 "a new session reads the design from disk, without building")
    gs.clear_cache()


def check_prediction(checks, package, scene):
    prediction = package.ui.prediction
    big = sdtest.ico_sphere(scene, "Big", subdivisions=4, location=(2.5, 2.0, 1.0))
    sdtest.bake_settings(scene, "msd_visibility", "LAMBERT", 4, 2, rays=128, select=[big])
    predictor = prediction.start(bpy.context)
    checks.check(predictor is not None and predictor.join(300), "the bake time is predicted")
    predicted = prediction.current(bpy.context)   # what the panel shows
    if not checks.check(predicted is not None and predicted.final, "the panel has the prediction",
                        predicted.text() if predicted else "none"):
        return
    start = time.perf_counter()
    result = bpy.ops.sd_lighting.bake()
    seconds = time.perf_counter() - start
    checks.check(result == {'FINISHED'}, "bake MSD (13), 2562 vertices")
    print("prediction: %.1f s predicted, %.1f s baked" % (predicted.seconds, seconds), flush=True)
    checks.check(predicted.needs_confirmation == (predicted.seconds > 60.0),
                 "a bake under a minute does not ask")

    # Degree-16 designs take about a second per vertex and core on these machines: 40962 vertices
    # take hours on any of them.
    huge = sdtest.ico_sphere(scene, "Huge", subdivisions=6, location=(-2.5, 2.0, 1.0))
    sdtest.bake_settings(scene, "msd_visibility", "PHONG", 12, 4, rays=1024, phong_exponent=20.0, select=[huge])
    bake_time = package.plan.bake_time
    clock, real_time = FakeClock(), bake_time.time
    bake_time.time = clock
    try:
        start = time.perf_counter()
        asked = prediction.for_confirmation(bpy.context, wait=30.0)
        seconds = time.perf_counter() - start
        checks.check(asked is not None and asked.needs_confirmation, "a long bake asks first, at once",
                     "%s after %.1f s" % (asked.text() if asked else "none", seconds))
        # the lower bound passes an hour within a minute: the predictor's clock is moved on by one
        clock.offset += 60.0
        later = prediction.current(bpy.context)
        checks.check(later is not None and later.seconds > 3600.0,
                     "and a minute later says it takes hours", later.text() if later else "none")
    finally:
        prediction.clear()
        bake_time.time = real_time


def main():
    checks = sdtest.Checks("test_background_builds")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    package.live.gpu_context.ensure()
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ball = sdtest.ico_sphere(scene, subdivisions=2, location=(0.0, 0.0, 1.0))
    sdtest.grid(scene, cuts=8, size=4.0)
    sdtest.camera(scene)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    view = package.scene.view.View.from_camera(scene.camera, depsgraph, 640, 480, scene)
    check_lobe_designs(checks, package, scene, ball, view, os.path.join(args.out, "lobe_designs"))
    check_prediction(checks, package, scene)
    return checks.summary()


sdtest.run(main)
