"""The environment's orientation and the world's Mapping rotation match Blender's own renderer.

A diffuse sphere (albedo 1, convex: no self-shadowing) under the forest HDRI turned by a Mapping
node with a full XYZ Euler rotation is rendered by Cycles and by the add-on's preview with the
unshadowed Lambert formula at s = 8 (Funk-Hecke: B = integral L cos / pi, exactly what Cycles
computes for a white diffuse surface, up to the order-8 truncation, ~1 %). The two agree; a preview
with a different rotation does not (so the comparison can tell orientations apart).
The World Background option draws the same rotated environment behind the sphere as Cycles does
without a transparent film (issue 8, item 6), and leaves the sphere's pixels as they were.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_world_orientation.py -- --zip Z --out DIR
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

SIZE = 96
BLOCK = 6
ROTATION = (math.radians(25.0), math.radians(-35.0), math.radians(70.0))


def main():
    checks = sdtest.Checks("test_world_orientation")
    args = sdtest.arguments()
    sdtest.install_addon(args.zip)

    scene = sdtest.empty_scene()
    _, mapping = sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    mapping.inputs["Rotation"].default_value = ROTATION
    ball = sdtest.ico_sphere(scene, subdivisions=5, radius=1.0, location=(0.0, 0.0, 0.0))
    ball.data.materials.append(sdtest.diffuse_material("White"))
    sdtest.camera(scene, location=(0.0, -4.5, 0.0), target=(0.0, 0.0, 0.0), lens=60.0)

    sdtest.bake_settings(scene, 'unshadowed', 'LAMBERT', 8, rays=16, select=[ball])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake")

    def preview(path):
        assert bpy.ops.sd_lighting.render_preview(filepath=path, width=SIZE, height=SIZE) == {'FINISHED'}
        return sdtest.load_exr(path)

    ours = preview(os.path.join(args.out, "orientation_preview.exr"))
    mapping.inputs["Rotation"].default_value[2] += math.radians(90.0)
    other = preview(os.path.join(args.out, "orientation_preview_other.exr"))
    mapping.inputs["Rotation"].default_value = ROTATION
    cycles = sdtest.cycles_render(scene, os.path.join(args.out, "orientation_cycles.exr"), SIZE)

    scene.sd_lighting.world_background = True
    behind = preview(os.path.join(args.out, "orientation_preview_background.exr"))
    scene.sd_lighting.world_background = False
    cycles_behind = sdtest.cycles_render(scene, os.path.join(args.out, "orientation_cycles_background.exr"),
                                         SIZE, samples=64, transparent=False)
    empty = (ours[..., 3] == 0.0) & (cycles[..., 3] < 0.01)
    sphere = sdtest.covered(ours)
    checks.check(np.all(behind[..., 3] == 1.0) and np.array_equal(behind[sphere], ours[sphere]),
                 "the world background fills every empty pixel and leaves the sphere as it was")
    background, wrong_background = sdtest.block_differences(
        (behind, np.roll(behind, SIZE // 4, axis=1)), cycles_behind, empty, BLOCK)
    checks.check(len(background) > 20 and np.median(background) < 0.02 and np.percentile(background, 90) < 0.05,
                 "the world background = Cycles' world behind the sphere (block averages)",
                 "median %.1f %%, 90th pct %.1f %% over %d blocks; shifted: median %.1f %%" % (
                     100 * np.median(background), 100 * np.percentile(background, 90), len(background),
                     100 * np.median(wrong_background)))
    checks.check(np.median(wrong_background) > 3 * np.median(background),
                 "a background shifted by a quarter of the view differs from Cycles'")

    mask = sdtest.covered(ours, cycles)
    checks.check(mask.mean() > 0.3, "both images show the sphere", "%.0f %% of pixels" % (100 * mask.mean()))
    relative, wrong = sdtest.block_differences((ours, other), cycles, mask, BLOCK)
    a, b = (sdtest.block_averages(image, mask, BLOCK) for image in (ours, cycles))
    checks.check(np.median(relative) < 0.03 and np.percentile(relative, 90) < 0.06,
                 "preview = Cycles for the rotated world (block averages)",
                 "median %.1f %%, 90th pct %.1f %% over %d blocks; mean B %.3f vs Cycles %.3f" % (
                     100 * np.median(relative), 100 * np.percentile(relative, 90), len(relative),
                     a.mean(), b.mean()))
    checks.check(np.median(wrong) > 3 * np.median(relative),
                 "a preview with the world turned another 90 degrees differs from Cycles",
                 "median %.1f %%" % (100 * np.median(wrong)))
    return checks.summary()


sdtest.run(main)
