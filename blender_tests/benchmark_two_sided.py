"""Faces seen from behind against Cycles (issue 32, item 2): each wrongly wound case of
test_two_sided beside its correctly wound twin, the preview at the panel's defaults for a Lambert
surface (PRT (2), s = 6, 2048 rays) against Cycles (direct light, pixel filter off, two seeds until
its noise is under 1.5 %: test_cycles_parity's comparison, 4 x 4-pixel blocks).

Printed per case: relative RMS, bias and the share of blocks black where Cycles is lit, with
Cycles' own noise. The twins' lines should agree; before the fix a ground pointing down shaded
0.07 - 0.16 of one pointing up, a flat ball with every other face reversed was a black
checkerboard, and a wall facing away blackened the ground at its foot.

--mesh PATH: a model file (OBJ, PLY, STL, glTF) instead of the ball, 1.5 units across, shaded
smooth on the ground and flat with every other face reversed; --hdri: one of Blender's studio
lights (forest.exr by default).

Run: blender -b --factory-startup --python blender_tests/benchmark_two_sided.py -- --zip build/sd_lighting.zip --out DIR
         [--mesh PATH] [--hdri NAME.exr]
Not part of the test suite (about 2 minutes).
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402
import test_cycles_parity as parity  # noqa: E402
import test_two_sided as two_sided  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

SIZE = 128


def row(name, scene, objects, out):
    sdtest.select_only(objects)
    assert bpy.ops.sd_lighting.bake(go_ahead=True) == {'FINISHED'}, name
    scene.sd_lighting.live_shading = True
    stem = os.path.join(out, name.replace(" ", "_").replace(",", ""))
    ours = sdtest.preview(stem + ".exr", width=SIZE, height=SIZE)
    theirs, noise, samples = parity.cycles(scene, stem)
    rms, bias, black = parity.compare(ours, theirs)
    print("%-40s relative RMS %5.1f %%  bias %+5.1f %%  black blocks %4.1f %%  (Cycles noise %.1f %%, %d spp)"
          % (name, 100 * rms, 100 * float(np.mean(bias)), 100 * black, 100 * noise, samples))


def subject(scene, path, smooth, name):
    """The ball, or the model at `path` 1.5 units across, standing on the ground."""
    if path is None:
        return sdtest.ico_sphere(scene, name=name, subdivisions=3 if smooth else 2, location=(0.0, 0.0, 0.75),
                                 radius=0.75, smooth=smooth)
    obj = sdtest.sized_model(path, 1.5, (0.0, 0.0, 0.0))
    obj.location.z = -min(v.co.z for v in obj.data.vertices)
    obj.data.polygons.foreach_set("use_smooth", [smooth] * len(obj.data.polygons))
    obj.data.materials.clear()
    obj.name = name
    return obj


def main():
    args = sdtest.arguments()
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--mesh", default=None)
    parser.add_argument("--hdri", default="forest.exr")
    extra, _ = parser.parse_known_args(argv)
    sdtest.install_addon(args.zip)
    parity.SIZE = SIZE
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri(extra.hdri))
    ground = sdtest.grid(scene, cuts=16, size=4.0)
    ball = subject(scene, extra.mesh, True, "Ball")
    sdtest.camera(scene, location=two_sided.ABOVE, target=two_sided.TARGET)
    white = sdtest.diffuse_material("White")
    for obj in (ground, ball):
        obj.data.materials.append(white)
    sdtest.bake_settings(scene, "prt_diffuse", 'LAMBERT', 6, rays=2048)
    what = "ball" if extra.mesh is None else os.path.basename(extra.mesh)
    row("ground up, " + what, scene, [ground, ball], args.out)
    two_sided.reverse_faces(ground)
    row("ground pointing down, " + what, scene, [ground, ball], args.out)
    two_sided.reverse_faces(ground)
    bpy.data.objects.remove(ball)
    flat = subject(scene, extra.mesh, False, "Flat")
    flat.data.materials.append(white)
    row("flat %s on the ground" % what, scene, [flat, ground], args.out)
    two_sided.reverse_faces(flat, every=2)
    row("flat %s, every other face reversed" % what, scene, [flat, ground], args.out)
    bpy.data.objects.remove(flat)
    for name, angle in (("wall facing the ground", -np.pi / 2), ("wall facing away", np.pi / 2)):
        wall = sdtest.grid(scene, name="Wall", cuts=4, size=4.0, location=(2.0, 0.0, 2.0))
        wall.rotation_euler = (0.0, angle, 0.0)
        wall.data.materials.append(white)
        row(name, scene, [ground, wall], args.out)
        bpy.data.objects.remove(wall)
    return 0


if __name__ == "__main__":
    sdtest.run(main)
