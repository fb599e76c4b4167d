"""Live Re-bake: edits of a baked object are baked again in the background and the shading follows;
a newer change, a cancel, a failure and an undo leave the object's bake consistent.

A sphere (PRT (10), 64 rays) is baked, the option turned on, and the object edited: vertices moved
in edit mode (bmesh), then a Subdivision modifier added and changed. The test runs the add-on's
timer itself (a script holds Blender's event loop), and checks after each step that the baked mesh
is the evaluated geometry (vertex count, positions), that the live shading of each vertex (GPU,
each vertex drawn as a pixel) equals sdnative.shade's of the bake, and that a re-bake equals a
fresh bake of the same geometry. Re-bakes that must be caught running use a held sdnative whose
bake waits until it is let go (or cancelled). Undo: Blender's own (memfile) undo where it has an
undo stack (the binary under Xvfb, the 5.0 module), in object mode (memfile undo) and in edit
mode, and everywhere the undo_post handler after the geometry was put back without its bake, as
an undo to a step before a re-bake does.
Run: xvfb-run -a blender --factory-startup --python-exit-code 1 --python blender_tests/test_live_rebake.py -- --zip Z
"""

import os
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bmesh  # noqa: E402
import bpy  # noqa: E402
import numpy as np  # noqa: E402

TOLERANCE = 1e-3       # GPU float32 against sdnative.shade (test_gpu_matches_cpu)
WIDTH, HEIGHT = 320, 240


class HeldNative:
    """sdnative whose bake_transfer waits until `release` is set (or the bake is cancelled:
    its progress callback says so), then raises `failure` if one is set."""

    def __init__(self, sd):
        self._sd = sd
        self.release = threading.Event()
        self.failure = None
        self.calls = 0
        self.ignore_cancel = False   # as a bake that ends just when it is cancelled

    def __getattr__(self, name):
        return getattr(self._sd, name)

    def bake_transfer(self, *args, progress=None, **kwargs):
        self.calls += 1
        while not self.release.wait(0.01):
            if not progress(0, 1) and not self.ignore_cancel:
                raise self._sd.BakeCancelled("cancelled")
        if self.failure:
            raise RuntimeError(self.failure)
        if self.ignore_cancel:
            progress = lambda done, total: True  # noqa: E731
        return self._sd.bake_transfer(*args, progress=progress, **kwargs)


class QuietClock:
    """live_rebake's clock (it reads time.monotonic() through its module's `time`): the real one
    plus `offset`, which run_timer moves on through the quiet quarter second after a change
    instead of waiting it out; perf_counter, the re-bake's own timing, is the real one."""

    def __init__(self):
        self.offset = 0.0

    def monotonic(self):
        return time.monotonic() + self.offset

    def perf_counter(self):
        return time.perf_counter()


