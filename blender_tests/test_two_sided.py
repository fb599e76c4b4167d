"""Faces seen from behind (issue 32, item 2): a mesh whose faces point the wrong way shades as its
correctly wound twin, and a face seen from behind shows its own side.

- A ball on a ground, the ground's faces pointing down: the ground is baked on both sides (every
  face doubled), and from above the preview shades it as the ground pointing up, within the bake's
  noise (block differences of the previews); before, it was 0.07 - 0.16 of it.
- From below, the ground shows its lower side: lit by the lower half of the world, without the
  ball's shadow (which the upper side shows from above).
- A flat-shaded ball with every other face reversed: the reversed faces are turned round (none
  doubled, a closed solid) and the preview equals the correctly wound ball's; before, a black
  checkerboard.
- A ground at the foot of a one-sided wall that faces away from it: the ground's vertices at the
  wall's foot get the ambient occlusion they get with the wall facing the ground; before, 0.
- Backface Culling on the ground's material: no face gets a reverse copy.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_two_sided.py -- --zip Z --out DIR
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

SIZE = 96
BLOCK = 4
RAYS = 1024
NOISE = 0.04   # the worst block's difference between two bakes of one surface (1024 rays each)


ABOVE, BELOW, TARGET = (0.0, -5.0, 4.0), (0.0, -5.0, -4.0), (0.0, 0.0, 0.3)


def aim(camera, location, target=TARGET):
    from mathutils import Vector
    camera.location = location
    camera.rotation_euler = (Vector(target) - Vector(location)).to_track_quat('-Z', 'Y').to_euler()


def bake(objects):
    sdtest.select_only(objects)
    return bpy.ops.sd_lighting.bake() == {'FINISHED'}


def record(package, obj):
    return package.store.baked.record(obj)


def reverse_faces(obj, every=1):
    """Reverses the winding (and so the normals) of every `every`-th face of the object's mesh."""
    import bmesh
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bmesh.ops.reverse_faces(bm, faces=[f for i, f in enumerate(bm.faces) if i % every == 0])
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()


def worst_block(image, reference):
    mask = sdtest.covered(image, reference)
    return float(sdtest.block_differences([image], reference, mask, BLOCK)[0].max())


def wall_foot_occlusion(package, scene, ground, facing_ground):
    """The ground's baked ambient occlusion at its vertices along x = 2, where a one-sided wall
    stands facing the ground (-x) or away from it (+x)."""
    wall = sdtest.grid(scene, name="Wall", cuts=4, size=4.0, location=(2.0, 0.0, 2.0))
    wall.rotation_euler = (0.0, -np.pi / 2 if facing_ground else np.pi / 2, 0.0)
    bpy.context.view_layer.update()
    normal = np.array(wall.matrix_world.to_3x3() @ wall.data.polygons[0].normal)
    ok = bake([ground])
    mesh = package.store.baked.baked_mesh(ground)
    positions = package.store.attributes.read_positions(mesh)
    normals = package.store.attributes.read_normals(mesh)
    foot = (np.abs(positions[:, 0] - 2.0) < 1e-6) & (np.abs(positions[:, 1]) < 1.5) & (normals[:, 2] > 0.5)
    occlusion = package.store.attributes.read(mesh)["ambient_occlusion"][foot]
    bpy.data.objects.remove(wall)
    return ok, normal, occlusion


