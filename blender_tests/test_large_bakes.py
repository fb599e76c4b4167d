"""Large and many (issue 32, item 5): identical objects share one automatic choice, and a script's
bake that would take over a minute or more memory than is free is refused unless told to go
ahead, leaving everything as it was.

- 30 copies of a cube in a grid on a ground, baked together at the panel's defaults (Automatic):
  one setting for all, measured once (the others' reasons say whose choice they share); the
  ground, another mesh, gets its own.
- A 10k-vertex ball with MSD Theorem 2.2 (13) (a design per vertex, s = 6, s' = 3), with the time
  that asks first lowered to 5 s (it bakes in 30-50 s, so the check does not hang on the machine's
  speed): bpy.ops.sd_lighting.bake() refuses with the predicted time and bakes nothing.
- With the free memory made to look smaller than the bake needs: refused with both figures;
  go_ahead=True bakes anyway.
- A refinement is predicted from a sample of the copy's triangles (plan/bake_time.py): a low-poly
  flat-shaded ball sampled whole is predicted to the vertex the bake refines it to; a finer one,
  sampled in part, within a factor of 2.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_large_bakes.py -- --zip Z --out DIR
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402

COPIES = (6, 5)


def setting(obj):
    record = obj["sd_bake"]
    return tuple(record[k] for k in ("method", "light_order", "visibility_order", "rays"))


def main():
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    checks = sdtest.Checks("test_large_bakes")
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ground = sdtest.grid(scene, cuts=8, size=12.0)
    cubes = []
    for i in range(COPIES[0]):
        for j in range(COPIES[1]):
            cube = sdtest.flat_cube(scene, name="Cube %d %d" % (i, j), size=0.8,
                                    location=(1.5 * i - 3.75, 1.5 * j - 3.0, 0.4))
            if cubes:   # one mesh each, equal: a copy made with Shift+D, or an import
                cube.data = cubes[0].data.copy()
            cubes.append(cube)
    sdtest.camera(scene, location=(0.0, -12.0, 8.0), target=(0.0, 0.0, 0.0))
    settings = scene.sd_lighting
    settings.refine = False   # the panel's defaults otherwise (Automatic, Least Squares)
    sdtest.select_only(cubes + [ground])
    result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
    chosen = {setting(cube) for cube in cubes}
    shared = sum("Shared: measured on" in cube["sd_bake"]["automatic"] for cube in cubes)
    checks.check(result == {'FINISHED'} and len(chosen) == 1 and shared == len(cubes) - 1 and
                 "Shared" not in ground["sd_bake"]["automatic"],
                 "identical cubes get one automatic setting, measured once",
                 "%s for the %d cubes (%d shared), %s for the ground"
                 % (sorted(chosen), len(cubes), shared, setting(ground)))
    for obj in cubes + [ground]:
        package.store.baked.clear(obj)

    # A bake predicted far over the time that asks first, from a script.
    ball = sdtest.ico_sphere(scene, subdivisions=6, location=(0.0, 0.0, 2.0))
    sdtest.bake_settings(scene, "msd_visibility", 'LAMBERT', 6, 3, rays=1024, select=[ball])
    bake_time = package.plan.bake_time
    confirm = bake_time.CONFIRM_SECONDS
    bake_time.CONFIRM_SECONDS = 5.0
    try:
        result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
    finally:
        bake_time.CONFIRM_SECONDS = confirm
    checks.check(result == {'CANCELLED'} and "predicted to take" in reports and "go_ahead=True" in reports
                 and package.store.baked.record(ball) is None,
                 "a script's bake predicted over the time that asks first is refused, nothing baked",
                 "%d vertices: %s" % (len(ball.data.vertices), reports.strip()))

    # More memory than is free.
    sdtest.bake_settings(scene, "ambient_occlusion", 'LAMBERT', 2, rays=16, select=[ball])
    cost = package.plan.cost
    free = cost.available_bytes
    cost.available_bytes = lambda: 1000
    try:
        result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
        refused = result == {'CANCELLED'} and "of memory" in reports and package.store.baked.record(ball) is None
        result, _ = sdtest.operator_reports(bpy.ops.sd_lighting.bake, go_ahead=True)
    finally:
        cost.available_bytes = free
    checks.check(refused and result == {'FINISHED'} and package.store.baked.record(ball) is not None,
                 "a bake over the free memory is refused with the figures; go_ahead=True bakes it",
                 reports.strip())
    for obj in (ball,):
        package.store.baked.clear(obj)

    # Refinement, predicted from the triangles sampled.
    ball.hide_set(True)
    for subdivisions in (1, 4):   # 20 and 1,280 triangles
        low_poly = sdtest.ico_sphere(scene, name="Low %d" % subdivisions, subdivisions=subdivisions,
                                     location=(0.0, 0.0, 1.0), smooth=False)
        sdtest.bake_settings(scene, "prt_diffuse", 'LAMBERT', 4, rays=256, select=[low_poly], refine=True)
        predictor = package.ui.prediction.start(bpy.context)
        predictor.join(120)
        task = predictor.jobs[0].task
        estimate = task.predicted_refinement
        predicted = -1 if estimate is None else estimate.vertex_growth * len(task.geometry.vertices)
        result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.bake, go_ahead=True)
        record = package.store.baked.record(low_poly)
        baked = -1 if record is None else record.vertices
        sampled = len(task.geometry.triangles) <= package.plan.bake_time.REFINE_SAMPLE
        checks.check(result == {'FINISHED'} and baked > len(task.geometry.vertices) and
                     (round(predicted) == baked if sampled else 0.5 * baked <= predicted <= 2.0 * baked),
                     "a refinement is predicted from a sample: %s" % (
                         "all of a low-poly ball, to the vertex" if sampled else "a finer ball's, within 2x"),
                     "%d triangles: %d -> %d vertices, predicted %.0f" % (
                         len(task.geometry.triangles), len(task.geometry.vertices), baked, predicted))
        package.store.baked.clear(low_poly)
        low_poly.hide_set(True)
    return checks.summary()


if __name__ == "__main__":
    sdtest.run(main)