class Context:
    def __init__(self, checks, package, ball, view):
        self.checks, self.package, self.view = checks, package, view
        self.live = package.live.live_rebake
        self.clock = QuietClock()
        self.live.time = self.clock
        self.name = ball.name

    @property
    def scene(self):
        return bpy.context.scene             # after an undo, the restored scene

    @property
    def ball(self):
        return bpy.data.objects[self.name]   # after an undo, the restored object

    def baked_count(self):
        return len(self.package.store.baked.baked_mesh(self.ball).vertices)

    def bake_id(self):
        return self.package.store.baked.record(self.ball).bake_id

    def run_timer(self, until=None, timeout=120.0):
        """Runs the add-on's timer as Blender would, until it ends (or until() holds)."""
        bpy.context.view_layer.update()     # the depsgraph handler sees the last change
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if until is not None and until():
                return True
            interval = self.live._tick()
            if interval is None:
                return until is None or until()
            panel = self.live._bake_from_panel
            if self.live._scheduler.running is None and (panel is None or panel.finished):
                self.clock.offset += interval     # the quiet time after a change: nothing runs
            else:
                time.sleep(min(interval, 0.05))   # a re-bake (or the panel's bake) runs in a thread
        return False

    def panel_texts(self):
        """The texts the panel (with its sub-panels) draws now."""
        return sdtest.panel_texts()

    def evaluated_positions(self):
        """The object's evaluated vertex positions (edit mode: the edit mesh with its modifiers)."""
        depsgraph = bpy.context.evaluated_depsgraph_get()
        evaluated = self.ball.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        try:
            return self.package.store.attributes.read_positions(mesh).astype(np.float64)
        finally:
            evaluated.to_mesh_clear()

    def consistent(self, what, follows=True):
        """The bake is whole: its baked mesh, attributes and GPU data agree, and the GPU shades it as
        sdnative.shade does; follows: its geometry is the object's evaluated geometry."""
        package, ball = self.package, self.ball
        mesh = package.store.baked.baked_mesh(ball)
        data = package.store.attributes.read(mesh)
        n = len(mesh.vertices)
        whole = package.store.baked.record(ball).vertices == n and len(data["normals"]) == n
        self.checks.check(whole, what + ": baked mesh and attributes agree", "%d vertices" % n)
        gpu = package.live.drawing.gpu_vertex_values(self.scene, ball, self.view)
        cpu = package.live.drawing.cpu_reference(self.scene, ball, self.view)
        relative, _ = sdtest.relative_error(gpu, cpu) if len(gpu) == len(cpu) else (np.inf, None)
        self.checks.check(relative <= TOLERANCE, what + ": the live shading draws this bake (GPU = CPU)",
                          "%d GPU values, %.2e" % (len(gpu), relative))
        if follows:
            baked = package.store.attributes.read_positions(mesh).astype(np.float64)
            geometry = np.unique(np.round(self.evaluated_positions(), 5), axis=0)
            same = (len(np.unique(np.round(baked, 5), axis=0)) == len(geometry) and
                    np.array_equal(np.unique(np.round(baked, 5), axis=0), geometry))
            self.checks.check(same, what + ": the bake has the object's geometry",
                              "%d baked vertices, %d evaluated" % (len(baked), len(geometry)))
        return cpu


def check_edit_mode(c):
    before = c.package.live.drawing.cpu_reference(c.scene, c.ball, c.view)
    first, asked = c.bake_id(), recorded(c)
    bpy.ops.object.mode_set(mode='EDIT')
    bm = bmesh.from_edit_mesh(c.ball.data)
    moved = 0
    for vertex in bm.verts:
        if vertex.co.z > 0.5:
            vertex.co.z += 0.6
            vertex.co.x += 0.3
            moved += 1
    bmesh.update_edit_mesh(c.ball.data)
    bpy.context.view_layer.update()
    c.checks.check(c.live.pending() == [c.name], "an edit-mode edit marks the object for a re-bake")
    c.checks.check(c.run_timer() and c.bake_id() != first, "the timer re-bakes it",
                   c.live.message)
    after = c.consistent("edit mode: moved %d vertices" % moved)
    c.checks.check(recorded(c) == asked, "the re-bake has the settings of the bake it replaces")
    changed = np.abs(after - before).max(axis=1) > 1e-3 * np.abs(before).max()
    c.checks.check(after.shape == before.shape and changed.sum() >= moved,
                   "the shading follows the edit", "%d of %d vertices shade differently"
                   % (changed.sum(), len(changed)))
    result, _ = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
    fresh = c.package.live.drawing.cpu_reference(c.scene, c.ball, c.view)
    c.checks.check(result == {'FINISHED'} and np.allclose(fresh, after, rtol=1e-6, atol=1e-9),
                   "the re-bake equals a fresh bake of the edited mesh")
    kept = c.bake_id()
    bpy.ops.object.mode_set(mode='OBJECT')
    c.run_timer()
    c.checks.check(c.bake_id() == kept, "leaving edit mode (the same geometry) bakes nothing")


def check_modifier(c):
    first, before = c.bake_id(), c.baked_count()
    modifier = c.ball.modifiers.new("Subdivision", 'SUBSURF')
    modifier.levels = 1
    c.run_timer()
    n = c.baked_count()
    c.checks.check(c.bake_id() != first and n == len(c.evaluated_positions()) and n > before,
                   "adding a modifier re-bakes the subdivided mesh", "%d vertices" % n)
    c.consistent("modifier added")
    c.checks.check(c.live.message in c.panel_texts() and c.live.message.startswith("re-baked"),
                   "the panel shows how long the last re-bake took", c.live.message)


