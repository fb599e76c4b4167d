"""Stale bakes (issue 32, item 1): a bake whose object's evaluated mesh changed since is not drawn over
the geometry it no longer fits, and the preview, the panel and the status say so; the same mesh
back is drawn again.

A ball on a ground is baked (PRT (8), s = 4, 64 rays), then changed as users do: moved (not stale),
its upper half deleted with bmesh in Object Mode, a vertex moved in Edit Mode, a Subdivision
Surface added, an animated shape key at another frame. After each change: whether the ball is
drawn (drawing.baked_objects), the preview (the stale ball in flat grey, as the scene's other
meshes, reported by render_preview; where the old ball was and nothing is now, nothing), the
panel's lines; after each undoing of it (the mesh put back, the modifier removed, the baked
frame again) the preview equals the first. A record from before the check (no `source`) is taken
as it is; a re-bake is drawn again; with Live Re-bake on the panel says it is re-baking.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_stale_bake.py -- --zip Z --out DIR
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bmesh  # noqa: E402
import bpy  # noqa: E402
import numpy as np  # noqa: E402

WIDTH, HEIGHT = 160, 120


class Scene:
    def __init__(self, checks, package, out):
        self.checks, self.package, self.out = checks, package, out
        self.count = 0

    @property
    def ball(self):
        return bpy.data.objects["Ball"]

    def drawn(self):
        bpy.context.evaluated_depsgraph_get()
        return sorted(obj.name for obj in self.package.live.drawing.baked_objects(bpy.context.scene))

    def preview(self):
        """(the image, the operator's reports) of a preview."""
        self.count += 1
        path = os.path.join(self.out, "stale_%02d.exr" % self.count)
        result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.render_preview, filepath=path,
                                                  width=WIDTH, height=HEIGHT)
        assert result == {'FINISHED'}, reports
        return sdtest.load_exr(path), reports

    def expect(self, what, stale, reference=None):
        """Checks the ball's state after a change: stale or fresh, drawn or not, what the preview,
        its report and the panel say; fresh with a reference image: the preview equals it."""
        drawn = self.drawn()
        image, reports = self.preview()
        texts = "\n".join(sdtest.panel_texts())
        said = "Ball changed since its bake" in reports
        panel = "Ball changed since its bake" in texts and "The mesh changed since the bake" in texts
        self.checks.check(("Ball" not in drawn) == stale and "Ground" in drawn,
                          "%s: the ball is %s" % (what, "not drawn" if stale else "drawn"), ", ".join(drawn))
        self.checks.check(said == stale and panel == stale,
                          "%s: the preview's report and the panel %s" % (what, "name it" if stale else "are silent"),
                          "report %s, panel %s" % (said, panel))
        grey = np.all(np.abs(image[..., :3] - self.package.live.preview.OTHER_MESH_GREY) < 1e-6, axis=2)
        self.checks.check((grey.sum() > 50) == stale, "%s: %s" % (
            what, "the ball drawn in flat grey" if stale else "nothing drawn in flat grey"),
            "%d grey pixels" % grey.sum())
        if reference is not None:
            difference = float(np.abs(image - reference).max())
            self.checks.check(difference < 1e-5, "%s: the preview equals the first" % what,
                              "max difference %.2g" % difference)
        return image


def main():
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    checks = sdtest.Checks("test_stale_bake")
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ball = sdtest.ico_sphere(scene, subdivisions=3, location=(0.0, 0.0, 0.75), radius=0.75)
    ground = sdtest.grid(scene, cuts=16, size=4.0)
    sdtest.camera(scene, location=(0.0, -5.0, 2.5), target=(0.0, 0.0, 0.5))
    scene.sd_lighting.live_shading = True
    sdtest.bake_settings(scene, "prt_matrix", 'LAMBERT', 4, rays=64, select=[ball, ground])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake")
    s = Scene(checks, package, args.out)
    record = package.store.baked.record(ball)
    checks.check(len(record.source) == 32, "the record has the source's digest", record.source)
    first = s.expect("after the bake", False)

    ball.location.x += 0.5                # the object moved: its mesh is the same
    moved = s.expect("moved", False)
    checks.check(float(np.abs(moved - first).max()) > 1e-3, "moved: the ball is drawn where it is now")
    ball.location.x -= 0.5

    # The upper half deleted in Object Mode (bmesh), then the mesh put back.
    original = ball.data.copy()
    mesh = bmesh.new()
    mesh.from_mesh(ball.data)
    bmesh.ops.delete(mesh, geom=[v for v in mesh.verts if v.co.z > 0.1], context='VERTS')
    mesh.to_mesh(ball.data)
    mesh.free()
    ball.data.update()
    halved = s.expect("upper half deleted", True)
    gone = (first[..., 3] > 0.99) & (halved[..., 3] < 0.01)
    checks.check(gone.sum() > 100, "upper half deleted: nothing is drawn where it was",
                 "%d pixels empty now" % gone.sum())
    halved_mesh = ball.data
    ball.data = original
    bpy.data.meshes.remove(halved_mesh)
    original.name = "Ball"
    s.expect("the mesh put back", False, first)

    # A vertex moved in Edit Mode, then back.
    sdtest.select_only([ball])
    bpy.ops.object.mode_set(mode='EDIT')
    mesh = bmesh.from_edit_mesh(ball.data)
    top = max(mesh.verts, key=lambda v: v.co.z)
    where = top.co.copy()
    top.co.z += 0.5
    bmesh.update_edit_mesh(ball.data)
    s.expect("a vertex moved in Edit Mode", True)
    top.co = where
    bmesh.update_edit_mesh(ball.data)
    s.expect("the vertex moved back in Edit Mode", False, first)
    bpy.ops.object.mode_set(mode='OBJECT')
    s.expect("back in Object Mode", False, first)

    # A modifier added, then removed.
    modifier = ball.modifiers.new("Subdivision", 'SUBSURF')
    modifier.levels = 1
    s.expect("a Subdivision Surface added", True)
    ball.modifiers.remove(modifier)
    s.expect("the modifier removed", False, first)

    # An animated shape key: baked at frame 1, where its value is 0; at frame 10 it is 1.
    ball.shape_key_add(name="Basis")
    key = ball.shape_key_add(name="Stretch")
    for point in key.data:
        point.co.z *= 1.5
    key.value = 0.0
    key.keyframe_insert("value", frame=1)
    key.value = 1.0
    key.keyframe_insert("value", frame=10)
    scene.frame_set(1)
    s.expect("an animated shape key at the baked frame", False, first)
    scene.frame_set(10)
    s.expect("the shape key at frame 10", True)
    scene.frame_set(1)
    s.expect("the baked frame again", False, first)

    # A re-bake at frame 10 fits frame 10's mesh.
    scene.frame_set(10)
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake at frame 10")
    s.expect("re-baked at frame 10", False)
    scene.frame_set(1)
    s.expect("frame 1 after the bake at frame 10", True)
    scene.sd_lighting.live_rebake = True
    texts = "\n".join(sdtest.panel_texts())
    checks.check("re-baking" in texts and "bake again" not in texts,
                 "with Live Re-bake on the panel says it is re-baking")
    scene.sd_lighting.live_rebake = False

    # A record from before the check: taken as it is.
    for holder in (ball, package.store.baked.baked_mesh(ball)):
        record = dict(holder["sd_bake"])
        del record["source"]
        holder["sd_bake"] = record
    package.live.staleness.forget()
    checks.check("Ball" in s.drawn(), "a record without a source is drawn as it is")
    return checks.summary()


if __name__ == "__main__":
    sdtest.run(main)
