"""Texture-space data (issue 8, item 3b; bake/lightmap.py): a ball on a ground of one quad (four
vertices: per vertex the ground cannot show the ball's contact shadow) baked with a lightmap.
Checks: the baked copy's UV map and the texels' mesh; the preview shows the contact shadow the
per-vertex bake cannot; the preview at ground pixels equals the CPU evaluation of the texels,
blended bilinearly at each pixel's lightmap UV; save and reload keep it; Clear Bake removes the
texels too; MSD (13) bakes per vertex; outside Object Mode, or while a thread of the add-on's
computes (background.quiet), the bake refuses and changes nothing.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_texture_space.py -- --zip Z --out DIR
"""

import os
import sys
import threading

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

WIDTH, HEIGHT = 320, 240
SIZE = 256
BALL = np.array([0.0, 0.0, 0.75]), 0.75      # centre, radius


def ground_pixels(view):
    """Pixels whose centre's ray meets the ground plane z = 0 inside the 4 x 4 quad, clear of the
    ball (its silhouette with a margin): (rows, columns, points on the ground [P, 3])."""
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
    ndc = np.stack([(x + 0.5) / WIDTH * 2 - 1, 1 - (y + 0.5) / HEIGHT * 2, np.ones_like(x, float),
                    np.ones_like(x, float)], axis=-1).reshape(-1, 4)
    far = ndc @ np.linalg.inv(view.view_projection).T
    far = far[:, :3] / far[:, 3:]
    eye = np.asarray(view.camera[:3], dtype=np.float64)
    direction = far - eye
    t = -eye[2] / direction[:, 2]
    points = eye + t[:, None] * direction
    centre, radius = BALL
    along = np.clip(((centre - eye) * direction).sum(axis=1) / (direction ** 2).sum(axis=1), 0.0, t)
    miss = np.linalg.norm(eye + along[:, None] * direction - centre, axis=1) > 1.1 * radius
    keep = (t > 0) & (np.abs(points[:, 0]) < 1.9) & (np.abs(points[:, 1]) < 1.9) & miss
    return y.ravel()[keep], x.ravel()[keep], points[keep]


def lightmap_uv(mesh, package, local_points):
    """The ground's lightmap UV at points of its plane: the UVs of the upward triangle holding each
    point (not its reverse copy: bake/sides.py), blended by its barycentric coordinates there."""
    positions = package.store.attributes.read_positions(mesh).astype(np.float64)
    loops = package.store.attributes.read_triangle_loops(mesh)
    corners = package.store.attributes.read_triangles(mesh)
    uvs = package.store.attributes.read_loop_uvs(mesh, "SD Lightmap").astype(np.float64)
    out = np.full((len(local_points), 2), np.nan)
    for triangle, loop in zip(corners, loops):
        a, b, c = positions[triangle][:, :2]
        d, e, q = b - a, c - a, local_points[:, :2] - a
        area = d[0] * e[1] - d[1] * e[0]
        if area <= 0.0:
            continue
        b1 = (q[:, 0] * e[1] - q[:, 1] * e[0]) / area
        b2 = (d[0] * q[:, 1] - d[1] * q[:, 0]) / area
        inside = (b1 >= 0) & (b2 >= 0) & (b1 + b2 <= 1)
        out[inside] = ((1 - b1 - b2)[inside, None] * uvs[loop[0]] + b1[inside, None] * uvs[loop[1]]
                       + b2[inside, None] * uvs[loop[2]])
    return out


