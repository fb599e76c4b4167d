"""Live Re-bake's time on a large mesh: from an edit to the new bake shown, per method.

Suzanne with a Subdivision modifier (level 4 by default: about 126k vertices, shaded smooth) over a
ground plane is baked with each method (Lambert, s = 4, s' = 2, --rays rays); with Live Re-bake
on, one of its vertices is moved in edit mode (bmesh) and the add-on's timer is run as Blender
runs it (a script holds the event loop) until the re-bake is applied. Printed per method:
- total: from the edit to the new bake in place, less the debounce delay (live_rebake.DELAY);
- main thread: the time Blender is busy in the timer (the re-bake's prepare: evaluated mesh,
  occluders, digest; and its apply: the new baked mesh), in all and in its longest call (the
  longest the UI freezes);
- worker: sdnative.bake_transfer in the worker thread.
Then the cancel latency: a re-bake is started, and 0.3 s later the mesh is edited again; printed is
the time from that edit until the running (superseded) bake has stopped.
MSD Theorem 2.2 (13) builds a design per vertex and is not run unless --methods names it.

Run: blender -b --factory-startup --python blender_tests/benchmark_rebake.py -- [--zip build/sd_lighting.zip]
         [--rays 128] [--levels 4] [--methods ambient_occlusion,prt_gaunt,msd_lobe,prt_diffuse]
Not part of the test suite.
"""

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bmesh  # noqa: E402
import bpy  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LIGHT_ORDER, VISIBILITY_ORDER = 4, 2


def options():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="benchmark_rebake.py")
    parser.add_argument("--zip", default=os.path.join(ROOT, "build", "sd_lighting.zip"))
    parser.add_argument("--rays", type=int, default=128)
    parser.add_argument("--levels", type=int, default=4, help="Subdivision levels on Suzanne")
    parser.add_argument("--methods", default="ambient_occlusion,prt_gaunt,msd_lobe,prt_diffuse")
    return parser.parse_args(argv)


def run_timer(live, until=None):
    """Runs the add-on's timer until it ends (or until() holds); returns the seconds spent in it
    in all and in its longest call."""
    calls = [0.0]
    while until is None or not until():
        start = time.perf_counter()
        interval = live._tick()
        calls.append(time.perf_counter() - start)
        if interval is None:
            break
        time.sleep(min(interval, 0.01))
    return sum(calls), max(calls)


def edit(obj, offset):
    """Moves the mesh's first vertex in edit mode, as a drag in the viewport would."""
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    bm.verts[0].co.z += offset
    bmesh.update_edit_mesh(obj.data)
    bpy.context.view_layer.update()
    return time.perf_counter()


def main():
    args = options()
    package = sdtest.install_addon(args.zip)
    live = package.live.live_rebake
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    sdtest.grid(scene, cuts=10, size=6.0, location=(0.0, 0.0, -1.0))
    bpy.ops.mesh.primitive_monkey_add()
    suzanne = bpy.context.active_object
    suzanne.data.polygons.foreach_set("use_smooth", [True] * len(suzanne.data.polygons))
    suzanne.modifiers.new("Subdivision", 'SUBSURF').levels = args.levels
    print("mesh: Suzanne, Subdivision level %d, %d rays, s = %d, s' = %d"
          % (args.levels, args.rays, LIGHT_ORDER, VISIBILITY_ORDER), flush=True)
    for method in args.methods.split(","):
        settings = sdtest.bake_settings(scene, method, "LAMBERT", LIGHT_ORDER, VISIBILITY_ORDER,
                                        rays=args.rays, select=[suzanne])
        settings.live_rebake = False
        if bpy.context.object.mode != 'OBJECT':
            bpy.ops.object.mode_set(mode='OBJECT')
        start = time.perf_counter()
        assert bpy.ops.sd_lighting.bake(go_ahead=True) == {'FINISHED'}
        bake = time.perf_counter() - start
        settings.live_rebake = True
        bpy.ops.object.mode_set(mode='EDIT')
        run_timer(live)                       # entering edit mode changes nothing to bake
        first = package.store.baked.record(suzanne).bake_id
        changed = edit(suzanne, 0.05)
        busy, longest = run_timer(live)
        total = time.perf_counter() - changed - live.DELAY
        record = package.store.baked.record(suzanne)
        assert record.bake_id != first, live.message
        print("%-28s %6d vertices: bake %.2f s; re-bake total %.2f s, main thread %.2f s (longest "
              "call %.2f s), worker %.2f s" % (package.methods.get(method).label, record.vertices,
                                                bake, total, busy, longest, record.seconds), flush=True)

    edit(suzanne, 0.05)
    run_timer(live, until=lambda: live.running() is not None and live.running()[1].fraction > 0.0)
    time.sleep(0.3)
    job = live.running()[1]
    changed = edit(suzanne, 0.05)
    while not job.finished:
        time.sleep(0.005)
    print("cancel latency (%s): the superseded bake stopped %.3f s after the edit"
          % (package.methods.get(method).label, time.perf_counter() - changed), flush=True)
    run_timer(live)
    return 0


sdtest.run(main)
