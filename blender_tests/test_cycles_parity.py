"""Parity with Cycles on real assets the project did not make (issue 8, item 7).

Assets, from Debian's assimp-testmodels, imported with Blender's own importers:
- engine: glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb, a CAD model (pistons, crank,
  plates; hard edges, large flat faces), white Diffuse BSDF;
- house:  OBJ/regr01.obj, a 3ds Max house (walls, rafters; flat faces), as in the accuracy report,
  white;
- wuson:  PLY/Wuson.ply, a smooth character (a triangle soup: every face has its own corners), an
  orange Diffuse BSDF (colour, not only luminance).
Each stands on nothing, scaled to about 4 units, filling the view of a camera from above the
front, lit by forest.exr and sunrise.exr (a low sun: hard shadows) - the engine by sunrise.exr
only: its bake at the defaults is the longest here (about a minute and a half with the other core
busy), and the hard shadows are the harder case.

For each asset and HDRI: Cycles as a user compares (direct light only, pixel filter off, the
mean of two seeds, samples raised until the noise of its 4 x 4 pixel blocks is under 1.5 %) and
the add-on's preview at the panel's defaults (Automatic, Refine and Least Squares on); on the
house under LADDER_HDRI also the ladder - the plain per-vertex bake (Refine and Least Squares
off), Least Squares alone, and texture-space data (a LIGHTMAP x LIGHTMAP lightmap instead of
Refine and Least Squares). What the fit, refinement and texels add is the bake's, shown on one CAD
model under the HDRI with the hardest shadows; blender_tests/benchmark_refine.py measures the
ladder on every asset and HDRI. Over the 4 x 4 blocks both cover: relative RMS (over blocks and
channels), the bias (mean over the mean of Cycles, per channel) and the share of blocks that are
black where Cycles is lit; per pixel, the mean HDR-FLIP (sdtest.perceptual_error), which sees the
shadow edges and shading detail that block averages smooth. Error images (Cycles, then each
preview and its |difference| x 4) go to --out.

Checks: Cycles' noise is under 1.5 %; on the ladder the least-squares fit lowers the plain
bake's error and refinement lowers it further, and texture-space data is within the same goal as
the defaults; no block is black where Cycles is lit; with the defaults each asset is within issue
8's goal (5 % on the CAD models, 3 % on the smooth one), its FLIP under the asset's bound (the
measured value and a margin: a regression in shading detail the RMS misses fails here), and its
bake takes at most twice the panel's prediction; the coloured asset's mean colour follows Cycles' channel by channel; the panel
tells what the refinement did.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_cycles_parity.py -- --zip Z --out DIR
"""

import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import accuracy_scenes  # noqa: E402

MODELS = "/usr/share/assimp/models"
SIZE = 160
BLOCK = 4
SAMPLES = 256
MAX_NOISE = 0.015
HDRIS = ("forest.exr", "sunrise.exr")
LADDER_HDRI = "sunrise.exr"   # the ladder's HDRI and asset (the module's doc)
LADDER_ASSET = "house"
LIGHTMAP = 1024      # the texture-space bake's lightmap side, on the ladder
ORANGE = (0.8, 0.35, 0.1, 1.0)

# asset: (file, colour, the largest relative RMS against Cycles at the defaults, its HDRIs, the
# largest mean HDR-FLIP at the defaults: 0.016-0.027 measured, the plain bake 0.068 on the ladder)
ASSETS = {
    "engine": ("glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb", (1.0, 1.0, 1.0, 1.0), 0.05,
               (LADDER_HDRI,), 0.04),
    "house": ("OBJ/regr01.obj", (1.0, 1.0, 1.0, 1.0), 0.05, HDRIS, 0.04),
    "wuson": ("PLY/Wuson.ply", ORANGE, 0.03, HDRIS, 0.04),
}
Y_UP = ("wuson",)     # files whose up axis is +y (turned to Blender's +z)


def place(obj, scene):
    """Scales the object to 4 units, standing at the origin, and aims a camera from the front
    above so that the object fills the frame."""
    bpy.context.view_layer.update()
    corners = np.array([obj.matrix_world @ v.co for v in obj.data.vertices])
    low, high = corners.min(axis=0), corners.max(axis=0)
    scale = 4.0 / float((high - low).max())
    obj.scale = [scale * s for s in obj.scale]
    centre = 0.5 * (low + high) * scale
    obj.location = [a + b for a, b in zip(obj.location, (-centre[0], -centre[1], -low[2] * scale))]
    size = (high - low) * scale
    return frame(scene, np.array([-0.5 * size[0], -0.5 * size[1], 0.0]),
                 np.array([0.5 * size[0], 0.5 * size[1], size[2]]))


