"""Viewport frame time of the live shading against Blender's own uniform-colour shader on the same
geometry, for 10k, 100k and 1M vertices, as a ratio (one run).

Each frame draws the mesh into a 1280x720 GPUOffScreen from the same camera and ends with a
one-pixel readback, which waits for the GPU (llvmpipe here) to finish; the time per frame is the
mean over several frames after a warm-up frame. The live shading is the add-on's default method,
MSD Theorem 2.2 (eq. 13) with s = 4, s' = 2 and a Lambert lobe, per vertex (the seed's way) and,
as an extra column, per pixel. Baking 1M vertices would take long, so the per-vertex designs are
synthetic: each vertex gets as many nodes as a vertex of a real bake of a small scene (node counts
drawn from that bake's distribution, stored at their own length like a bake's) - the frame time
depends on the node counts, not on the values.

Run: xvfb-run -a blender --factory-startup --python-exit-code 1 --python blender_tests/benchmark_viewport.py -- --zip Z
     (or blender -b ...: the GPU then comes from a Workbench render)
The tables after the first draw without the bright sources' own shadows (Sharp Source Shadows
off): under forest.exr's sun they are shaded per pixel for a Lambert lobe, the same for every method
(blender_tests/benchmark_source_shadows.py times them), and there they took most of each 100k
frame (README, Accuracy against cost), which hid what the methods' own work costs. A second table compares every method per
vertex at --methods-size vertices (100k), with synthetic per-vertex data of each method's real size
(V~ of order s', M, T, designs), each the median of ROUNDS interleaved rounds (a load elsewhere on
this shared machine moved single runs' ratios by tens of percent); the MSD methods (12), (13)
twice: L~ as an SH sum (exact, default) and looked up in the band-limited texture (the
band-limited texture option). It ends with MSD (13) and (12), SH and texture,
as ratios to PRT (8) and PRT (10). A third table times every method but PRT (2) with the lobes a
material can ask for - Lambert, Phong (sigma 61, a roughness of 0.3) and both, weighted per pixel as
from a Principled BSDF (Lambert + Phong) - as ratios to Lambert alone. A fourth times that
Principled pair with the glossy lobe truncated per vertex against the prefiltered glossy light,
per vertex (with the baked visibility ratio, and with the reflection rays tracing it through the
heightfield's triangles) and per pixel, for PRT (10) at s = 8 and MSD (13) at s = 4, and the same mesh as a metal
of roughness 0.5, whose glossy light is sampled by GLOSSY_TAPS lookups at every pixel
(live/shader_variant.SAMPLED_ROUGHNESS; the plastic's only where the view grazes, SAMPLED_N_DOT_V).

A last table (--model PATH) bakes a real model for real, twice, with MSD (13) and PRT (8) at s = 4,
s' = 2, 256 rays, and times both in interleaved rounds, L~ of MSD (13) as an SH sum and from the
texture: its designs' node counts where the model puts them, neighbours alike or not.

Options after --: --sizes 10000,100000,1000000 --frames 5 --methods-size 100000 (0: skip)
                  --model PATH (e.g. assimp's 2CylinderEngine.glb)
                  --json PATH: the ratios of the "MSD against PRT" and --model tables, with the
                  frames of the built-in shaders, for the accuracy report's Table 1
                  (docs/report/viewport_frames.json)
"""

import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

WIDTH, HEIGHT = 1280, 720
ROUNDS = 3   # interleaved rounds of the every-method table, whose medians it quotes
FEW_RAYS = 8   # the glossy table's cheaper reflection rays, beside the default count


def options():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    out = {"sizes": [10000, 100000, 1000000], "frames": 5, "methods_size": 100000, "model": None, "json": None}
    for i, arg in enumerate(argv):
        if arg == "--sizes":
            out["sizes"] = [int(s) for s in argv[i + 1].split(",")]
        elif arg == "--frames":
            out["frames"] = int(argv[i + 1])
        elif arg == "--methods-size":
            out["methods_size"] = int(argv[i + 1])
        elif arg == "--model":
            out["model"] = argv[i + 1]
        elif arg == "--json":
            out["json"] = argv[i + 1]
    return out


