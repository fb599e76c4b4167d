"""Cycles parity from three sides (issue 29, item 6): test_cycles_parity's assets at the panel's
defaults under each sun or window HDRI, each seen by three cameras - the parity test's, from the
front above, and the same turned 120 and 240 degrees about the vertical - so that the worst case is
quoted, not the one view the test affords.

Per asset and HDRI: one bake (the defaults: Automatic, Refine, Least Squares, Sharp Source
Shadows), then per camera the preview against Cycles (test_cycles_parity.cycles: two seeds, noise
under 1.5 %), relative RMS over 4 x 4 blocks, and the same preview with Sharp Source Shadows off.
Prints one row per view and the worst per asset and HDRI; error images (test_cycles_parity's
strip: Cycles, the preview and its |difference| x 4) go to --out.

Run: blender -b --factory-startup --python blender_tests/benchmark_parity_views.py -- --zip build/sd_lighting.zip
         --out DIR [--assets engine,house,wuson] [--hdris sunrise.exr,city.exr,...]
Not part of the test suite (about a minute per asset, HDRI and view; the engine's bake longer).
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import accuracy_scenes  # noqa: E402
import test_cycles_parity as parity  # noqa: E402

HDRIS = ("sunrise.exr", "sunset.exr", "city.exr", "courtyard.exr", "interior.exr")   # a sun or a window
TURNS = (0.0, 120.0, 240.0)   # degrees about the vertical from the parity test's camera


def option(argv, name, default):
    return argv[argv.index(name) + 1].split(",") if name in argv else list(default)


def turn_camera(camera, target, degrees):
    """The camera moved about the vertical through `target` by `degrees`, still aimed at it."""
    from mathutils import Matrix, Vector
    rotation = Matrix.Rotation(math.radians(degrees), 4, 'Z')
    offset = Vector(camera["sd_start"]) - Vector(target)
    camera.location = Vector(target) + rotation @ offset
    direction = Vector(target) - camera.location
    camera.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()


def main():
    args = sdtest.arguments()
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    sdtest.install_addon(args.zip)
    assets = option(argv, "--assets", parity.ASSETS)
    hdris = option(argv, "--hdris", HDRIS)
    print("| asset | HDRI | view | noise | with the sources | SH alone | bake s | setting |")
    print("|---|---|---|---|---|---|---|---|")
    worst = []
    for name in assets:
        scene, obj, texture = parity.build(name)
        camera = scene.camera
        camera["sd_start"] = tuple(camera.location)
        bpy.context.view_layer.update()
        # turned about the object's bounding box centre (the parity camera aims near it)
        corners = np.array([obj.matrix_world @ v.co for v in obj.data.vertices])
        centre = 0.5 * (corners.min(axis=0) + corners.max(axis=0))
        target = (float(centre[0]), float(centre[1]), float(centre[2]))
        for hdri in hdris:
            accuracy_scenes.set_hdri(texture, sdtest.hdri(hdri))
            settings = scene.sd_lighting
            settings.source_shadows = True
            _, info = parity.preview(scene, obj, True, os.path.join(args.out, "bake.exr"))
            errors = []
            for turn in TURNS:
                turn_camera(camera, target, turn)
                tag = "%s_%s_%03d" % (name, hdri[:-4], int(turn))
                stem = os.path.join(args.out, tag)
                theirs, noise, _ = parity.cycles(scene, stem)
                settings.source_shadows = True
                ours = sdtest.preview(stem + "_sources.exr", width=parity.SIZE, height=parity.SIZE)
                settings.source_shadows = False
                sh = sdtest.preview(stem + "_sh.exr", width=parity.SIZE, height=parity.SIZE)
                settings.source_shadows = True
                rms, _, _ = parity.compare(ours, theirs)
                rms_sh, _, _ = parity.compare(sh, theirs)
                parity.error_image(stem + "_errors.png", theirs, [ours, sh])
                errors.append(rms)
                print("| %s | %s | %+.0f° | %.2f %% | %.2f %% | %.2f %% | %.1f | %s s = %d, %d rays |" % (
                    name, hdri, turn, 100 * noise, 100 * rms, 100 * rms_sh, info["wall_seconds"],
                    info["method"], info["light_order"], info["rays"]), flush=True)
            turn_camera(camera, target, 0.0)
            worst.append((max(errors), name, hdri))
    print("\nWorst view per asset and HDRI, with the sources:")
    for error, name, hdri in sorted(worst, reverse=True):
        print("  %s / %s: %.2f %%" % (name, hdri, 100 * error))
    return 0


if __name__ == "__main__":
    sdtest.run(main)
