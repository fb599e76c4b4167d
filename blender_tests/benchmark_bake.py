"""Bake time of every shading method against Cycles' ambient-occlusion bake to vertex colours and
against the rays alone, on the same mesh and ray count, as ratios measured in one run.

For each bake the add-on does (one per distinct set of sdnative.bake_transfer arguments, built as
BakeTask.bake_arguments builds them for the method, s = 4, s' = 2, seed 0, sdnative's default
threads: every core), the wall time of `sdnative.bake_transfer` on the mesh's vertices, unit normals
and triangles as the add-on reads them (bake/geometry.Geometry). Against:
- Cycles: `bpy.ops.object.bake(type='AO', target='VERTEX_COLORS')` of the same object, CPU, all
  threads, samples = rays, adaptive sampling and denoising off, into a colour attribute; timed
  around the operator (scene sync and BVH build included, as for ours). Its AO distance (the
  world's) is the mesh's bounding-box diagonal unless --cycles-distance says otherwise: the
  factory default, 10, would let a large model's Cycles rays stop short where ours go on.
- the rays alone: sdnative has no raw-ray entry point, so the closest proxy is bake_transfer with
  only the ambient occlusion requested (the same rays, traced and counted, nothing else built);
  the C++ `visibility_benchmarks` compares that with raw Embree rtcOccluded1M.

Mesh: by default assimp's 2CylinderEngine.glb (Debian's assimp-testmodels,
/usr/share/assimp/models/glTF2/...; all its parts joined into one object, transforms applied), else
Suzanne subdivided (level 4). --quick: Suzanne subdivided to level 2 (about 8k vertices).

Run: blender -b --factory-startup --python blender_tests/benchmark_bake.py -- [--zip build/sd_lighting.zip]
         [--rays 256] [--mesh PATH|suzanne] [--quick] [--cycles-distance D]
         [--skip METHOD_ID,...]
(PATH: .glb/.gltf/.obj/.ply/.stl.) Not part of the test suite.
"""

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_MESH = "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"
LIGHT_ORDER, VISIBILITY_ORDER, SEED = 4, 2, 0


def options():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="benchmark_bake.py")
    parser.add_argument("--zip", default=os.path.join(ROOT, "build", "sd_lighting.zip"))
    parser.add_argument("--rays", type=int, default=256, help="rays per vertex = Cycles samples")
    parser.add_argument("--mesh", default=None, help="a model file, or 'suzanne'")
    parser.add_argument("--quick", action="store_true", help="a small mesh (Suzanne, ~8k vertices)")
    parser.add_argument("--cycles-distance", type=float, default=None,
                        help="Cycles' AO distance (world); default: the mesh's bounding-box diagonal, "
                             "so that every occluder counts as in sdnative's unbounded rays; "
                             "0: keep the world's default (10)")
    parser.add_argument("--skip", default="", help="method ids not to bake, comma-separated")
    args = parser.parse_args(argv)
    if args.mesh is None:
        args.mesh = "suzanne" if args.quick or not os.path.isfile(DEFAULT_MESH) else DEFAULT_MESH
    return args


# ----------------------------------------------------------------------------------------------
# The mesh

def suzanne(scene, levels):
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    modifier = obj.modifiers.new("Subdivision", 'SUBSURF')
    modifier.levels = modifier.render_levels = levels
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    return obj, "Suzanne subdivided %d times" % levels


def load_mesh(scene, args):
    if args.mesh == "suzanne":
        return suzanne(scene, 2 if args.quick else 4)
    return sdtest.imported(os.path.abspath(args.mesh))


# ----------------------------------------------------------------------------------------------
# The bakes

def bake_jobs(package, skip):
    """[(labels, method ids, bake_transfer keywords)]: one per distinct bake the add-on does, with
    the arguments BakeTask.bake_arguments gives the method at s = 4, s' = 2."""
    methods = package.methods
    jobs = {}
    for method in methods.METHODS:
        if method.data is None or method.id in skip:    # unshadowed: nothing to bake
            continue
        settings = {"method": method.id, "rays": 0, "seed": SEED, "light_order": LIGHT_ORDER,
                    "visibility_order": VISIBILITY_ORDER if method.uses_visibility_order else 0}
        task = package.bake.task.BakeTask("benchmark", None, (None, None), settings, None)
        kwargs = task.bake_arguments()
        kwargs.pop("rays")
        key = tuple(sorted((k, repr(v)) for k, v in kwargs.items()))
        jobs.setdefault(key, ([], [], kwargs))
        jobs[key][0].append(method.label)
        jobs[key][1].append(method.id)
    return list(jobs.values())