def heightfield(vertex_count):
    """A bumpy n x n grid over [-2, 2]^2 with about vertex_count vertices: positions, unit normals,
    triangles."""
    n = max(2, int(round(vertex_count ** 0.5)))
    xs = np.linspace(-2.0, 2.0, n)
    x, y = np.meshgrid(xs, xs)
    z = 0.15 * np.sin(3.0 * x) * np.cos(2.0 * y)
    dzdx = 0.45 * np.cos(3.0 * x) * np.cos(2.0 * y)
    dzdy = -0.3 * np.sin(3.0 * x) * np.sin(2.0 * y)
    positions = np.c_[x.ravel(), y.ravel(), z.ravel()]
    normals = np.c_[-dzdx.ravel(), -dzdy.ravel(), np.ones(n * n)]
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    triangles = np.concatenate([np.c_[a, a + 1, a + n], np.c_[a + 1, a + n + 1, a + n]]).astype(np.int32)
    return positions, normals, triangles


def synthetic_designs(normals, real_counts, seed=0):
    """Per-vertex designs with node counts drawn from a real bake's, nodes on the upper hemisphere
    of each normal, weights summing to 0.5 (an unoccluded vertex): the shader's work is a real
    bake's."""
    rng = np.random.default_rng(seed)
    n = len(normals)
    counts = rng.choice(np.asarray(real_counts), size=n)
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    owner = np.repeat(np.arange(n), counts)
    directions = rng.normal(size=(offsets[-1], 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    flip = (directions * normals[owner]).sum(axis=1) < 0
    directions[flip] *= -1.0
    weights = 0.5 / counts[owner]
    return offsets, directions, weights


def synthetic_result(package, method, normals, real_counts, s=4, sv=2, seed=0):
    """Per-vertex data of a method's real shapes (values random: the frame time does not depend
    on them)."""
    rng = np.random.default_rng(seed)
    n = len(normals)
    result = {"ambient_occlusion": np.full(n, 0.5)}
    data = package.methods.get(method).data
    if data is not None and data.packing == "design":
        result.update(zip(data.keys, synthetic_designs(normals, real_counts)))
    elif data is not None and data.packing == "coefficients":
        result[data.keys[0]] = rng.normal(scale=0.1, size=(n,) + data.shape(s, sv))
    return result


LAMBERT = {"lobe": "lambert", "exponent": 1.0}


def baked_object(package, scene, positions, normals, triangles, real_counts, method="msd_visibility",
                 lobes=LAMBERT, s=4, sv=2):
    """A mesh object carrying a (synthetic) bake of the method at s, s' with the lobes (sd_bake's
    lobe keys), as the bake operator stores it."""
    mesh = package.store.attributes.new_mesh("Benchmark", positions, triangles.ravel(),
                                       np.arange(0, 3 * len(triangles), 3), np.full(len(triangles), 3))
    result = synthetic_result(package, method, normals, real_counts, s, sv)
    stored = package.store.attributes.write(mesh, normals, result)
    record = package.store.record.BakeRecord.from_dict(dict(
        lobes, method=method, light_order=s, visibility_order=sv, rays=0, seed=0, environment="synthetic",
        refine=False, refine_target=0.0, refine_max_vertices=0, least_squares=False, lightmap=0,
        floats_per_vertex=stored / 4, bytes_per_vertex=stored, bake_id="benchmark-%s-%d-%d-%d-%s" % (method, len(positions), s, sv,
                                                                        sorted(lobes.items()))))
    mesh["sd_bake"] = record.to_dict()
    mesh.use_fake_user = True
    obj = bpy.data.objects.new("Benchmark", mesh)
    scene.collection.objects.link(obj)
    obj["sd_baked_mesh"] = mesh
    obj["sd_bake"] = dict(mesh["sd_bake"])
    return obj


def time_frames(draw, frames):
    """Mean seconds per frame: clear, draw, read one pixel back (waits for the GPU)."""
    import gpu
    from sd_lighting.live import drawing
    offscreen = gpu.types.GPUOffScreen(WIDTH, HEIGHT, format='RGBA16F')
    try:
        def frame():
            drawing.draw_offscreen(offscreen, draw, region=(WIDTH // 2, HEIGHT // 2, 1, 1))
        frame()  # warm-up: shader compilation, uploads
        start = time.perf_counter()
        for _ in range(frames):
            frame()
        return (time.perf_counter() - start) / frames
    finally:
        offscreen.free()


def design_node_counts_of_a_real_bake(package, scene):
    """Per-vertex node counts of a real MSD 2.2 bake (s = 4, s' = 2) of a small scene."""
    ball = sdtest.ico_sphere(scene, subdivisions=2, location=(0.0, 0.0, 0.8), radius=0.7)
    ground = sdtest.grid(scene, cuts=10, size=4.0)
    sdtest.bake_settings(scene, 'msd_visibility', 'LAMBERT', 4, 2, rays=256, select=[ball, ground])
    assert bpy.ops.sd_lighting.bake(go_ahead=True) == {'FINISHED'}
    counts = []
    for obj in (ball, ground):
        counts.append(np.diff(package.store.attributes.read(package.store.baked.baked_mesh(obj))["design_offsets"]))
    for obj in (ball, ground):
        package.store.baked.clear(obj)
        mesh = obj.data
        bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)
    return np.concatenate(counts)


def uniform_drawer(uniform, projection, positions, triangles):
    """(draw function, batch) of Blender's uniform-colour shader on the mesh."""
    return _builtin_drawer(uniform, projection, triangles, {"pos": positions.astype(np.float32)},
                           lambda: uniform.uniform_float("color", (0.8, 0.8, 0.8, 1.0)))


def smooth_colour_drawer(projection, positions, normals, triangles):
    """(draw function, batch) of Blender's smooth-colour shader on the mesh, a colour per vertex: the
    rasteriser's interpolation of a per-vertex colour, which every per-vertex method pays on top of
    its own evaluation (the uniform colour has nothing to interpolate)."""
    import gpu
    shader = gpu.shader.from_builtin('3D_SMOOTH_COLOR' if bpy.app.version < (3, 5, 0) else 'SMOOTH_COLOR')
    colours = np.c_[0.5 + 0.5 * normals, np.ones(len(normals))].astype(np.float32)
    return _builtin_drawer(shader, projection, triangles,
                           {"pos": positions.astype(np.float32), "color": colours}, lambda: None)


def _builtin_drawer(shader, projection, triangles, attributes, set_uniforms):
    import gpu
    from gpu_extras.batch import batch_for_shader
    from mathutils import Matrix
    batch = batch_for_shader(shader, 'TRIS', attributes, indices=triangles)

    def draw():
        with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
            gpu.matrix.load_matrix(Matrix.Identity(4))
            gpu.matrix.load_projection_matrix(projection)
            shader.bind()
            set_uniforms()
            batch.draw(shader)
    return draw, batch


def remove_object(package, obj):
    """Drops the benchmark object, its mesh and the cached GPU data."""
    package.live.drawing.clear_cache()
    mesh = obj.data
    bpy.data.objects.remove(obj)
    package.store.attributes.remove_all(mesh)
    bpy.data.meshes.remove(mesh)


def glossy_table(package, scene, view, mesh, real_counts, frames):
    """The prefiltered glossy light's frame cost (issue 28): Lambert + Phong weighted as from a
    Principled BSDF (roughness 0.3), its lobe truncated at s per vertex (the seed's way) against
    the prefiltered lookup per vertex with the baked visibility ratio, with FEW_RAYS reflection rays
    and with the default count, and per pixel, for PRT (10) at s = 8 and MSD (13) at s = 4."""
    env, shading = package.scene.environment, package.live.gpu_shading
    if shading.prefiltered_texture(env.source(scene), True) is None:
        raise RuntimeError("the prefiltered environment was not made")
    rows, width = package.native.get().prefilter_atlas_shape(*shading.prefiltered_layout())
    sigma = package.scene.lobes.exponent_from_roughness(0.3)
    lobes = {"lobe": "phong", "exponent": sigma, "diffuse_lobe": True, "lobe_weights": True, "diffuse_share": 0.9}
    settings = scene.sd_lighting
    taps = package.live.shader_variant.GLOSSY_TAPS
    rays = package.live.shader_variant.REFLECTION_RAYS
    print("\nThe prefiltered glossy light, %d vertices, Lambert + Phong (roughness 0.3), frame ms "
          "(atlas %d x %d RGBA32F, %.1f MB, and two %d x %d BRDF tables); last column: the lobe of a "
          "metal of roughness 0.5, sampled by %d taps per pixel:" % (
              len(mesh[0]), width, rows, width * rows * 16 / 1e6,
              package.live.shader_variant.BRDF_TABLE_SIZE, package.live.shader_variant.BRDF_TABLE_SIZE, taps))
    print("%-28s %20s %20s %20s %20s %20s %20s" % (
        "method", "truncated / vertex", "prefiltered / vertex", "+ %d rays" % FEW_RAYS, "+ %d rays" % rays,
        "prefiltered / pixel", "sampled metal"))
    metal = sdtest.principled_material("Metal", (0.9, 0.9, 0.9, 1.0), 0.5, 1.0)
    for method, s, sv in (("prt_gaunt", 8, 2), ("msd_visibility", 4, 2)):
        obj = baked_object(package, scene, *mesh, real_counts, method, lobes, s, sv)
        cells = []
        for prefiltered, count, per_pixel in ((False, 0, False), (True, 0, False), (True, FEW_RAYS, False),
                                              (True, rays, False), (True, rays, True)):
            settings.prefiltered_glossy = prefiltered
            settings.reflection_rays = count > 0
            if count:
                settings.reflection_ray_count = str(count)
            cells.append(time_frames(lambda: package.live.drawing.draw_objects(scene, [obj], view, 1.0, per_pixel),
                                     frames if not per_pixel else 1))
        settings.prefiltered_glossy = True
        obj.data.materials.append(metal)
        package.live.drawing.clear_cache()
        cells.append(time_frames(lambda: package.live.drawing.draw_objects(scene, [obj], view, 1.0, False), frames))
        remove_object(package, obj)
        print("%-28s" % ("%s, s = %d" % (package.methods.get(method).label, s)) +
              "".join("%20s" % ("%.2f (%.2fx)" % (1e3 * t, t / cells[0])) for t in cells), flush=True)


def real_model_table(package, scene, view, path, frames):
    """MSD (13) against PRT (8) on a real bake of the model at `path` (3 units across, at the
    origin): each of two copies baked with one method, then both drawn in interleaved rounds.
    Returns the ratios for --json."""
    model = sdtest.sized_model(path, 3.0, (0.0, 0.0, 0.0))
    copy = model.copy()
    copy.data = model.data.copy()
    scene.collection.objects.link(copy)
    baked = {}
    for method, obj in (("msd_visibility", model), ("prt_matrix", copy)):
        sdtest.bake_settings(scene, method, 'LAMBERT', 4, 2, rays=256, select=[obj])
        start = time.perf_counter()
        assert bpy.ops.sd_lighting.bake(go_ahead=True) == {'FINISHED'}
        baked[method] = (obj, time.perf_counter() - start)
    counts = np.diff(package.store.attributes.read(package.store.baked.baked_mesh(model))["design_offsets"])
    cases = (("msd_visibility", False), ("msd_visibility", True), ("prt_matrix", False))
    settings = scene.sd_lighting
    samples = {case: [] for case in cases}
    for _ in range(ROUNDS):
        for method, texture in cases:
            settings.band_limited_texture = texture
            obj = baked[method][0]
            samples[method, texture].append(time_frames(
                lambda: package.live.drawing.draw_objects(scene, [obj], view, 1.0, False), frames))
    settings.band_limited_texture = False
    times = {case: float(np.median(t)) for case, t in samples.items()}
    print("\nMSD (13) against PRT (8) baked, %s, %d vertices, s = 4, s' = 2, 256 rays, Lambert, per vertex "
          "(design nodes: mean %.1f, max %d; medians of %d interleaved rounds):" % (
              os.path.basename(path), len(model.data.vertices), counts.mean(), counts.max(), ROUNDS))
    print("%-44s %10s %10s %12s %10s" % ("", "bake (s)", "bytes/v", "frame (ms)", "/ PRT (8)"))
    for method, texture in cases:
        obj, seconds = baked[method]
        label = package.methods.get(method).label + (
            (", band-limited texture" if texture else ", L~ SH sum") if package.methods.get(method).band_limited_texture else "")
        print("%-44s %10.1f %10.1f %12.2f %10.2f" % (label, seconds, obj["sd_bake"]["bytes_per_vertex"],
                                                    1e3 * times[method, texture],
                                                    times[method, texture] / times["prt_matrix", False]), flush=True)
    return {"model": os.path.basename(path), "vertices": len(model.data.vertices),
            "design_nodes_mean": float(counts.mean()),
            "msd_visibility": {"texture": times["msd_visibility", True] / times["prt_matrix", False],
                               "sh": times["msd_visibility", False] / times["prt_matrix", False]},
            "bytes": baked["msd_visibility"][0]["sd_bake"]["bytes_per_vertex"] /
            baked["prt_matrix"][0]["sd_bake"]["bytes_per_vertex"]}


def main():
    import gpu
    args = sdtest.arguments()
    opts = options()
    package = sdtest.install_addon(args.zip)
    package.live.gpu_context.ensure()
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    camera = sdtest.camera(scene, location=(0.0, -4.5, 3.5), target=(0.0, 0.0, 0.0))
    real_counts = design_node_counts_of_a_real_bake(package, scene)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    view = package.scene.view.View.from_camera(camera, depsgraph, WIDTH, HEIGHT, scene)
    uniform = package.compat.uniform_color_shader()
    from mathutils import Matrix
    projection = Matrix(view.view_projection.tolist())

    print("\nsd_lighting viewport benchmark: %s, %s (%s)" % (
        gpu.platform.renderer_get(), gpu.platform.version_get(), bpy.app.version_string))
    print("MSD Theorem 2.2 (13), s = 4, s' = 2, Lambert; design nodes per vertex as a real bake's: "
          "mean %.1f, max %d; %dx%d, mean of %d frames (per pixel: 1 frame)" % (
              real_counts.mean(), real_counts.max(), WIDTH, HEIGHT, opts["frames"]))
    print("%10s %10s %14s %14s %8s %14s %8s" % ("vertices", "triangles", "uniform (ms)",
                                                "MSD/vertex(ms)", "ratio", "MSD/pixel(ms)", "ratio"))
    rows = []
    # --json: the MSD / PRT frame-time ratios, which the accuracy report's Table 1 quotes
    # (scripts/accuracy_summary.py reads docs/report/viewport_frames.json)
    record = {"renderer": gpu.platform.renderer_get(), "blender": bpy.app.version_string, "rounds": ROUNDS}
    for size in opts["sizes"]:
        positions, normals, triangles = heightfield(size)
        obj = baked_object(package, scene, positions, normals, triangles, real_counts)
        bpy.context.view_layer.update()
        draw_uniform, batch = uniform_drawer(uniform, projection, positions, triangles)

        def draw_msd(per_pixel):
            return lambda: package.live.drawing.draw_objects(scene, [obj], view, 1.0, per_pixel)

        t_uniform = time_frames(draw_uniform, opts["frames"])
        t_vertex = time_frames(draw_msd(False), opts["frames"])
        t_pixel = time_frames(draw_msd(True), 1)
        rows.append((len(positions), len(triangles), t_uniform, t_vertex, t_pixel))
        print("%10d %10d %14.2f %14.2f %8.1f %14.2f %8.1f" % (
            len(positions), len(triangles), 1e3 * t_uniform, 1e3 * t_vertex, t_vertex / t_uniform,
            1e3 * t_pixel, t_pixel / t_uniform), flush=True)
        del batch
        remove_object(package, obj)
    print("ratio = frame time of the live shading / frame time of Blender's uniform-colour shader")

    scene.sd_lighting.source_shadows = False   # the methods' own work (the module's doc)
    if opts["methods_size"]:
        positions, normals, triangles = heightfield(opts["methods_size"])
        draw_uniform, batch = uniform_drawer(uniform, projection, positions, triangles)
        draw_smooth, smooth_batch = smooth_colour_drawer(projection, positions, normals, triangles)
        settings = scene.sd_lighting
        objects = {method.id: baked_object(package, scene, positions, normals, triangles, real_counts, method.id)
                   for method in package.methods.METHODS}
        cases = [(method.id, texture) for method in package.methods.METHODS
                 for texture in ((False, True) if method.band_limited_texture else (False,))]
        # in interleaved rounds, each case's median: a load elsewhere on the machine then falls on
        # every case alike, not on the one it happened to meet
        samples = {case: [] for case in cases + ["uniform", "smooth"]}
        for _ in range(ROUNDS):
            samples["uniform"].append(time_frames(draw_uniform, opts["frames"]))
            samples["smooth"].append(time_frames(draw_smooth, opts["frames"]))
            for method, texture in cases:
                settings.band_limited_texture = texture
                obj = objects[method]
                samples[method, texture].append(time_frames(
                    lambda: package.live.drawing.draw_objects(scene, [obj], view, 1.0, False), opts["frames"]))
        settings.band_limited_texture = False
        times = {case: float(np.median(t)) for case, t in samples.items()}
        t_uniform = times["uniform"]
        print("\nEvery method per vertex, %d vertices, s = 4, s' = 2, Lambert (uniform colour: %.2f ms, "
              "smooth colour: %.2f ms; medians of %d interleaved rounds):" % (
                  len(positions), 1e3 * t_uniform, 1e3 * times["smooth"], ROUNDS))
        print("%-44s %10s %12s %8s" % ("method", "bytes/v", "frame (ms)", "ratio"))
        for method, texture in cases:
            label = package.methods.get(method).label + (", band-limited texture" if texture else "")
            t = times[method, texture]
            print("%-44s %10.1f %12.2f %8.1f" % (label, objects[method]["sd_bake"]["bytes_per_vertex"], 1e3 * t,
                                                 t / t_uniform), flush=True)
        for obj in objects.values():
            remove_object(package, obj)
        del batch, smooth_batch
        width, height = package.live.band_limited_map.texture_size(4)
        print("\nMSD against PRT, %d vertices, s = 4, s' = 2, Lambert, per vertex (frame-time ratios; "
              "band-limited texture %dx%d RGBA32F, bilinear):" % (len(positions), width, height))
        print("%-44s %12s %12s %12s" % ("", "frame (ms)", "/ PRT (8)", "/ PRT (10)"))
        methods = package.methods
        record["synthetic"] = {"vertices": len(positions), "design_nodes_mean": float(real_counts.mean()),
                               "uniform_ms": 1e3 * t_uniform, "smooth_ms": 1e3 * times["smooth"],
                               "frame_ms": {method + ("_texture" if texture else ""): 1e3 * times[method, texture]
                                            for method, texture in cases}}
        for method, base in (("msd_visibility", "prt_matrix"), ("msd_lobe", "prt_gaunt")):
            record["synthetic"][method] = {"texture": times[method, True] / times[base, False],
                                           "sh": times[method, False] / times[base, False]}
        for method, texture in (("msd_visibility", False), ("msd_visibility", True),
                                ("msd_lobe", False), ("msd_lobe", True),
                                ("prt_matrix", False), ("prt_gaunt", False)):
            if (method, texture) not in times:
                continue
            t = times[method, texture]
            label = methods.get(method).label + (
                (", band-limited texture" if texture else ", L~ SH sum")
                if methods.get(method).band_limited_texture else "")
            print("%-44s %12.2f %12.2f %12.2f" % (label, 1e3 * t, t / times["prt_matrix", False],
                                                  t / times["prt_gaunt", False]), flush=True)

        sigma = package.scene.lobes.exponent_from_roughness(0.3)
        lobe_sets = (("Lambert", LAMBERT), ("Phong", {"lobe": "phong", "exponent": sigma}),
                     ("Lambert + Phong", {"lobe": "phong", "exponent": sigma, "diffuse_lobe": True,
                                          "lobe_weights": True, "diffuse_share": 0.9}))
        print("\nWhat the lobes cost, %d vertices, s = 4, s' = 2, per vertex (Phong sigma %.1f; "
              "frame ms, and the ratio to Lambert):" % (len(positions), sigma))
        print("%-28s" % "method" + "".join("%22s" % name for name, _ in lobe_sets))
        for method in package.methods.METHODS:
            if method.lambert_only:
                continue
            cells = []
            for _, lobes in lobe_sets:
                obj = baked_object(package, scene, positions, normals, triangles, real_counts, method.id, lobes)
                cells.append(time_frames(lambda: package.live.drawing.draw_objects(scene, [obj], view, 1.0, False),
                                         opts["frames"]))
                remove_object(package, obj)
            print("%-28s" % method.label + "".join("%14.2f (%4.2fx)" % (1e3 * t, t / cells[0]) for t in cells),
                  flush=True)
        glossy_table(package, scene, view, (positions, normals, triangles), real_counts, opts["frames"])
    if opts["model"]:
        record["baked"] = real_model_table(package, scene, view, opts["model"], opts["frames"])
    if opts["json"]:
        with open(opts["json"], "w") as f:
            json.dump(record, f, indent=1)
        print("\nratios written to", opts["json"])
    return 0


if __name__ == "__main__":   # accuracy_report.py imports time_frames
    sdtest.run(main)