def frame(scene, low, high):
    """A camera from the front above whose view holds the box low..high."""
    size = high - low
    target = np.array([0.5 * (low[0] + high[0]), 0.5 * (low[1] + high[1]), low[2] + 0.5 * size[2]])
    radius = 0.5 * float(np.linalg.norm(size))
    lens = 35.0
    distance = 1.05 * radius / math.sin(math.atan(18.0 / lens))   # the sphere around it in view
    direction = np.array([0.55, -0.75, 0.37]) / np.linalg.norm([0.55, -0.75, 0.37])
    return sdtest.camera(scene, location=tuple(target + distance * direction), target=tuple(target),
                         lens=lens)


def build(name):
    path, colour = ASSETS[name][:2]
    scene = sdtest.empty_scene()
    world, _ = sdtest.hdri_world(scene, sdtest.hdri(ASSETS[name][3][0]), rotation_z=math.radians(30.0))
    if name == "house":
        obj = accuracy_scenes.house(scene)[0][0]
    else:
        obj, _ = sdtest.imported(os.path.join(MODELS, path))
        if name in Y_UP:
            obj.rotation_euler = (math.pi / 2.0, 0.0, 0.0)
    place(obj, scene)
    obj.data.materials.clear()
    obj.data.materials.append(sdtest.diffuse_material("Colour", colour))
    texture = next(n for n in world.node_tree.nodes if n.type == 'TEX_ENVIRONMENT')
    return scene, obj, texture


def cycles(scene, stem):
    samples = SAMPLES
    while True:
        # Cycles' own importance map, as the README's parity numbers were measured with
        image, noise = sdtest.cycles_pair(scene, stem, SIZE, samples, BLOCK, importance_map=None)
        if noise < MAX_NOISE or samples >= 16 * SAMPLES:
            return image, noise, samples
        samples *= 4


def preview(scene, obj, refine, path, least_squares=True, lightmap=0, before_bake=None):
    """Bakes the object at the panel's settings with Refine and Least Squares on or off, and
    with texture-space data of a lightmap of that side (0: none), and renders the preview: (the
    image, the bake's `sd_bake` with the operator's wall-clock seconds as "wall_seconds").
    before_bake: None, or called once the settings are made and the object selected."""
    settings = scene.sd_lighting
    settings.refine = refine
    settings.least_squares = least_squares
    settings.texture_space = bool(lightmap)
    if lightmap:
        settings.lightmap_size = str(lightmap)
    sdtest.select_only([obj])
    if before_bake is not None:
        before_bake()
    start = time.perf_counter()
    if bpy.ops.sd_lighting.bake(go_ahead=True) != {'FINISHED'}:
        raise RuntimeError("the bake of %s failed" % obj.name)
    seconds = time.perf_counter() - start
    settings.live_shading = True
    if bpy.ops.sd_lighting.render_preview(filepath=path, width=SIZE, height=SIZE) != {'FINISHED'}:
        raise RuntimeError("render_preview failed for " + path)
    return sdtest.load_exr(path), dict(obj["sd_bake"], wall_seconds=seconds)


def compare(ours, theirs):
    """(relative RMS, bias per channel, the share of blocks black where Cycles is lit) over the
    blocks both cover."""
    rms, bias, a, b = sdtest.block_error(ours, theirs, BLOCK)
    lit = b.mean(axis=1) > 0.1 * b.mean()
    black = float(np.mean(a[lit].mean(axis=1) < 0.2 * b[lit].mean(axis=1)))
    return rms, bias, black


def error_image(path, theirs, images):
    """Cycles | each preview | its |difference| x 4, side by side, as a PNG."""
    panels = [theirs[..., :3]]
    for image in images:
        panels += [image[..., :3], 4.0 * np.abs(image[..., :3] - theirs[..., :3])]
    strip = np.concatenate(panels, axis=1)
    height, width = strip.shape[:2]
    rgba = np.concatenate([np.clip(strip, 0.0, 1.0), np.ones((height, width, 1))], axis=2)
    image = bpy.data.images.new("parity", width, height, alpha=True, float_buffer=True)
    image.pixels.foreach_set(rgba[::-1].astype(np.float32).ravel())
    image.filepath_raw = path
    image.file_format = 'PNG'
    image.save()
    bpy.data.images.remove(image)


