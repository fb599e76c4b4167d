"""Glossy Principled materials against Cycles (issue 28): the prefiltered GGX light (the split sum
with the bake's visibility ratio, the default) beside the seed's Phong lobe truncated at order s.

Scenes: a smooth sphere in gold (metallic 1) at roughness 0.05, 0.15, 0.3 and 0.5, in red plastic
at 0.2, in Blender's default material (grey, roughness 0.5) and in red clay at 0.8; a subdivided
Suzanne in gold (roughness 0.3) on a red plastic floor (0.2), where the shadows and the floor's
reflection of the head need the baked visibility. Each is baked from its materials with MSD (13)
at s = 8, s' = 4 (256 rays, no refinement) and previewed per vertex; Cycles renders it with direct
light, pixel filter off, from two seeds (its noise printed).

--models: also Debian's assimp test models (MODELS: a smooth and a faceted Wuson, the low-poly
spider) in gold, red plastic and polished steel under three HDRIs and again under the suns of
sunrise.exr and city.exr, and the smooth Wuson in Blender's default material under three, baked
at the panel's defaults
(the automatic mode) and 192 pixels wide.

--matrix [HDRI ...]: instead, issue 28's grid alone - the smooth and the faceted Wuson each in gold
(0.3), polished steel (0.15), red plastic (0.2), gold (0.05) and gold and red plastic (0.5) under each HDRI named (default:
MATRIX_HDRIS) at the panel's defaults, 192 pixels; Cycles' and EEVEE's renders are kept and reused
(about 10 minutes on 3.4.1 at first, 4 again; on bpy 4.5 with EEVEE about 25 at first).

Printed per scene: relative RMS of block averages, bias per channel, the mean HDR-FLIP per
pixel (sdtest.perceptual_error: highlights are where RMS and the eye disagree most) and the darkest
block against Cycles' where Cycles is lit (sdtest.darkest_block), truncated (not with --matrix) and
prefiltered, and on Blender 4.2 and later EEVEE's at its defaults (what a user would pick instead; 64 samples,
the world's light and its probes as EEVEE makes them).

Run: blender -b --factory-startup --python blender_tests/benchmark_glossy.py -- --zip build/sd_lighting.zip --out DIR
         [--hdri NAME.exr] [--models | --matrix [HDRI ...] [--roughness R ...]]
(Debian's Blender needs `xvfb-run -a` in front for its GPU; a `bpy` module of 4.2+ runs it with
its venv's python: `~/.cache/sd-lighting/venv/bpy-4.5.15/bin/python blender_tests/benchmark_glossy.py
-- ...`.) Not part of the test suite (about 3 minutes; with EEVEE on llvmpipe about 6).
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

GOLD = (1.0, 0.7, 0.3, 1.0)
RED = (0.8, 0.1, 0.05, 1.0)
SPHERES = [("gold, roughness 0.05", GOLD, 0.05, 1.0), ("gold, roughness 0.15", GOLD, 0.15, 1.0),
           ("gold, roughness 0.3", GOLD, 0.3, 1.0), ("gold, roughness 0.5", GOLD, 0.5, 1.0),
           ("red plastic, roughness 0.2", RED, 0.2, 0.0),
           ("grey, roughness 0.5 (Blender's default material)", (0.8, 0.8, 0.8, 1.0), 0.5, 0.0),
           ("red clay, roughness 0.8", RED, 0.8, 0.0)]


MODELS = [  # Debian's assimp-testmodels: file, material, base colour, roughness, metallic, HDRI
    ("OBJ/WusonOBJ.obj", "gold", GOLD, 0.3, 1.0, "forest.exr"),
    ("PLY/Wuson.ply", "red plastic", RED, 0.2, 0.0, "courtyard.exr"),
    ("OBJ/spider.obj", "steel", (0.6, 0.6, 0.62, 1.0), 0.15, 1.0, "studio.exr"),
    ("OBJ/WusonOBJ.obj", "default material", (0.8, 0.8, 0.8, 1.0), 0.5, 0.0, "forest.exr"),
    ("OBJ/WusonOBJ.obj", "default material", (0.8, 0.8, 0.8, 1.0), 0.5, 0.0, "studio.exr"),
    ("OBJ/WusonOBJ.obj", "default material", (0.8, 0.8, 0.8, 1.0), 0.5, 0.0, "courtyard.exr"),
    # under a sun, whose highlight is shaded on its own
    ("OBJ/WusonOBJ.obj", "gold", GOLD, 0.3, 1.0, "sunrise.exr"),
    ("OBJ/WusonOBJ.obj", "gold", GOLD, 0.05, 1.0, "city.exr"),
    ("PLY/Wuson.ply", "red plastic", RED, 0.2, 0.0, "city.exr"),
    ("OBJ/spider.obj", "steel", (0.6, 0.6, 0.62, 1.0), 0.15, 1.0, "city.exr")]
# --matrix: issue 28's grid - a smooth and a faceted real model, each material at each HDRI
MATRIX_MODELS = [("smooth Wuson", "OBJ/WusonOBJ.obj"), ("faceted Wuson", "PLY/Wuson.ply")]
MATRIX_MATERIALS = [("gold", GOLD, 0.3, 1.0), ("steel", (0.6, 0.6, 0.62, 1.0), 0.15, 1.0),
                    ("red plastic", RED, 0.2, 0.0), ("gold", GOLD, 0.05, 1.0), ("gold", GOLD, 0.5, 1.0),
                    ("red plastic", RED, 0.5, 0.0)]
MATRIX_HDRIS = ["sunrise.exr", "forest.exr", "courtyard.exr", "city.exr", "studio.exr"]


def compare(name, scene, objects, out, size, block, defaults=False, truncated=True, reuse=False):
    """Bakes `objects` (MSD (13), s = 8, s' = 4; defaults: at the panel's defaults), previews them
    with the prefiltered light and (truncated) without, prints the line. reuse: Cycles' (and
    EEVEE's) renders of a run before into `out` (sdtest.cycles_pair), where the name says all the
    scene is."""
    stem = os.path.join(out, "".join(c for c in name.replace(" ", "_") if c.isalnum() or c in "_."))
    cycles, noise = sdtest.cycles_pair(scene, stem, size, 1024, block, reuse=reuse)
    if defaults:
        sdtest.default_settings(scene)
        sdtest.select_only(objects)
    else:
        sdtest.bake_settings(scene, 'msd_visibility', 'MATERIAL', 8, 4, rays=256, select=objects)
    assert bpy.ops.sd_lighting.bake(go_ahead=True) == {'FINISHED'}, name
    images = {}
    for prefiltered in (False, True) if truncated else (True,):
        scene.sd_lighting.prefiltered_glossy = prefiltered
        label = "prefiltered" if prefiltered else "truncated"
        images[label] = sdtest.preview(stem + "_" + label + ".exr", width=size, height=size)
    if bpy.app.version >= (4, 2, 0):
        eevee = stem + "_eevee.exr"
        images["EEVEE"] = sdtest.reused(eevee, size, reuse)
        if images["EEVEE"] is None:
            images["EEVEE"] = eevee_render(scene, eevee, size)
    cells = []
    for label, ours in images.items():
        error, bias, a, b = sdtest.block_error(ours, cycles, block)
        try:
            flip = "%.3f" % sdtest.perceptual_error(ours, cycles)
        except ImportError:   # no FLIP for this CPython (sdtest.flip_module)
            flip = "n/a"
        cells.append("%s %5.1f %% (bias %s %%, FLIP %s, darkest lit block %.2fx)" % (
            label, 100 * error, np.round(100 * bias, 1), flip, sdtest.darkest_block(a, b)))
    print("%-44s %s | Cycles' noise %.2f %%" % (name, " | ".join(cells), 100 * noise), flush=True)


def eevee_render(scene, path, size):
    """EEVEE at its defaults (4.2+: EEVEE Next), transparent film, as cycles_render frames it."""
    scene.render.engine = 'BLENDER_EEVEE_NEXT' if bpy.app.version < (5, 0, 0) else 'BLENDER_EEVEE'
    return sdtest.render_still(scene, path, size)


def matrix(hdris, out, roughnesses=None):
    """Issue 28's grid at the panel's defaults, 192 pixels: MATRIX_MODELS x MATRIX_MATERIALS (those
    of these roughnesses; None: all) under each of `hdris`, one line each (Cycles' renders
    are kept in a folder of `out` per Blender version and reused)."""
    print("glossy grid against Cycles at the panel's defaults (Blender %s)" % bpy.app.version_string)
    out = os.path.join(out, bpy.app.version_string.split()[0])
    os.makedirs(out, exist_ok=True)
    for hdri in hdris:
        for label, path in MATRIX_MODELS:
            for material, colour, roughness, metallic in MATRIX_MATERIALS:
                if roughnesses is not None and roughness not in roughnesses:
                    continue
                scene, model = sdtest.glossy_model_scene(hdri, path, material, colour, roughness, metallic)
                compare("%s, %s (%.2f), %s" % (label, material, roughness, hdri), scene, [model], out, 192, 4,
                        defaults=True, truncated=False, reuse=True)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--hdri", default="forest.exr")
    scenes = parser.add_mutually_exclusive_group()
    scenes.add_argument("--models", action="store_true")
    scenes.add_argument("--matrix", nargs="*", metavar="HDRI",
                        help="only issue 28's grid (MATRIX_*), under these HDRIs (none named: all of MATRIX_HDRIS)")
    parser.add_argument("--roughness", nargs="+", type=float,
                        help="with --matrix: only the materials of these roughnesses")
    args = parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
    os.makedirs(args.out, exist_ok=True)
    sdtest.install_addon(args.zip)
    if args.matrix is not None:
        matrix(args.matrix or MATRIX_HDRIS, args.out, args.roughness)
        return
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri(args.hdri))
    print("glossy against Cycles under %s (MSD (13), s = 8, s' = 4)" % args.hdri)

    sdtest.camera(scene, location=(0.0, -4.2, 0.6), target=(0.0, 0.0, 0.0), lens=55.0)
    ball = sdtest.ico_sphere(scene, "Glossy", subdivisions=5, location=(0.0, 0.0, 0.0))
    for name, colour, roughness, metallic in SPHERES:
        ball.data.materials.clear()
        ball.data.materials.append(sdtest.principled_material(name, colour, roughness, metallic))
        compare("sphere, " + name, scene, [ball], args.out, 120, 6)
    bpy.data.objects.remove(ball)

    sdtest.camera(scene, location=(0.0, -5.0, 2.5), target=(0.0, 0.0, 0.5), lens=45.0)
    bpy.ops.mesh.primitive_monkey_add(size=1.6, location=(0.0, 0.0, 0.9))
    monkey = bpy.context.active_object
    monkey.modifiers.new("Subdivision", 'SUBSURF').levels = 2
    monkey.data.polygons.foreach_set("use_smooth", [True] * len(monkey.data.polygons))
    monkey.data.materials.append(sdtest.principled_material("gold", GOLD, 0.3, 1.0))
    ground = sdtest.grid(scene, cuts=30, size=4.0)
    ground.data.materials.append(sdtest.principled_material("red plastic", RED, 0.2, 0.0))
    compare("gold Suzanne (0.3) on a red plastic floor (0.2)", scene, [monkey, ground], args.out, 160, 4)
    if args.models:
        for path, material, colour, roughness, metallic, hdri in MODELS:
            scene, model = sdtest.glossy_model_scene(hdri, path, material, colour, roughness, metallic)
            compare("%s, %s (%.2f), %s, defaults" % (os.path.basename(path), material, roughness, hdri),
                    scene, [model], args.out, 192, 4, defaults=True)


main()