def check_superseded(c, held):
    """A change while the object's re-bake runs cancels it; the next one bakes the newest state."""
    modifier = c.ball.modifiers["Subdivision"]
    first, before = c.bake_id(), c.baked_count()
    modifier.levels = 2
    c.checks.check(c.run_timer(until=lambda: c.live.running() is not None), "a re-bake runs")
    _, job = c.live.running()
    texts = c.panel_texts()
    c.checks.check("Re-baking %s, 0 %%" % c.name in texts and "Cancel" in texts,
                   "the panel shows the running re-bake, with Cancel")
    modifier.levels = 3
    bpy.context.view_layer.update()
    c.checks.check(job.cancel_requested, "a newer change cancels the running re-bake")
    counts = set()

    def let_go_when_restarted():
        counts.add(c.baked_count())
        running = c.live.running()
        if running is not None and running[1] is not job:
            held.release.set()
        return False
    c.run_timer(until=let_go_when_restarted)
    c.checks.check(job.cancelled and held.calls == 2, "it stops and the next re-bake starts after it",
                   "%d bakes" % held.calls)
    n = len(c.evaluated_positions())
    c.checks.check(c.bake_id() != first and c.baked_count() == n and counts <= {before, n},
                   "only the newest state's bake is applied",
                   "baked vertex counts seen %s, then %d" % (sorted(counts), n))
    c.consistent("after a superseded re-bake")
    held.release.clear()


def check_superseded_result_dropped(c, held):
    """A re-bake that ends with a result just as a newer change comes is not applied."""
    modifier = c.ball.modifiers["Subdivision"]
    before = c.baked_count()
    held.ignore_cancel = True
    modifier.levels = 2
    c.run_timer(until=lambda: c.live.running() is not None)
    _, job = c.live.running()
    modifier.levels = 1
    bpy.context.view_layer.update()
    held.release.set()
    counts, messages = set(), set()

    def watch():
        counts.add(c.baked_count())
        messages.add(c.live.message)
        return False
    c.run_timer(until=watch)
    n = len(c.evaluated_positions())
    c.checks.check(job.finished and not job.cancelled and counts <= {before, n} and c.baked_count() == n,
                   "a superseded re-bake's result is dropped, the newest state's applied",
                   "baked vertex counts seen %s, then %d" % (sorted(counts), n))
    c.checks.check(not any("cancelled" in m for m in messages), "a superseded re-bake is not reported as cancelled")
    c.consistent("after a dropped result")
    held.ignore_cancel = False
    held.release.clear()


def check_cancel_and_failure(c, held):
    modifier = c.ball.modifiers["Subdivision"]
    kept = sdtest.snapshot()
    modifier.levels = 2
    c.run_timer(until=lambda: c.live.running() is not None)
    result, _ = sdtest.operator_reports(bpy.ops.sd_lighting.cancel_bake)
    c.run_timer()
    c.checks.check(result == {'FINISHED'} and sdtest.snapshot() == kept and "cancelled" in c.live.message
                   and not c.live.pending(), "a cancelled re-bake changes nothing and says so",
                   c.live.message)
    c.consistent("after a cancel", follows=False)

    held.failure = "simulated failure"
    held.release.set()
    modifier.levels = 3
    c.run_timer()
    c.checks.check(sdtest.snapshot() == kept and "failed" in c.live.message and "simulated" in c.live.message,
                   "a failed re-bake changes nothing and says why", c.live.message)
    c.consistent("after a failure", follows=False)
    held.failure = None
    modifier.levels = 2
    c.run_timer()
    c.consistent("the next change re-bakes")