def main():
    args = sdtest.arguments()
    sdtest.flip_module()   # before the renders: it says how to install it
    package = sdtest.install_addon(args.zip)
    os.makedirs(args.out, exist_ok=True)
    checks = sdtest.Checks("test_cycles_parity")
    names = os.environ.get("SD_PARITY_ASSETS", ",".join(ASSETS)).split(",")   # a part, by hand
    for name in names:
        scene, obj, texture = build(name)
        for hdri in ASSETS[name][3]:
            ladder = name == LADDER_ASSET and hdri == LADDER_HDRI
            accuracy_scenes.set_hdri(texture, sdtest.hdri(hdri))
            tag = "%s_%s" % (name, hdri[:-4])
            stem = os.path.join(args.out, tag)
            theirs, noise, samples = cycles(scene, stem)
            checks.check(noise < MAX_NOISE, "%s: Cycles' noise under 1.5 %%" % tag,
                         "%.2f %% at %d samples" % (100 * noise, samples))
            textured = []
            if ladder:   # texture-space data instead of more vertices
                image, info = preview(scene, obj, False, stem + "_texture_space.exr", False, LIGHTMAP)
                rms, bias, black = compare(image, theirs)
                textured.append(image)
                print("%s: texture space %d: %.1f %% RMS, bias %s %%, black %.2f %%; %s s = %d; %d texels, "
                      "bake %.2f s" % (tag, LIGHTMAP, 100 * rms, "/".join("%+.1f" % (100 * x) for x in bias),
                                       100 * black, info["method"], info["light_order"],
                                       info.get("lightmap_texels", 0), info["seconds"]), flush=True)
                checks.check(info.get("lightmap_texels", 0) > 0 and rms <= ASSETS[name][2] and black == 0.0,
                             "%s: with a %d x %d lightmap within %.0f %% of Cycles, no block black"
                             % (tag, LIGHTMAP, LIGHTMAP, 100 * ASSETS[name][2]),
                             "%.1f %%, %d texels" % (100 * rms, info.get("lightmap_texels", 0)))
            results = {}
            # (refine, least squares); the defaults last: the panel tells of their refinement below
            configurations = ([(False, False), (False, True)] if ladder else []) + [(True, True)]
            predicted = []

            def predict():   # the panel's bake time at the defaults, once its sampling is done
                predictor = package.ui.prediction.start(bpy.context)
                predictor.join()
                predicted.append(predictor.prediction().seconds)

            for refine, fit in configurations:
                image, info = preview(scene, obj, refine, "%s_%s%s.exr" % (
                    stem, "refined" if refine else "unrefined", "_fit" if fit else ""), fit,
                    before_bake=predict if (refine, fit) == (True, True) else None)
                rms, bias, black = compare(image, theirs)
                flip = sdtest.perceptual_error(image, theirs)
                results[refine, fit] = (image, rms, bias, black, flip)
                defaults_seconds = info["wall_seconds"]   # the defaults come last
                print("%s: refine %s, least squares %s: %.1f %% RMS, bias %s %%, black %.2f %%, FLIP %.3f; %s s = %d, "
                      "%d rays; %d vertices (%s unrefined, %s levels), bake %.2f s, %d bytes per vertex"
                      % (tag, "on " if refine else "off", "on " if fit else "off", 100 * rms,
                         "/".join("%+.1f" % (100 * x) for x in bias), 100 * black, flip, info["method"],
                         info["light_order"], info["rays"], info["vertices"],
                         info.get("unrefined_vertices", "-"), info.get("refine_levels", "-"),
                         info["seconds"], info["bytes_per_vertex"]), flush=True)
            error_image(stem + "_error.png", theirs, [results[c][0] for c in reversed(configurations)] + textured)
            texts = sdtest.panel_texts()
            info = dict(obj["sd_bake"])
            told = "%d -> %d" % (info["unrefined_vertices"], info["vertices"])
            checks.check(told in texts,
                         "%s: the panel tells what the refinement did" % tag, told)
            ratio = defaults_seconds / predicted[0]
            checks.check(ratio <= 2.0, "%s: the bake at the defaults takes at most twice its predicted time" % tag,
                         "%.1f s against %.1f s predicted: %.2f x" % (defaults_seconds, predicted[0], ratio))
            rms, bias, black, flip = results[True, True][1:]
            checks.check(rms <= ASSETS[name][2], "%s: within %.0f %% of Cycles at the defaults"
                         % (tag, 100 * ASSETS[name][2]), "%.1f %%" % (100 * rms))
            checks.check(flip <= ASSETS[name][4], "%s: FLIP at most %.2f at the defaults" % (tag, ASSETS[name][4]),
                         "%.3f" % flip)
            checks.check(black == 0.0, "%s: no block black where Cycles is lit" % tag,
                         "%.2f %%" % (100 * black))
            if ladder:
                plain, fitted = results[False, False][1], results[False, True][1]
                checks.check(fitted < 0.8 * plain, "%s: the least-squares fit lowers the plain bake's error"
                             % tag, "%.1f %% -> %.1f %%" % (100 * plain, 100 * fitted))
                checks.check(rms < fitted, "%s: refinement lowers the error" % tag,
                             "%.1f %% -> %.1f %%" % (100 * fitted, 100 * rms))
            if ASSETS[name][1] != (1.0, 1.0, 1.0, 1.0):
                checks.check(np.abs(bias - bias.mean()).max() < 0.03,
                             "%s: the colour follows Cycles' per channel" % tag,
                             "bias %s %%" % "/".join("%+.1f" % (100 * x) for x in bias))
    return checks.summary()


if __name__ == "__main__":   # benchmark_refine.py imports the scenes and the comparison
    sdtest.run(main)
