"""Large and many at the panel's defaults (issue 32, item 5): the predicted bake time and memory
against the bake's own, for one large mesh and for many identical small ones.

- large: Suzanne (or --mesh, a model file, scaled to 2 units and shaded smooth) with a
  Subdivision Surface modifier (--levels, 6: about 2M vertices for Suzanne) over a ground;
- many: --copies copies of a cube (or of --mesh, scaled to 0.6 units) - one mesh each, equal - in
  a grid on a ground;
- parts: --mesh imported as a user imports it, its parts kept as they are (the glTF engine's 67
  parts), in white and standing on nothing as in test_cycles_parity; with --against-cycles, its preview
  against Cycles as that test measures it.
Under --hdri (one of Blender's studio lights, forest.exr by default).
Each scene at the panel's defaults (Automatic, Refine, Least Squares): printed are how long the
prediction took to be final and what it says (the time, and the predicted memory against the free
memory), whether a script's bake is refused without go_ahead, then the bake with go_ahead=True:
its seconds, the process's peak memory so far (ru_maxrss), its settings (how many different ones
among the objects), the ratio of the bake's time to the predicted one, and the automatic mode's
own cost estimate for the first object.

Run: blender -b --factory-startup --python blender_tests/benchmark_large.py -- --zip build/sd_lighting.zip
         [--scene large|many|parts] [--levels 6] [--copies 200] [--mesh PATH] [--hdri NAME.exr]
         [--against-cycles DIR] [--set NAME=VALUE ...]
Not part of the test suite (minutes).
"""

import argparse
import os
import resource
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402

import test_cycles_parity as parity  # noqa: E402


def options():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", default="build/sd_lighting.zip")
    parser.add_argument("--scene", choices=("large", "many", "parts"), default="large")
    parser.add_argument("--levels", type=int, default=6)
    parser.add_argument("--copies", type=int, default=200)
    parser.add_argument("--mesh", default=None)
    parser.add_argument("--hdri", default="forest.exr")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="a panel setting other than its default (scene.sd_lighting.NAME)")
    parser.add_argument("--against-cycles", metavar="DIR", help="parts: the preview against Cycles, images to DIR")
    return parser.parse_args(argv)


def large_scene(scene, levels, path):
    if path is None:
        bpy.ops.mesh.primitive_monkey_add(location=(0.0, 0.0, 1.0))
        obj = bpy.context.active_object
    else:
        obj = sdtest.sized_model(path, 2.0, (0.0, 0.0, 1.0))
    obj.data.polygons.foreach_set("use_smooth", [True] * len(obj.data.polygons))
    modifier = obj.modifiers.new("Subdivision", 'SUBSURF')
    modifier.levels = modifier.render_levels = levels
    return [obj]


