"""Instances and copies (issue 32, item 4): what the depsgraph instances occludes a bake and is drawn
with its bake; a copy drawn elsewhere than its bake was made is named.

A ball stands on a ground; the ball's collection is also instanced by an Empty 2 units aside.
- The ground baked (ambient occlusion, 256 rays): under the instance its ambient occlusion is that
  of a real copy of the ball standing there (and well below the open ground's);
- the ball baked: its instance is drawn shaded in the preview, as the ball itself is (not in the
  flat grey of unbaked meshes), and the report names it as drawn away from where the ball was
  baked (the ground's shadow on it is the ball's);
- a linked copy (Alt+D) turned upside down shares the bake: the panel and the report name it, the
  ball itself is not named; an object moved after its bake is named too, one without occluders not.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_instances.py -- --zip Z --out DIR
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

WIDTH, HEIGHT = 200, 120
ASIDE = (2.0, 0.0, 0.0)


def ambient_occlusion_below(package, ground, point):
    """The ground's baked ambient occlusion at its vertex nearest to `point` (x, y)."""
    mesh = package.store.baked.baked_mesh(ground)
    positions = package.store.attributes.read_positions(mesh)
    nearest = int(np.argmin(np.linalg.norm(positions[:, :2] - np.asarray(point), axis=1)))
    return float(package.store.attributes.read(mesh)["ambient_occlusion"][nearest])


def bake(objects):
    sdtest.select_only(objects)
    return bpy.ops.sd_lighting.bake() == {'FINISHED'}


def main():
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    checks = sdtest.Checks("test_instances")
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ground = sdtest.grid(scene, cuts=32, size=6.0)
    ball = sdtest.ico_sphere(scene, subdivisions=3, location=(0.0, 0.0, 0.75), radius=0.75)
    sdtest.camera(scene, location=(1.0, -6.0, 3.0), target=(1.0, 0.0, 0.5))
    props = bpy.data.collections.new("Props")
    scene.collection.children.link(props)
    props.objects.link(ball)                  # in the scene and in Props
    empty = bpy.data.objects.new("Instance", None)
    empty.instance_type = 'COLLECTION'
    empty.instance_collection = props
    empty.location = ASIDE
    scene.collection.objects.link(empty)

    sdtest.bake_settings(scene, "ambient_occlusion", 'LAMBERT', 2, rays=256)
    checks.check(bake([ground]), "bake the ground")
    under_instance = ambient_occlusion_below(package, ground, ASIDE[:2])
    open_ground = ambient_occlusion_below(package, ground, (-2.5, -2.5))
    empty.instance_type = 'NONE'
    copy = ball.copy()
    copy.location = (ASIDE[0], ASIDE[1], 0.75)
    scene.collection.objects.link(copy)
    checks.check(bake([ground]), "bake the ground with a real copy there")
    under_copy = ambient_occlusion_below(package, ground, ASIDE[:2])
    checks.check(abs(under_instance - under_copy) < 0.01 and under_instance < 0.6 * open_ground,
                 "a collection instance occludes the ground as a real copy does",
                 "AO %.3f under the instance, %.3f under a copy, %.3f in the open"
                 % (under_instance, under_copy, open_ground))
    bpy.data.objects.remove(copy)
    empty.instance_type = 'COLLECTION'

    sdtest.bake_settings(scene, "prt_diffuse", 'LAMBERT', 4, rays=128)
    checks.check(bake([ball, ground]), "bake the ball and the ground")
    scene.sd_lighting.live_shading = True
    drawing = package.live.drawing
    bpy.context.evaluated_depsgraph_get()
    instances = drawing.baked_instances(scene, drawing.baked_objects(scene))
    checks.check(len(instances) == 1 and instances[0][0] == ball and
                 np.allclose(np.array(instances[0][1])[:3, 3], (ASIDE[0], ASIDE[1], 0.75)),
                 "the ball's instance is drawn with its bake, where it stands",
                 str([(obj.name, tuple(np.array(m)[:3, 3])) for obj, m in instances]))
    path = os.path.join(args.out, "instances.exr")
    result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.render_preview, filepath=path,
                                              width=WIDTH, height=HEIGHT)
    image = sdtest.load_exr(path)
    grey = np.all(np.abs(image[..., :3] - package.live.preview.OTHER_MESH_GREY) < 1e-6, axis=2)
    # The ball itself moved to where its instance stood: the same pixels there.
    empty.instance_type = 'NONE'
    ball.location = (ASIDE[0], ASIDE[1], 0.75)
    alone = sdtest.preview(os.path.join(args.out, "instances_ball_moved.exr"), width=WIDTH, height=HEIGHT)
    ball.location = (0.0, 0.0, 0.75)
    empty.instance_type = 'COLLECTION'
    view = package.scene.view.View.from_camera(scene.camera, bpy.context.evaluated_depsgraph_get(),
                                               WIDTH, HEIGHT, scene)
    clip = view.view_projection @ np.array((ASIDE[0], ASIDE[1], 0.75, 1.0))
    x = int((clip[0] / clip[3] + 1.0) * 0.5 * WIDTH)
    y = int((1.0 - (clip[1] / clip[3] + 1.0) * 0.5) * HEIGHT)
    window = np.s_[y - 5:y + 6, x - 5:x + 6]
    difference = float(np.abs(image[window] - alone[window]).max())
    checks.check(result == {'FINISHED'} and grey.sum() == 0 and difference < 1e-4,
                 "the preview shades the instance as the ball standing there (nothing flat grey)",
                 "max difference %.2g over 11 x 11 pixels, %d grey pixels" % (difference, grey.sum()))
    checks.check("1 instance of Ball" in reports and "shadows on Ball," not in reports,
                 "the report names the instance as away from where the ball was baked", reports.strip())

    # A linked copy upside down (Alt+D shares the mesh and its bake).
    linked = ball.copy()
    linked.name = "Linked"
    linked.location = (-2.0, 0.0, 1.0)
    linked.rotation_euler = (math.pi, 0.0, 0.0)
    scene.collection.objects.link(linked)
    bpy.context.view_layer.update()
    bpy.context.view_layer.objects.active = linked
    texts = "\n".join(sdtest.panel_texts())
    result, reports = sdtest.operator_reports(bpy.ops.sd_lighting.render_preview, filepath=path,
                                              width=WIDTH, height=HEIGHT)
    checks.check(package.store.baked.baked_mesh(linked) == package.store.baked.baked_mesh(ball) and
                 "Not where it was baked" in texts and "Linked" in reports,
                 "a linked copy turned upside down: the panel and the report name it", reports.strip())
    bpy.context.view_layer.objects.active = ball
    texts = "\n".join(sdtest.panel_texts())
    checks.check("Not where it was baked" not in texts, "the ball itself is not named")
    bpy.data.objects.remove(linked)

    ball.location.z += 0.5
    bpy.context.view_layer.update()
    moved = package.store.baked.placed_elsewhere(ball)
    ball.location.z -= 0.5
    ground.hide_viewport = True
    empty.hide_viewport = True
    checks.check(bake([ball]), "bake the ball alone")
    ball.location.z += 0.5
    bpy.context.view_layer.update()
    checks.check(moved and not package.store.baked.placed_elsewhere(ball),
                 "moved after its bake: named while other objects occluded it, not when none did")
    return checks.summary()


if __name__ == "__main__":
    sdtest.run(main)
