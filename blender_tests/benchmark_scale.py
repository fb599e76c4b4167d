"""Scale (issue 30, item 3): a bumpy heightfield of 100k, 1M, 4M and 10M vertices baked at the
panel's defaults and drawn, each size in turn: the prediction (its seconds and memory, and how long
it took), the bake (its seconds, the process's peak memory during it, the bake's time on the main
thread: gathering the arrays before the worker and storing after it), the bytes stored per vertex,
and the viewport's frame time per vertex against Blender's own uniform-colour shader on the same
mesh (benchmark_viewport's frame: 1280x720 offscreen, one-pixel readback). A size whose bake is
predicted not to fit the free memory is baked as a user's bake would be (without go_ahead): what
the prediction and the bake said ends the table.

Peak memory: the bake's own, against the predicted: Linux's VmHWM of the process, reset before each
bake (/proc/self/clear_refs), less its resident memory just before (Blender and the mesh).

Run: xvfb-run -a blender -b --factory-startup --python blender_tests/benchmark_scale.py -- --zip build/sd_lighting.zip
         [--sizes 100000,1000000,4000000,10000000] [--hdri forest.exr] [--frames 3] [--method ID]
Not part of the test suite (tens of minutes at 10M).
"""

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import benchmark_viewport as viewport  # noqa: E402


def options():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", default="build/sd_lighting.zip")
    parser.add_argument("--sizes", default="100000,1000000,4000000,10000000")
    parser.add_argument("--hdri", default="forest.exr")
    parser.add_argument("--frames", type=int, default=3)
    parser.add_argument("--method", default=None,
                        help="a method id instead of Automatic (which lights the shallow heightfield unshadowed)")
    return parser.parse_known_args(argv)[0]


def peak_reset():
    """Resets the process's peak resident memory (VmHWM)."""
    with open("/proc/self/clear_refs", "w") as refs:
        refs.write("5")


def resident_bytes(field="VmRSS"):
    """The process's resident memory now (VmRSS) or its peak since peak_reset (VmHWM)."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    return 0


def heightfield_object(package, scene, size):
    """A smooth-shaded heightfield object of about `size` vertices (benchmark_viewport.heightfield)."""
    positions, _, triangles = viewport.heightfield(size)
    mesh = package.store.attributes.new_mesh("Heightfield", positions, triangles.ravel(),
                                             np.arange(0, 3 * len(triangles), 3), np.full(len(triangles), 3))
    mesh.polygons.foreach_set("use_smooth", np.ones(len(triangles), dtype=bool))
    obj = sdtest.add_object(scene, "Heightfield", mesh)
    return obj, positions, triangles


def main():
    import gpu
    opts = options()
    package = sdtest.install_addon(opts.zip)
    package.live.gpu_context.ensure()
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri(opts.hdri))
    camera = sdtest.camera(scene, location=(0.0, -4.5, 3.5), target=(0.0, 0.0, 0.0))
    uniform = package.compat.uniform_color_shader()
    from mathutils import Matrix
    prediction = package.ui.prediction
    if opts.method:
        scene.sd_lighting.method = opts.method
    print("\nsd_lighting scale benchmark: %s, %s (%s), %d cores, %s free; under %s, panel defaults%s"
          % (gpu.platform.renderer_get(), gpu.platform.version_get(), bpy.app.version_string,
             os.cpu_count(), package.plan.cost.memory_text(package.plan.cost.available_bytes()), opts.hdri,
             " but the method " + opts.method if opts.method else ""))
    header = ("vertices", "predicted", "took", "pred. mem", "bake (s)", "main (s)", "bake mem", "setting",
              "bytes/v", "uniform ms", "live ms", "ratio")
    print("%10s %10s %6s %10s %9s %9s %9s %-26s %8s %10s %9s %6s" % header, flush=True)
    for size in [int(s) for s in opts.sizes.split(",") if s]:
        obj, positions, triangles = heightfield_object(package, scene, size)
        sdtest.select_only([obj])
        peak_reset()
        before = resident_bytes()
        start = time.perf_counter()
        predicted = prediction.for_confirmation(bpy.context, wait=None)
        took = time.perf_counter() - start
        print("prediction of %d vertices: %.1f s, its own peak memory %s" % (
            len(positions), took, package.plan.cost.memory_text(resident_bytes("VmHWM") - before)), flush=True)
        needed = prediction.memory(bpy.context)
        row = (len(positions), predicted.text() if predicted else "-", took,
               package.plan.cost.memory_text(needed[1]) if needed else "-")
        problem = prediction.error(bpy.context)
        if problem or (needed and needed[1] > needed[2]):   # what the bake a user asks for does
            result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
            print("%10d %10s %6.1f %10s  prediction: %s; bake: %s %s" % (
                row + (problem or "-", sorted(result), reports.strip())), flush=True)
            break
        peak_reset()
        before = resident_bytes()
        start = time.perf_counter()
        result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.bake, go_ahead=True)   # over a minute: asks
        seconds = time.perf_counter() - start
        if result != {'FINISHED'}:
            print("%10d %10s %6.1f %10s  failed: %s" % (row + (reports.strip(),)), flush=True)
            break
        record = obj["sd_bake"]
        setting = "%s s=%d s'=%d %d rays" % (record["method"], record["light_order"], record["visibility_order"],
                                             record["rays"])
        bpy.context.view_layer.update()
        depsgraph = bpy.context.evaluated_depsgraph_get()
        view = package.scene.view.View.from_camera(camera, depsgraph, viewport.WIDTH, viewport.HEIGHT, scene)
        draw_uniform, batch = viewport.uniform_drawer(uniform, Matrix(view.view_projection.tolist()),
                                                      positions, triangles)
        t_uniform = viewport.time_frames(draw_uniform, opts.frames)
        t_live = viewport.time_frames(
            lambda: package.live.drawing.draw_objects(scene, [obj], view, 1.0, False), opts.frames)
        print("%10d %10s %6.1f %10s %9.1f %9.1f %9s %-26s %8.0f %10.1f %9.1f %6.1f" % (
            row + (seconds, seconds - record["seconds"], package.plan.cost.memory_text(resident_bytes("VmHWM") - before), setting,
                   record["bytes_per_vertex"], 1e3 * t_uniform, 1e3 * t_live, t_live / t_uniform)), flush=True)
        del batch
        package.store.baked.clear(obj)
        viewport.remove_object(package, obj)
    print("took: the prediction's own seconds; main: the bake's seconds outside its worker (the "
          "arrays gathered, the results stored); ratio: the live shading's frame / the uniform shader's")
    return 0


if __name__ == "__main__":
    sdtest.run(main)