def bilinear_texels(values, entries, uv):
    """The stored texels' values [K, 3] (texels `entries`) blended as the shader does at lightmap
    UVs: bilinear over the four around, those stored, divided by their weight."""
    row = np.full(SIZE * SIZE, -1)
    row[entries] = np.arange(len(entries))
    t = uv * SIZE - 0.5
    base = np.floor(t).astype(int)
    f = t - base
    out, total = np.zeros((len(uv), 3)), np.zeros(len(uv))
    for dx, dy in ((0, 0), (1, 0), (0, 1), (1, 1)):
        weight = (f[:, 0] if dx else 1 - f[:, 0]) * (f[:, 1] if dy else 1 - f[:, 1])
        x = np.clip(base[:, 0] + dx, 0, SIZE - 1)
        y = np.clip(base[:, 1] + dy, 0, SIZE - 1)
        tap = row[y * SIZE + x]
        weight = np.where(tap >= 0, weight, 0.0)
        out += weight[:, None] * values[np.maximum(tap, 0)]
        total += weight
    return out / np.where(total > 0, total, 1.0)[:, None]


def chart_gap(package, mesh):
    """The least distance (in texels, Chebyshev) between texel centres of different charts of the
    baked mesh's lightmap: each chart (a UV island of "SD Lightmap") rasterized as the bake does."""
    import bmesh
    from bpy_extras.bmesh_utils import bmesh_linked_uv_islands
    bm = bmesh.new()
    bm.from_mesh(mesh)
    layer = bm.loops.layers.uv["SD Lightmap"]
    label = np.full(SIZE * SIZE, -1)
    for chart, faces in enumerate(bmesh_linked_uv_islands(bm, layer)):
        corners = []
        for face in faces:
            uvs = [tuple(loop[layer].uv) for loop in face.loops]
            corners += [(uvs[0], uvs[k], uvs[k + 1]) for k in range(1, len(uvs) - 1)]
        label[package.bake.lightmap.texels(np.array(corners), SIZE, SIZE)[0]] = chart
    bm.free()
    grid = label.reshape(SIZE, SIZE)
    for distance in range(1, package.bake.lightmap.MARGIN_TEXELS + 1):
        for dy in range(-distance, distance + 1):
            for dx in range(-distance, distance + 1):
                a = grid[max(dy, 0):SIZE + min(dy, 0), max(dx, 0):SIZE + min(dx, 0)]
                b = grid[max(-dy, 0):SIZE + min(-dy, 0), max(-dx, 0):SIZE + min(-dx, 0)]
                if np.any((a >= 0) & (b >= 0) & (a != b)):
                    return distance
    return package.bake.lightmap.MARGIN_TEXELS + 1


def check_chart_gap(checks, package, obj):
    """Charts MARGIN_TEXELS apart in UV: their texel centres at least one less apart by rows or
    columns (a diagonal neighbour)."""
    least = package.bake.lightmap.MARGIN_TEXELS - 1
    gap = chart_gap(package, package.store.baked.baked_mesh(obj))
    checks.check(gap >= least, "%s: the texels of two charts at least %d texels apart" % (obj.name, least),
                 "nearest %d apart" % gap)