def many_scene(scene, copies, path):
    side = int(copies ** 0.5 + 0.999)
    objects = []
    for k in range(copies):
        location = (1.0 * (k % side) - 0.5 * side, 1.0 * (k // side) - 0.5 * side, 0.3)
        if path is None:
            obj = sdtest.flat_cube(scene, name="Cube %03d" % k, size=0.6, location=location)
        else:
            obj = sdtest.sized_model(path, 0.6, location)
        if objects:
            obj.data = objects[0].data.copy()
        objects.append(obj)
    return objects


def parts_scene(scene, path):
    """The parts of `path` as imported, standing on nothing as in test_cycles_parity, in a white
    Diffuse BSDF, framed by its camera."""
    parts, _ = sdtest.imported(path, join=False)
    bpy.data.objects.remove(bpy.data.objects["Ground"])
    bpy.context.view_layer.update()
    corners = np.array([o.matrix_world @ Vector(c) for o in parts for c in o.bound_box])
    white = sdtest.diffuse_material("White")
    for obj in parts:
        obj.data.materials.clear()
        obj.data.materials.append(white)
    parity.frame(scene, corners.min(axis=0), corners.max(axis=0))
    return parts


def against_cycles(scene, out):
    """The preview against Cycles as test_cycles_parity measures it: (relative RMS, Cycles' noise)."""
    stem = os.path.join(out, "parts")
    theirs, noise, _ = parity.cycles(scene, stem)
    scene.sd_lighting.live_shading = True
    if bpy.ops.sd_lighting.render_preview(filepath=stem + ".exr", width=parity.SIZE, height=parity.SIZE) != {'FINISHED'}:
        raise RuntimeError("render_preview failed")
    ours = sdtest.load_exr(stem + ".exr")
    parity.error_image(stem + "_error.png", theirs, [ours])
    return parity.compare(ours, theirs)[0], noise


def main():
    opts = options()
    package = sdtest.install_addon(opts.zip)
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri(opts.hdri))
    sdtest.grid(scene, cuts=10, size=30.0 if opts.scene == "many" else 6.0)
    if opts.scene == "parts":
        objects = parts_scene(scene, opts.mesh)
    else:
        objects = (large_scene(scene, opts.levels, opts.mesh) if opts.scene == "large" else
                   many_scene(scene, opts.copies, opts.mesh))
        sdtest.camera(scene, location=(0.0, -14.0, 9.0), target=(0.0, 0.0, 0.0))
    for assignment in opts.set:
        name, value = assignment.split("=", 1)
        current = getattr(scene.sd_lighting, name)
        setattr(scene.sd_lighting, name, type(current)(value) if not isinstance(current, bool) else value == "1")
    sdtest.select_only(objects)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    vertices = sum(len(o.evaluated_get(depsgraph).data.vertices) for o in objects)
    print("scene: %s, %d objects, %d mesh vertices" % (opts.scene, len(objects), vertices))

    prediction = package.ui.prediction
    start = time.perf_counter()
    predicted = prediction.for_confirmation(bpy.context, wait=None)
    memory = prediction.memory(bpy.context)
    print("prediction: final after %.1f s: %s; memory %s for %s, %s free"
          % (time.perf_counter() - start, predicted.text(), package.plan.cost.memory_text(memory[1]), memory[0],
             package.plan.cost.memory_text(memory[2])))
    if predicted.seconds > package.plan.bake_time.CONFIRM_SECONDS:
        result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
        print("script bake without go_ahead: %s" % sorted(result))

    start = time.perf_counter()
    result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.bake, go_ahead=True)
    seconds = time.perf_counter() - start
    settings = {tuple(o["sd_bake"][k] for k in ("method", "light_order", "visibility_order", "rays"))
                for o in objects if "sd_bake" in o}
    print("bake with go_ahead: %s in %.1f s (%.2f x the prediction), peak memory %.1f GB; %d setting(s) %s"
          % (sorted(result), seconds, seconds / predicted.seconds,
             resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6, len(settings), sorted(settings)))
    record = objects[0]["sd_bake"]
    records = [o["sd_bake"] for o in objects if "sd_bake" in o]
    methods = {}
    for r in records:
        methods[r["method"]] = methods.get(r["method"], 0) + 1
    print("all %d objects: %d -> %d vertices, refinement %.1f s, bake %.1f s; methods %s"
          % (len(records), sum(r.get("unrefined_vertices", r["vertices"]) for r in records),
             sum(r["vertices"] for r in records), sum(r.get("refine_seconds", 0.0) for r in records),
             sum(r["seconds"] for r in records), sorted(methods.items())))
    print("%s: %s -> %s vertices (%s refinement levels, %s s; interpolation error left %s, predicted "
          "error %s), %s faces doubled, %s turned; bake %.1f s"
          % (objects[0].name, record.get("unrefined_vertices"), record["vertices"], record.get("refine_levels"),
             record.get("refine_seconds"), record.get("refine_estimated_left"), record.get("predicted_error"),
             record.get("faces_doubled"), record.get("faces_flipped"), record["seconds"]))
    print("the automatic mode's own estimate: %s" % next(
        (line for line in objects[0]["sd_bake"].get("automatic", "").splitlines() if line.startswith("Cost:")), "none"))
    if opts.against_cycles:
        os.makedirs(opts.against_cycles, exist_ok=True)
        rms, noise = against_cycles(scene, opts.against_cycles)
        print("against Cycles (%s, its noise %.2f %%): %.1f %% relative RMS over %d x %d blocks"
              % (opts.hdri, 100 * noise, 100 * rms, parity.BLOCK, parity.BLOCK))
    return 0


if __name__ == "__main__":
    sdtest.run(main)