def main():
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    checks = sdtest.Checks("test_two_sided")
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ground = sdtest.grid(scene, cuts=16, size=4.0)
    ball = sdtest.ico_sphere(scene, subdivisions=2, location=(0.0, 0.0, 0.75), radius=0.75)
    camera = sdtest.camera(scene, location=ABOVE, target=TARGET)
    sdtest.bake_settings(scene, "prt_diffuse", 'LAMBERT', 4, rays=RAYS)

    # The ground pointing up, then down.
    checks.check(bake([ground, ball]), "bake the ground and the ball")
    faces = len(ground.data.polygons)
    up = sdtest.preview(os.path.join(args.out, "ground_up.exr"), width=SIZE, height=SIZE)
    aim(camera, BELOW)
    below_up = sdtest.preview(os.path.join(args.out, "ground_up_below.exr"), width=SIZE, height=SIZE)
    aim(camera, ABOVE)
    checks.check((record(package, ground).faces_doubled, record(package, ground).faces_flipped) == (faces, 0) and
                 (record(package, ball).faces_doubled, record(package, ball).faces_flipped) == (0, 0),
                 "an open ground is baked on both sides, a closed ball on its outside only",
                 "ground %d doubled of %d, ball %d doubled" % (record(package, ground).faces_doubled, faces,
                                                                record(package, ball).faces_doubled))
    reverse_faces(ground)
    checks.check(bake([ground, ball]), "bake the ground pointing down and the ball")
    down = sdtest.preview(os.path.join(args.out, "ground_down.exr"), width=SIZE, height=SIZE)
    difference = worst_block(down, up)
    checks.check(difference < NOISE, "from above, a ground pointing down shades as one pointing up",
                 "worst %dx%d block %.1f %%" % (BLOCK, BLOCK, 100 * difference))

    # From below: the lower side, the same for either winding, and without the ball's shadow.
    aim(camera, BELOW)
    below_down = sdtest.preview(os.path.join(args.out, "ground_down_below.exr"), width=SIZE, height=SIZE)
    aim(camera, ABOVE)
    difference = worst_block(below_down, below_up)
    lit = sdtest.covered(below_up)
    luminance = below_up[..., :3].mean(axis=2)[lit]
    spread = float(luminance.std() / luminance.mean()) if lit.any() else 1.0
    above = up[..., :3].mean(axis=2)[sdtest.covered(up)]
    checks.check(lit.sum() > 100 and difference < NOISE and spread < 0.5 * float(above.std() / above.mean()),
                 "from below the ground shows its lower side, unshadowed, for either winding",
                 "%d pixels, worst block %.1f %% between windings, spread %.3f below and %.3f above"
                 % (lit.sum(), 100 * difference, spread, float(above.std() / above.mean())))

    # A flat ball with every other face reversed.
    bpy.data.objects.remove(ball)
    flat = sdtest.ico_sphere(scene, name="Flat", subdivisions=2, location=(0.0, 0.0, 0.75), radius=0.75,
                             smooth=False)
    reverse_faces(ground)
    checks.check(bake([flat]), "bake the flat ball")
    wound = sdtest.preview(os.path.join(args.out, "flat.exr"), width=SIZE, height=SIZE)
    reverse_faces(flat, every=2)
    checks.check(bake([flat]), "bake the flat ball with every other face reversed")
    chequered = sdtest.preview(os.path.join(args.out, "flat_chequered.exr"), width=SIZE, height=SIZE)
    difference = worst_block(chequered, wound)
    flat_faces = len(flat.data.polygons)
    checks.check(difference < NOISE and record(package, flat).faces_flipped == (flat_faces + 1) // 2 and
                 record(package, flat).faces_doubled == 0,
                 "a ball with every other face reversed shades as the ball, its reversed faces turned round",
                 "worst block %.1f %%, %d of %d turned, %d doubled"
                 % (100 * difference, record(package, flat).faces_flipped, flat_faces,
                    record(package, flat).faces_doubled))
    bpy.data.objects.remove(flat)

    # A one-sided wall facing away from the ground.
    sdtest.bake_settings(scene, "ambient_occlusion", 'LAMBERT', 2, rays=RAYS)
    ok_facing, normal_facing, facing = wall_foot_occlusion(package, scene, ground, True)
    ok_away, normal_away, away = wall_foot_occlusion(package, scene, ground, False)
    checks.check(ok_facing and ok_away and normal_facing[0] < -0.99 and normal_away[0] > 0.99 and
                 len(away) == len(facing) > 0 and np.abs(away - facing).max() < 0.03 and facing.min() > 0.2,
                 "at the foot of a wall facing away, the ground sees what it sees with the wall facing it",
                 "AO %s facing away, %s facing the ground" % (np.round(away, 3), np.round(facing, 3)))

    # Backface Culling: the material says the ground is seen from its front only.
    material = sdtest.diffuse_material("Culled")
    material.use_backface_culling = True
    ground.data.materials.append(material)
    checks.check(bake([ground]) and record(package, ground).faces_doubled == 0,
                 "with Backface Culling on its material the ground gets no reverse copies",
                 "%d doubled" % record(package, ground).faces_doubled)
    return checks.summary()


if __name__ == "__main__":
    sdtest.run(main)
