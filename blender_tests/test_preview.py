"""sd_lighting.render_preview: the still shows the shaded mesh with contact shadows, agrees with the
CPU evaluator at the projected vertices, follows the world's rotation, and writes scene-linear EXR
and Standard-view-transform PNG.
Run (headless, GPU through a Workbench render):
    blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_preview.py -- --zip Z --out DIR
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

WIDTH, HEIGHT = 640, 480


def render(package, path):
    """Runs the operator; returns the scene-linear image (EXR) or the 8-bit one (PNG)."""
    result = bpy.ops.sd_lighting.render_preview(filepath=path, width=WIDTH, height=HEIGHT)
    assert result == {'FINISHED'}, result
    if path.endswith(".png"):
        return package.live.preview.read_png(path)
    image = bpy.data.images.load(path)
    pixels = np.empty(WIDTH * HEIGHT * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(HEIGHT, WIDTH, 4)[::-1]


def projected(view, obj, mesh_positions):
    """Pixel coordinates (x, y with rows top-first) and clip depth of the object's vertices."""
    matrix = np.array(obj.matrix_world)
    world = mesh_positions @ matrix[:3, :3].T + matrix[:3, 3]
    clip = np.c_[world, np.ones(len(world))] @ view.view_projection.T
    ndc = clip[:, :3] / clip[:, 3:4]
    x = (ndc[:, 0] + 1.0) * 0.5 * WIDTH
    y = (1.0 - (ndc[:, 1] + 1.0) * 0.5) * HEIGHT
    return x, y


def agreement(package, scene, image, obj):
    """Fraction of the object's on-screen, front-facing vertices whose pixel is within 2 % of the
    CPU value, the median relative difference, and how many vertices were compared."""
    drawing = package.live.drawing
    depsgraph = bpy.context.evaluated_depsgraph_get()
    view = package.scene.view.View.from_camera(scene.camera, depsgraph, WIDTH, HEIGHT, scene)
    mesh = package.store.baked.baked_mesh(obj)
    cpu = drawing.cpu_reference(scene, obj, view)
    x, y = projected(view, obj, package.store.attributes.read_positions(mesh).astype(np.float64))
    matrix = np.array(obj.matrix_world)
    world = package.store.attributes.read_positions(mesh) @ matrix[:3, :3].T + matrix[:3, 3]
    to_eye = view.camera[:3] - world
    to_eye /= np.linalg.norm(to_eye, axis=1)[:, None]
    normals = package.store.attributes.read_normals(mesh) @ matrix[:3, :3].T
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    facing = (to_eye * normals).sum(axis=1) > 0.3
    inside = (x > 2) & (x < WIDTH - 2) & (y > 2) & (y < HEIGHT - 2) & facing
    inside &= unoccluded(scene, depsgraph, view.camera[:3], world)
    inside[inside] &= covered(image, x[inside], y[inside])
    px = sdtest.bilinear(image, x[inside], y[inside])
    reference = cpu[inside]
    relative = np.abs(px - reference).max(axis=1) / np.maximum(np.abs(reference).max(axis=1), 1e-3)
    return float(np.mean(relative < 0.02)), float(np.median(relative)), int(inside.sum())


def unoccluded(scene, depsgraph, eye, points):
    """Points the eye sees (Blender's scene ray cast finds nothing in front of them)."""
    from mathutils import Vector
    out = np.zeros(len(points), dtype=bool)
    for i, point in enumerate(points):
        direction = Vector(point) - Vector(eye)
        distance = direction.length
        hit = scene.ray_cast(depsgraph, Vector(eye), direction.normalized(), distance=distance - 1e-3)
        out[i] = not hit[0]
    return out


def covered(image, x, y):
    """The four pixels around each position are all drawn (alpha 1): no background mixed in."""
    x0, y0 = np.floor(x - 0.5).astype(int), np.floor(y - 0.5).astype(int)
    a = image[..., 3]
    return (a[y0, x0] > 0.5) & (a[y0, x0 + 1] > 0.5) & (a[y0 + 1, x0] > 0.5) & (a[y0 + 1, x0 + 1] > 0.5)


