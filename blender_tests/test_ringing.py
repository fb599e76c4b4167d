"""Ringing (issue 12): a glossy ball (Phong sigma = 61, s = 16) under Blender's sunrise.exr, whose
sun rings the truncated B below zero. The live shading's Automatic window lowers the displayed
error there (and says so in the panel's line), and no pixel or vertex is ever negative: the shader
clamps B at 0 per channel, as drawing.cpu_reference does, so GPU = CPU holds with the window and
without.
Run (headless, GPU through a Workbench render):
    blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_ringing.py -- --zip Z --out DIR
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

TOLERANCE = 1e-3          # GPU float32 vs CPU float64, as test_gpu_matches_cpu
TEXTURE_TOLERANCE = 1e-3  # the band-limited texture's bilinear lookup, as test_gpu_matches_cpu
WIDTH, HEIGHT = 320, 240


def main():
    checks = sdtest.Checks("test_ringing")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    drawing = package.drawing
    package.gpu_context.ensure()

    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("sunrise.exr"))
    ball = sdtest.ico_sphere(scene, subdivisions=4, location=(0.0, 0.0, 1.0))
    sdtest.camera(scene)
    settings = sdtest.bake_settings(scene, 'unshadowed', 'PHONG', 16, 0, rays=16, phong_exponent=61.0,
                                    select=[ball])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    view = drawing.View.from_camera(scene.camera, depsgraph, WIDTH, HEIGHT, scene)

    checks.check(settings.ringing_window == 'AUTOMATIC', "the ringing window is Automatic by default")
    choice = drawing.ringing_choice(scene, ball)
    line = package.utils.ringing.describe(choice, "automatic")
    checks.check(choice["window"] != "none" and choice["error"] < choice["unwindowed_error"] and
                 choice["min_over_max"] > choice["unwindowed_min_over_max"],
                 "Automatic picks a window that lowers the displayed error and lifts the negative part",
                 line)

    clamped = {}
    for setting in ('NONE', 'AUTOMATIC'):
        settings.ringing_window = setting
        cpu = drawing.cpu_reference(scene, ball, view)
        clamped[setting] = int((cpu == 0.0).any(axis=1).sum())
        for per_pixel in (False, True):
            gpu = drawing.gpu_vertex_values(scene, ball, view, per_pixel=per_pixel)
            relative, _ = sdtest.relative_error(gpu, cpu)
            checks.check(relative <= TOLERANCE and gpu.min() >= 0.0,
                         "GPU = CPU, nothing negative: %s %s" % (setting, "per-pixel" if per_pixel else "per-vertex"),
                         "max rel %.2e, min GPU %.3g" % (relative, gpu.min()))
        settings.per_pixel = False
        image = package.preview.render(scene, depsgraph, bpy.context.view_layer, WIDTH, HEIGHT)
        covered = image[..., 3] > 0.5
        checks.check(covered.mean() > 0.05 and np.isfinite(image).all() and image[covered][:, :3].min() >= 0.0,
                     "preview (%s): no negative pixel" % setting,
                     "%.0f %% covered, min %.3g, max %.3g" % (100 * covered.mean(), image[covered][:, :3].min(),
                                                               image[covered][:, :3].max()))
    checks.check(clamped['NONE'] > 0 and clamped['AUTOMATIC'] < clamped['NONE'],
                 "without a window B rings below zero at some vertices (shown as 0); the window lifts most",
                 "vertices with a channel clamped to 0: %d without, %d with the window of %d" % (
                     clamped['NONE'], clamped['AUTOMATIC'], len(ball.data.vertices)))

    # The band-limited texture holds the same windowed L~ as the SH sums (MSD 12 at s + s' = 8:
    # a small lobe design), so GPU (texture) = CPU (SH) with the window and without.
    sdtest.bake_settings(scene, 'msd_lobe', 'PHONG', 8, 0, rays=16, phong_exponent=61.0, select=[ball])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake MSD (12), s = 8")
    settings.band_limited_texture = True
    for setting in ('NONE', 'AUTOMATIC'):
        settings.ringing_window = setting
        window = drawing.ringing_choice(scene, ball)["window"]
        cpu = drawing.cpu_reference(scene, ball, view)
        gpu = drawing.gpu_vertex_values(scene, ball, view)
        relative, _ = sdtest.relative_error(gpu, cpu)
        checks.check(relative <= TEXTURE_TOLERANCE and (window != "none") == (setting == 'AUTOMATIC'),
                     "band-limited texture = CPU: %s (window %s)" % (setting, window),
                     "max rel %.2e" % relative)
    return checks.summary()


sdtest.run(main)