def cycles_ao(scene, obj, samples, distance):
    """Seconds of Cycles' AO bake of obj to a colour attribute at `samples` samples, and the mean
    AO it stored."""
    if distance:
        scene.world.light_settings.distance = distance
    scene.render.engine = 'CYCLES'
    scene.cycles.device = 'CPU'
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    if hasattr(scene.cycles, "use_preview_denoising"):
        scene.cycles.use_preview_denoising = False
    scene.render.threads_mode = 'AUTO'
    mesh = obj.data
    attribute = mesh.color_attributes.new("AO", 'BYTE_COLOR', 'POINT')
    if hasattr(mesh.color_attributes, "active_color"):
        mesh.color_attributes.active_color = attribute
    mesh.attributes.active_color = attribute
    bpy.ops.object.select_all(action='DESELECT')
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    start = time.perf_counter()
    result = bpy.ops.object.bake(type='AO', target='VERTEX_COLORS')
    seconds = time.perf_counter() - start
    if result != {'FINISHED'}:
        raise RuntimeError("Cycles bake returned %s" % result)
    values = np.empty(len(mesh.vertices) * 4, dtype=np.float32)
    attribute.data.foreach_get("color", values)
    return seconds, float(values.reshape(-1, 4)[:, 0].mean())


def main():
    args = options()
    package = sdtest.install_addon(args.zip)
    sd = package.native.get()
    scene = sdtest.empty_scene()
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    obj, mesh_name = load_mesh(scene, args)
    bpy.context.view_layer.update()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    shape, _ = package.scene.transforms.bake_space(obj.evaluated_get(depsgraph).matrix_world)
    geometry = package.bake.geometry.evaluated_geometry(obj, depsgraph, shape)
    n = len(geometry.vertices)
    rays = args.rays
    print("mesh: %s: %d vertices, %d triangles; %d rays/samples per vertex; sdnative threads: "
          "default (%d hardware threads); module %s" % (
              mesh_name, n, len(geometry.triangles), rays, os.cpu_count(),
              os.path.basename(package.native.get().__file__)), flush=True)

    def bake(kwargs):
        start = time.perf_counter()
        result = sd.bake_transfer(geometry.vertices, geometry.normals, geometry.triangles,
                                  rays=rays, **kwargs)
        return time.perf_counter() - start, result

    bake({"seed": SEED})   # warm-up (library, page faults); not timed
    rows = []
    ao_seconds = None
    for labels, ids, kwargs in bake_jobs(package, set(filter(None, args.skip.split(",")))):
        seconds, result = bake(kwargs)
        extra = ""
        if "design_offsets" in result:
            counts = np.diff(result["design_offsets"])
            extra = "nodes mean %.1f max %d" % (counts.mean(), counts.max())
        if not set(kwargs) - {"seed"}:
            labels = labels + ["rays proxy"]
            ao_seconds = seconds
            ao_mean = float(np.mean(result["ambient_occlusion"]))
        shown = {k: v for k, v in kwargs.items() if k != "seed"} or "AO only"
        rows.append((" / ".join(labels), seconds, str(shown), extra))
        print("  baked %s in %.2f s %s" % (rows[-1][0], seconds, extra), flush=True)

    distance = args.cycles_distance
    if distance is None:
        distance = float(np.linalg.norm(geometry.vertices.max(axis=0) - geometry.vertices.min(axis=0)))
    cycles_seconds, cycles_mean = cycles_ao(scene, obj, rays, distance)
    print("  Cycles AO bake in %.2f s" % cycles_seconds, flush=True)
    print("  mean AO: sdnative %.3f (whole sphere, unbounded), Cycles %.3f (cosine-weighted "
          "hemisphere, world AO distance %.3g)"
          % (ao_mean if ao_seconds else float("nan"), cycles_mean,
             scene.world.light_settings.distance), flush=True)

    print()
    print("Bake of %s, %d vertices, %d rays per vertex (Cycles: %d samples, AO distance %.4g), "
          "s = %d, s' = %d" % (mesh_name, n, rays, rays, scene.world.light_settings.distance,
                               LIGHT_ORDER, VISIBILITY_ORDER))
    header = "%-42s %9s %12s %10s %10s  %s" % ("method", "seconds", "vertices/s", "÷ Cycles",
                                              "÷ AO-only", "bake_transfer arguments")
    print(header)
    print("-" * len(header))
    table = rows + [("Cycles AO bake to vertex colours", cycles_seconds, "bpy.ops.object.bake", "")]
    for label, seconds, shown, extra in table:
        ratio_ao = "%10.2f" % (seconds / ao_seconds) if ao_seconds else "%10s" % "-"
        print("%-42s %9.2f %12.0f %10.3f %s  %s%s" % (label, seconds, n / seconds,
                                                     seconds / cycles_seconds, ratio_ao, shown,
                                                     "; " + extra if extra else ""))
    print("Rays alone: sdnative has no raw-ray entry point; the AO-only bake (the same rays, nothing "
          "else built) is the proxy (÷ AO-only column).")
    print("Cycles ÷ ours: " + ", ".join("%s %.1fx" % (label, cycles_seconds / seconds)
                                        for label, seconds, _, _ in rows))
    return 0


sdtest.run(main)