def main():
    checks = sdtest.Checks("test_preview")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)

    scene = sdtest.empty_scene()
    _, mapping = sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    # the formulas through SH alone, as the CPU evaluator has them: forest.exr's two glints would
    # otherwise be shaded on their own (test_source_shadows)
    scene.sd_lighting.source_shadows = False
    ball = sdtest.ico_sphere(scene, subdivisions=3, location=(0.0, 0.0, 0.75), radius=0.75)
    ground = sdtest.grid(scene, cuts=24, size=4.0)
    white = sdtest.diffuse_material("White")     # the preview shows B itself
    for obj in (ball, ground):
        obj.data.materials.append(white)
    sdtest.camera(scene, location=(0.0, -5.0, 2.5), target=(0.0, 0.0, 0.5))
    settings = sdtest.bake_settings(scene, 'msd_visibility', 'LAMBERT', 4, 2, rays=128,
                                    select=[ball, ground])
    scene.view_settings.view_transform = 'Standard'
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake")

    exr = render(package, os.path.join(args.out, "preview.exr"))
    png = render(package, os.path.join(args.out, "preview.png"))
    checks.check(exr.shape == (HEIGHT, WIDTH, 4) and png.shape == (HEIGHT, WIDTH, 4),
                 "preview written as EXR and PNG at the requested size")
    covered = exr[..., 3] > 0.5
    checks.check(0.2 < covered.mean() < 0.99, "the mesh covers the frame, background transparent",
                 "%.0f %% covered" % (100 * covered.mean()))
    checks.check(np.isfinite(exr).all() and exr[covered][:, :3].max() > 0.05,
                 "shaded pixels are finite and lit", "max %.3f" % exr[covered][:, :3].max())

    # PNG = sRGB(2^exposure B) of the EXR's values (Standard view transform).
    expected = package.live.preview.display_rgba8(exr, scene.view_settings.exposure)
    difference = np.abs(expected.astype(int) - png.astype(int)).max()
    checks.check(difference <= 1, "PNG holds the sRGB-encoded scene-linear values", "max diff %d" % difference)
    scene.view_settings.exposure = 1.0
    brighter = render(package, os.path.join(args.out, "preview_exposure.png"))
    expected = package.live.preview.display_rgba8(exr, 1.0)
    difference = np.abs(expected.astype(int) - brighter.astype(int)).max()
    checks.check(difference <= 1 and brighter[..., :3].mean() > png[..., :3].mean(),
                 "exposure +1 doubles the radiance before the sRGB curve", "max diff %d" % difference)
    scene.view_settings.exposure = 0.0

    # Contact shadows: the ground right under the ball is darker than the open ground.
    for obj, label in ((ground, "ground"), (ball, "ball")):
        fraction, median, count = agreement(package, scene, exr, obj)
        checks.check(fraction > 0.95 and median < 0.005,
                     "preview = CPU evaluator at the %s's projected vertices" % label,
                     "%.0f %% of %d within 2 %%, median %.2e" % (100 * fraction, count, median))
    drawing = package.live.drawing
    depsgraph = bpy.context.evaluated_depsgraph_get()
    view = package.scene.view.View.from_camera(scene.camera, depsgraph, WIDTH, HEIGHT, scene)
    ground_values = drawing.cpu_reference(scene, ground, view).mean(axis=1)
    co = package.store.attributes.read_positions(package.store.baked.baked_mesh(ground))
    r = np.hypot(co[:, 0], co[:, 1])
    contact, open_ground = ground_values[r < 0.45].mean(), ground_values[r > 1.5].mean()
    checks.check(contact < 0.6 * open_ground, "contact shadow under the ball",
                 "%.3f under vs %.3f open" % (contact, open_ground))
    # In the picture: the darkest visible ground near the ball against the open ground.
    x, y = projected(view, ground, co.astype(np.float64))
    on_screen = (x > 2) & (x < WIDTH - 2) & (y > 2) & (y < HEIGHT - 2)
    seen = np.zeros(len(co), dtype=bool)
    pixels = np.zeros(len(co))
    pixels[on_screen] = sdtest.bilinear(exr, x[on_screen], y[on_screen]).mean(axis=1)
    seen[on_screen] = np.abs(pixels[on_screen] - ground_values[on_screen]) < 0.02 * ground_values[on_screen]
    near, far = seen & (r < 1.0), seen & (r > 1.5)
    checks.check(near.any() and far.any() and pixels[near].min() < 0.6 * np.median(pixels[far]),
                 "contact shadow visible in the preview",
                 "darkest visible ground near the ball %.3f vs open ground %.3f" % (
                     pixels[near].min() if near.any() else -1, np.median(pixels[far]) if far.any() else -1))

    # Rotating the world changes the preview accordingly.
    mapping.inputs["Rotation"].default_value[2] = math.radians(90.0)
    rotated = render(package, os.path.join(args.out, "preview_rotated.exr"))
    change = np.abs(rotated[..., :3] - exr[..., :3])[covered].mean() / exr[..., :3][covered].mean()
    checks.check(change > 0.05, "rotating the world's Mapping node changes the preview",
                 "mean change %.0f %%" % (100 * change))
    for obj, label in ((ground, "ground"), (ball, "ball")):
        fraction, median, count = agreement(package, scene, rotated, obj)
        checks.check(fraction > 0.95 and median < 0.005,
                     "rotated preview = CPU evaluator with g = Rz(90) (%s)" % label,
                     "%.0f %% within 2 %%, median %.2e" % (100 * fraction, median))
    settings.environment_rotation = (0.0, 0.0, math.radians(45.0))
    checks.check(abs(mapping.inputs["Rotation"].default_value[2] - math.radians(45.0)) < 1e-6,
                 "the panel's rotation slider drives the world's Mapping node")

    # Turning the world by g (looked up at g d) and the whole scene, camera included, by g leaves
    # the picture unchanged.
    from mathutils import Matrix
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(60.0))
    turned = render(package, os.path.join(args.out, "preview_turned_world.exr"))
    back = Matrix.Rotation(math.radians(60.0), 4, 'Z')
    for obj in (ball, ground, scene.camera):
        obj.matrix_world = back @ obj.matrix_world
    bpy.context.view_layer.update()
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, 0.0)
    turned_scene = render(package, os.path.join(args.out, "preview_turned_scene.exr"))
    both = (turned[..., 3] > 0.5) & (turned_scene[..., 3] > 0.5)
    difference = np.abs(turned - turned_scene)[both][:, :3]
    checks.check(np.median(difference) < 1e-4 * max(1.0, float(turned[both][:, :3].mean())) and
                 abs(both.mean() - covered.mean()) < 0.02,
                 "world turned by g = scene turned by g (same picture)",
                 "median diff %.2e, 99th pct %.2e" % (np.median(difference), np.percentile(difference, 99)))
    return checks.summary()


sdtest.run(main)