def check_undo_handler(c):
    """What an undo to a step before a re-bake leaves: the geometry back, its bake not."""
    modifier = c.ball.modifiers["Subdivision"]
    first = c.bake_id()
    handlers = bpy.app.handlers.depsgraph_update_post
    handlers.remove(c.live._on_depsgraph_update)
    modifier.levels = 1
    bpy.context.view_layer.update()
    handlers.append(c.live._on_depsgraph_update)
    c.checks.check(not c.live.pending() and c.bake_id() == first, "(geometry changed behind the handler)")
    c.live._on_undo(c.scene)
    c.checks.check(c.live.pending() == [c.name], "undo_post marks every baked object")
    c.run_timer()
    c.checks.check(c.bake_id() != first, "the bake of a restored geometry that differs is re-baked")
    c.consistent("after undo_post")
    again = c.bake_id()
    c.live._on_undo(c.scene)
    c.run_timer()
    c.checks.check(c.bake_id() == again, "a bake that matches its restored geometry stays")


def check_blender_undo(c):
    def ed(name, **kwargs):
        return sdtest.operator_reports(getattr(bpy.ops.ed, name), **kwargs)[0] == {'FINISHED'}

    modifier = c.ball.modifiers["Subdivision"]
    ed("undo_push", message="before")
    step = c.bake_id()
    modifier.levels = 2
    ed("undo_push", message="levels 2")     # what the UI pushes: the change, not its re-bake
    c.run_timer()
    rebaked = c.bake_id()
    if not ed("undo"):
        print("undo: Blender has no undo stack here (a bpy module, or no window): undo_post tested alone")
        return
    c.run_timer()
    c.checks.check(c.bake_id() == step and c.ball.modifiers["Subdivision"].levels == 1,
                   "undo brings the modifier and its bake back; nothing is re-baked")
    c.consistent("after undo")
    ed("redo")
    c.run_timer()
    c.checks.check(c.bake_id() not in (step, rebaked) and c.ball.modifiers["Subdivision"].levels == 2,
                   "redo brings the change back (without its re-bake), which is re-baked")
    c.consistent("after redo")

    # Edit mode: its undo restores the edit mesh alone; the restored geometry is re-baked.
    bpy.ops.object.mode_set(mode='EDIT')
    c.run_timer()
    ed("undo_push", message="edit mode")
    step, original = c.bake_id(), c.evaluated_positions()
    bm = bmesh.from_edit_mesh(c.ball.data)
    for vertex in bm.verts:
        vertex.co.z += 0.2 if vertex.co.z > 0.5 else 0.0
    bmesh.update_edit_mesh(c.ball.data)
    ed("undo_push", message="move")
    c.run_timer()
    moved = c.bake_id()
    ed("undo")
    c.run_timer()
    c.checks.check(moved != step and c.bake_id() not in (step, moved) and
                   np.allclose(c.evaluated_positions(), original),
                   "undo in edit mode restores the edit mesh, which is re-baked")
    c.consistent("after undo in edit mode")
    bpy.ops.object.mode_set(mode='OBJECT')


def check_slow_method(c):
    """MSD (13) re-bakes as it bakes (a design per vertex): the panel says so."""
    c.ball.modifiers.remove(c.ball.modifiers["Subdivision"])
    sdtest.bake_settings(c.scene, "msd_visibility", "LAMBERT", 2, 2, rays=64, select=[c.ball])
    c.checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake MSD (13)")
    c.checks.check(any("builds a design per vertex" in text for text in c.panel_texts()),
                   "the panel says that MSD (13) re-bakes slowly")
    first = c.bake_id()
    c.ball.location.x += 0.5        # a move is no change of geometry
    bpy.context.view_layer.update()
    c.checks.check(not c.live.pending(), "moving the object is no change to re-bake")
    bpy.ops.object.mode_set(mode='EDIT')
    bm = bmesh.from_edit_mesh(c.ball.data)
    bm.verts.ensure_lookup_table()
    bm.verts[0].co.z += 0.3
    bmesh.update_edit_mesh(c.ball.data)
    c.run_timer()
    c.checks.check(c.bake_id() != first and c.package.store.baked.record(c.ball).method == "msd_visibility",
                   "an MSD (13) bake re-bakes with its own method", c.live.message)
    c.consistent("MSD (13) re-baked")
    bpy.ops.object.mode_set(mode='OBJECT')


