"""The preview stays the same when the add-on's GPU programs are freed and compiled again, as a
file load does (registration._on_load). Blender skips binding a shader at the address of the one
bound last, and a new program can get a freed one's address: without gpu_shading.bind's guard
the ground (no material: the 0.8 default surface) drew with its white variant's program after a
reload, 1.25 x too bright (test_default_scene, bpy 5.0.1, now and then). A white ball and that
ground give each object two variants (its first, white, and its albedo's); every cycle frees
them all, so an address is reused in most cycles (measured on bpy 4.2.23, 4.5.15 and 5.0.1
with OpenGL; 5.3's Vulkan binds by other means).
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_shader_rebind.py -- --zip Z --out DIR
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

CYCLES = 8


def main():
    checks = sdtest.Checks("test_shader_rebind")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ground = sdtest.grid(scene, cuts=4)      # drawn first: it compiles the white variant, then its own
    ball = sdtest.ico_sphere(scene, radius=0.75, location=(0.0, 0.0, 0.75))
    ball.data.materials.append(sdtest.diffuse_material("White"))
    sdtest.camera(scene)
    sdtest.bake_settings(scene, "prt_diffuse", 'MATERIAL', 3, rays=64, select=[ball, ground])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake a white ball and a ground without material")

    first = sdtest.preview(os.path.join(args.out, "rebind_0.exr"), width=160, height=120)
    covered = first[..., 3] > 0.5
    checks.check(0.2 < covered.mean() < 0.99, "the preview shows both", "%.0f %% covered" % (100 * covered.mean()))
    differing = []
    for cycle in range(1, CYCLES + 1):
        package.registration._on_load(None)
        image = sdtest.preview(os.path.join(args.out, "rebind_%d.exr" % cycle), width=160, height=120)
        difference = np.abs(image - first).max()
        if difference >= 1e-5:
            differing.append("cycle %d: max diff %.2e, %d pixels" % (
                cycle, difference, np.count_nonzero(np.abs(image - first).max(axis=2) >= 1e-5)))
    checks.check(not differing, "the preview is the same after the GPU programs are compiled again, "
                 "%d times" % CYCLES, "; ".join(differing))
    return checks.summary()


sdtest.run(main)
