"""Sharp Source Shadows against EEVEE (issue 29: our error below EEVEE's on the same scenes), on
Blender 4.2 and later, where EEVEE extracts one sun from the world and shadow-maps it - what a
user would pick instead.

Scene: test_source_shadows' ground, cube and ball (all three baked here, white Diffuse BSDF), at the
panel's defaults, under each HDRI with a sun, lamps or softboxes and under test_source_shadows'
two opposite suns. Per HDRI: our preview, Cycles (two seeds, direct light, pixel filter off; its
noise printed) and EEVEE at its defaults with the world's sun shadow on (World > Sun: Shadow, its
threshold and angle at their defaults; 64 samples), each as relative RMS over 4 x 4 blocks against
Cycles; error images (Cycles, then ours and EEVEE each with its |difference| x 4) go to --out.

Run (a bpy module of 4.2+, with its venv's python):
  ~/.cache/sd-lighting/venv/bpy-4.5.15/bin/python blender_tests/benchmark_eevee_sources.py -- --zip build/sd_lighting.zip --out DIR [--hdris sunrise.exr,...]
Not part of the test suite (about half a minute per HDRI on llvmpipe).
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402

import numpy as np  # noqa: E402

import test_cycles_parity as parity  # noqa: E402
import test_source_shadows as shadows  # noqa: E402

HDRIS = ("sunrise.exr", "city.exr", "interior.exr", "studio.exr", "night.exr", "sunset.exr", "two suns")
EEVEE_SAMPLES = 64


def eevee(scene, path):
    """EEVEE at its defaults with the world's sun extracted and shadowed (4.2+: EEVEE Next)."""
    scene.world.use_sun_shadow = True
    scene.render.engine = 'BLENDER_EEVEE_NEXT' if bpy.app.version < (5, 0, 0) else 'BLENDER_EEVEE'
    scene.eevee.taa_render_samples = EEVEE_SAMPLES
    image = sdtest.render_still(scene, path, shadows.SIZE)
    scene.render.engine = 'CYCLES'
    return image


def eevee_casts_shadows(scene):
    """Whether EEVEE draws shadows on this GPU: the scene under a sun lamp in a dim world shows a
    shadow on the ground (EEVEE Next's shadow maps need GPU features Mesa's llvmpipe lacks, and
    then it draws none, not even a lamp's)."""
    world = scene.world
    scene.world = bpy.data.worlds.new("SD dim world")
    sun = bpy.data.objects.new("SD probe sun", bpy.data.lights.new("SD probe sun", 'SUN'))
    sun.data.energy = 3.0
    sun.rotation_euler = (0.9, 0.0, 0.5)
    scene.collection.objects.link(sun)
    image = eevee(scene, os.path.join(bpy.app.tempdir, "sd_eevee_probe.exr"))
    bpy.data.objects.remove(sun)
    scene.world = world
    y = image[..., :3].mean(axis=-1)[sdtest.covered(image)]
    low, median = np.percentile(y, [5.0, 50.0])
    return low < 0.5 * median


def main():
    args = sdtest.arguments()
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    hdris = argv[argv.index("--hdris") + 1].split(",") if "--hdris" in argv else list(HDRIS)
    if bpy.app.version < (4, 2, 0):
        print("EEVEE extracts a world sun from Blender 4.2 on: run this with a bpy module of 4.2+")
        return 1
    package = sdtest.install_addon(args.zip)
    scene, ground, cube = shadows.scene_setup()
    world, _ = sdtest.hdri_world(scene, sdtest.hdri("sunrise.exr"))
    texture = world.node_tree.nodes["Environment Texture"]
    meshes = [obj for obj in scene.objects if obj.type == 'MESH']
    if not eevee_casts_shadows(scene):
        import gpu
        print("EEVEE draws no shadows on this GPU (%s), not even a sun lamp's: its column is EEVEE "
              "without shadows - run this where a real GPU is" % gpu.platform.renderer_get(), flush=True)
    print("| HDRI | Cycles' noise | ours | EEVEE | ours, SH alone |")
    print("|---|---|---|---|---|")
    for hdri in hdris:
        path = (shadows.two_suns(package, os.path.join(args.out, "two_suns.exr")) if hdri == "two suns"
                else sdtest.hdri(hdri))
        texture.image = bpy.data.images.load(path, check_existing=True)
        sdtest.select_only(meshes)
        result, _ = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
        assert result == {'FINISHED'}, hdri
        tag = hdri.replace(" ", "_").replace(".exr", "")
        stem = os.path.join(args.out, tag)
        cycles, noise = sdtest.cycles_pair(scene, stem, shadows.SIZE, shadows.SAMPLES, shadows.BLOCK)
        ours = sdtest.preview(stem + "_ours.exr", width=shadows.SIZE, height=shadows.SIZE)
        scene.sd_lighting.source_shadows = False
        sh = sdtest.preview(stem + "_sh.exr", width=shadows.SIZE, height=shadows.SIZE)
        scene.sd_lighting.source_shadows = True
        theirs = eevee(scene, stem + "_eevee.exr")
        mask = sdtest.covered(cycles, ours, theirs)
        errors = [shadows.relative_rms(image, cycles, mask) for image in (ours, theirs, sh)]
        print("| %s | %.2f %% | %.2f %% | %.2f %% | %.2f %% |" % ((hdri, 100 * noise) + tuple(100 * e for e in errors)),
              flush=True)
        parity.error_image(stem + "_cycles_ours_eevee.png", cycles, [ours, theirs])
    return 0


if __name__ == "__main__":
    sdtest.run(main)