def recorded(c):
    """What the object's bake was asked for and chose (its record without what the bake found)."""
    return {key: value for key, value in c.package.store.baked.record(c.ball).settings().items()
            if key != "shape"}


def check_automatic(c):
    """A bake of the automatic mode re-bakes with its choice (method, orders, rays, per-pixel
    evaluation and the reasons), not by choosing again."""
    sdtest.bake_settings(c.scene, "automatic", "LAMBERT", 2, 2, rays=64, select=[c.ball])
    c.checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake with the automatic mode")
    chosen, first = recorded(c), c.bake_id()
    c.ball.modifiers.new("Subdivision", 'SUBSURF').levels = 1
    c.run_timer()
    c.checks.check(c.bake_id() != first and recorded(c) == chosen and "automatic" in chosen and
                   chosen["method"] != "automatic", "an automatic bake re-bakes with its choice",
                   "%s, s = %d, s' = %d, %d rays" % (chosen["method"], chosen["light_order"],
                                                   chosen["visibility_order"], chosen["rays"]))
    c.consistent("automatic bake re-baked")


def check_texture_space(c):
    """A bake with texture-space data re-bakes with new texels in Object Mode; in Edit Mode, whose
    unwrap needs Object Mode, the re-bake says so and the bake stays."""
    baked = c.package.store.baked
    settings = sdtest.bake_settings(c.scene, "prt_diffuse", "LAMBERT", 2, rays=64, select=[c.ball])
    settings.texture_space, settings.lightmap_size = True, '256'
    c.checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'} and
                   baked.lightmap_mesh(baked.baked_mesh(c.ball)) is not None, "bake with texture-space data")
    first = c.bake_id()
    c.ball.modifiers["Subdivision"].levels = 2
    c.run_timer()
    texels = baked.lightmap_mesh(baked.baked_mesh(c.ball))
    c.checks.check(c.bake_id() != first and texels is not None and baked.record(c.ball).lightmap_texels > 0
                   and [m.name for m in bpy.data.meshes if m.name.startswith("SD Lightmap")] == [texels.name],
                   "a modifier change re-bakes the texels; the previous ones go", c.live.message)
    kept = c.bake_id()
    bpy.ops.object.mode_set(mode='EDIT')
    bm = bmesh.from_edit_mesh(c.ball.data)
    for vertex in bm.verts:
        vertex.co.z += 0.1
    bmesh.update_edit_mesh(c.ball.data)
    c.run_timer()
    message = c.live.message
    bpy.ops.object.mode_set(mode='OBJECT')
    c.checks.check(c.bake_id() == kept and "Object Mode" in message,
                   "in Edit Mode the re-bake says it needs Object Mode, the bake stays", message)


def main():
    checks = sdtest.Checks("test_live_rebake")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    package.live.gpu_context.ensure()
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ball = sdtest.ico_sphere(scene, subdivisions=2, location=(0.0, 0.0, 1.0))
    ball.data.materials.append(sdtest.diffuse_material("White"))
    sdtest.grid(scene, cuts=6, size=4.0)
    sdtest.camera(scene)
    settings = sdtest.bake_settings(scene, "prt_gaunt", "LAMBERT", 3, 2, rays=64, select=[ball])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake PRT (10)")
    view = package.live.drawing.View.from_camera(scene.camera, bpy.context.evaluated_depsgraph_get(),
                                            WIDTH, HEIGHT, scene)
    c = Context(checks, package, ball, view)
    c.consistent("the first bake")
    settings.live_rebake = True

    check_edit_mode(c)
    check_modifier(c)
    held = HeldNative(package.native.get())
    package.native._module = held
    try:
        check_superseded(c, held)
        check_superseded_result_dropped(c, held)
        check_cancel_and_failure(c, held)
    finally:
        package.native._module = held._sd
    check_undo_handler(c)
    check_blender_undo(c)
    check_slow_method(c)
    check_automatic(c)
    check_texture_space(c)
    return checks.summary()


sdtest.run(main)