def main():
    checks = sdtest.Checks("test_texture_space")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    baked = package.store.baked

    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    scene.sd_lighting.source_shadows = False   # the texels' SH formulas alone, as the CPU evaluates them
    ball = sdtest.ico_sphere(scene, subdivisions=3, location=tuple(BALL[0]), radius=BALL[1])
    ground = sdtest.grid(scene, cuts=1, size=4.0)
    white = sdtest.diffuse_material("White")
    for obj in (ball, ground):
        obj.data.materials.append(white)
    sdtest.camera(scene, location=(0.0, -5.0, 2.5), target=(0.0, 0.0, 0.5))
    settings = sdtest.bake_settings(scene, 'prt_diffuse', 'LAMBERT', 2, rays=256, select=[ball, ground])

    # Per vertex: the ground's four corners are far from the ball.
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "per-vertex bake")
    per_vertex = sdtest.preview(os.path.join(args.out, "per_vertex.exr"), width=WIDTH, height=HEIGHT)

    settings.texture_space = True
    settings.lightmap_size = str(SIZE)
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake with texture-space data")
    for obj in (ball, ground):
        mesh = baked.baked_mesh(obj)
        texels = baked.lightmap_mesh(mesh)
        record = baked.record(obj)
        uv = package.store.attributes.read_loop_uvs(mesh, "SD Lightmap") if "SD Lightmap" in mesh.uv_layers else None
        checks.check(uv is not None and uv.min() >= 0.0 and uv.max() <= 1.0,
                     "%s: the baked copy has the lightmap UV map, inside [0, 1]" % obj.name)
        entries = package.store.attributes.read_texels_entries(texels) if texels is not None else np.zeros(0)
        checks.check(texels is not None and
                     0 < (record.lightmap_texels or 0) <= len(texels.vertices) == record.lightmap_stored and
                     np.all(np.diff(entries) > 0) and 0 <= entries.min() and entries.max() < SIZE * SIZE and
                     {"sd_transfer_000", "sd_ambient_occlusion", "sd_normal"} <= set(texels.attributes.keys()),
                     "%s: a texels' mesh of the texels stored, each with its entry and the method's "
                     "attributes" % obj.name, "%d texels baked, %d stored of %d" % (
                         record.lightmap_texels or 0, len(entries), SIZE * SIZE))
        if obj == ball:
            check_chart_gap(checks, package, obj)
        data = package.store.attributes.read(texels, record)
        checks.check(np.all((data["ambient_occlusion"] >= 0) & (data["ambient_occlusion"] <= 1)) and
                     np.isfinite(data["transfer"]).all(), "%s: texel AO in [0, 1], transfer finite" % obj.name)

    # The contact shadow, which the texels carry and the vertices cannot.
    lit = sdtest.preview(os.path.join(args.out, "texture_space.exr"), width=WIDTH, height=HEIGHT)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    view = package.scene.view.View.from_camera(scene.camera, depsgraph, WIDTH, HEIGHT, scene)
    rows, columns, points = ground_pixels(view)
    r = np.hypot(points[:, 0], points[:, 1])
    near, open_ground = (r > 0.3) & (r < 0.6), r > 1.5
    for image, label, expected in ((lit, "texture space", True), (per_vertex, "per vertex", False)):
        brightness = image[rows, columns, :3].mean(axis=1)
        ratio = np.median(brightness[near]) / np.median(brightness[open_ground])
        checks.check((ratio < 0.8) == expected, "%s: the ball's contact shadow on the ground %s"
                     % (label, "shows" if expected else "does not show (four vertices)"),
                     "ground near the ball / open ground = %.3f (%d, %d pixels)"
                     % (ratio, near.sum(), open_ground.sum()))

    # The shader's texels: the CPU's B at each texel, blended bilinearly at the pixel's UV.
    mesh = baked.baked_mesh(ground)
    cpu = package.live.drawing.cpu_reference(scene, ground, view, texels=True)
    entries = package.store.attributes.read_texels_entries(package.store.baked.lightmap_mesh(mesh))
    uv = lightmap_uv(mesh, package, points)
    inside = np.isfinite(uv).all(axis=1) & (lit[rows, columns, 3] > 0.5)
    expected = bilinear_texels(cpu, entries, uv[inside])
    gpu = lit[rows[inside], columns[inside], :3]
    relative = np.abs(gpu - expected).max(axis=1) / np.maximum(expected.max(axis=1), 1e-3)
    checks.check(inside.sum() > 1000 and np.percentile(relative, 99) < 0.01,
                 "preview = CPU evaluation of the texels at the pixels' lightmap UVs",
                 "%d pixels, median %.1e, 99th percentile %.1e" % (inside.sum(), np.median(relative),
                                                                    np.percentile(relative, 99)))

    # Save and reload: the texels stay with the bake, and shade the same.
    path = os.path.join(args.out, "texture_space.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    ball, ground = bpy.data.objects["Ball"], bpy.data.objects["Ground"]
    reloaded = sdtest.preview(os.path.join(args.out, "texture_space_reloaded.exr"), width=WIDTH, height=HEIGHT)
    checks.check(baked.lightmap_mesh(baked.baked_mesh(ground)) is not None and
                 float(np.abs(reloaded - lit).max()) < 1e-5, "save and reload keep the texels and the picture",
                 "max diff %.2e" % float(np.abs(reloaded - lit).max()))

    # Outside Object Mode the unwrap cannot run: the bake refuses and nothing changes.
    scene = bpy.context.scene
    sdtest.select_only([ball, ground])
    bpy.ops.object.mode_set(mode='EDIT')     # a round trip first: 4.x adds selection attributes
    bpy.ops.object.mode_set(mode='OBJECT')
    before = sdtest.snapshot()
    bpy.ops.object.mode_set(mode='EDIT')
    result, text = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
    bpy.ops.object.mode_set(mode='OBJECT')
    after = sdtest.snapshot()
    checks.check(result == {'CANCELLED'} and "Object Mode" in text and after == before,
                 "in Edit Mode the bake refuses with a message and changes nothing",
                 "%s, %s; changed: %s" % (result, text.strip().splitlines()[-1][-100:] if text.strip() else "",
                                          [k for k in set(before) | set(after) if before.get(k) != after.get(k)]))

    # A lightmap whose data would not fit one GPU texture: refused before anything is baked.
    scene.sd_lighting.method = 'prt_matrix'      # 49 x 16 floats per texel
    scene.sd_lighting.light_order, scene.sd_lighting.visibility_order = 6, 3
    scene.sd_lighting.lightmap_size = '1024'
    before = sdtest.snapshot()
    result, text = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
    checks.check(result == {'CANCELLED'} and "smaller lightmap" in text and sdtest.snapshot() == before,
                 "a lightmap too large for the GPU is refused, nothing changes",
                 text.strip().splitlines()[-1][-120:] if text.strip() else "")
    scene.sd_lighting.lightmap_size = str(SIZE)

    scene.sd_lighting.light_order = scene.sd_lighting.visibility_order = 2

    # While a thread of the add-on's computes, the unwrap (operators under a context override,
    # which Blender reads without the GIL while another thread holds it) does not run: it waits,
    # here QUIET_SECONDS = 0.5 s, then the bake refuses and nothing changes.
    held = threading.Event()
    work = package.background.Background("test_texture_space hold")
    work.get("held", lambda: held.wait(30))
    unwrap, saved = package.bake.unwrap, package.bake.unwrap.QUIET_SECONDS
    unwrap.QUIET_SECONDS = 0.5
    before = sdtest.snapshot()
    try:
        result, text = sdtest.operator_reports(bpy.ops.sd_lighting.bake)
    finally:
        unwrap.QUIET_SECONDS = saved
        held.set()
    checks.check(result == {'CANCELLED'} and "test_texture_space hold" in text and sdtest.snapshot() == before
                 and work.wait(30), "while the add-on's thread computes the unwrap waits, then the bake "
                 "refuses and changes nothing", text.strip().splitlines()[-1][-120:] if text.strip() else "")

    # MSD (13): per-vertex designs only, no texels.
    scene.sd_lighting.method = 'msd_visibility'
    scene.sd_lighting.visibility_order = 2
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'} and
                 baked.lightmap_mesh(baked.baked_mesh(ground)) is None and
                 not any(m.name.startswith("SD Lightmap") for m in bpy.data.meshes),
                 "MSD (13) bakes per vertex: no texels, the previous ones removed")

    scene.sd_lighting.method = 'ambient_occlusion'
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'} and
                 baked.lightmap_mesh(baked.baked_mesh(ground)) is not None, "AO bakes texels")

    # A flat cube: six charts, which Smart UV Project's default margin packs about a texel apart.
    box = sdtest.flat_cube(scene, "Box", 0.5, (1.5, 1.5, 0.25))
    sdtest.select_only([box])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'} and baked.lightmap_mesh(baked.baked_mesh(box)),
                 "Box: bakes texels")
    check_chart_gap(checks, package, box)

    sdtest.select_only([ball, ground, box])
    checks.check(bpy.ops.sd_lighting.clear_bake() == {'FINISHED'} and
                 not any(m.name.startswith("SD ") for m in bpy.data.meshes),
                 "Clear Bake removes the baked meshes and their texels")
    return checks.summary()


sdtest.run(main)
