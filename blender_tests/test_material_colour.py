"""Material colour and corner data (issue 8, items 4 and 5) against Cycles.

A smooth UV sphere (convex: no self-shadowing) with two material slots - a red Diffuse BSDF on
the upper half, a Diffuse BSDF reading a generated colour-grid image through the sphere's UVs on
the lower half - under forest.exr is rendered by Cycles (direct light, pixel filter off) and by
the add-on's preview with the unshadowed Lambert formula at s = 8, as in test_world_orientation.
The preview multiplies B by each slot's albedo (the image per pixel), so the two agree channel by
channel; the same preview with white materials does not. A colour changed after the bake shows
without baking again (albedos are read at every draw).

Corner data: a flat-shaded cube's baked copy has one vertex per face corner (24) with the face
normals; the smooth sphere keeps its vertices, split only along the material boundary and the UV
seam; a flat-shaded icosphere shades flat like Cycles, unlike the same mesh baked smooth.

Principled BSDFs (GLOSSY): a red plastic (roughness 0.3), gold (metallic 1, roughness 0.4), a
half-metallic blue (roughness 0.3) and a rough blue plastic (0.6) on a smooth icosphere, baked
from the material (Lambert + Phong, Phong alone for the metal, Lambert for the rough plastic with
its specular layer lit live, weighted per pixel by scene/lobes.py) and previewed with the
unshadowed formula at s = 12 and the prefiltered glossy light (the default), against Cycles from
two seeds: relative RMS of block averages and bias per channel within GLOSSY's limits, the gold
also with the world turned and tilted (the prefilter, run in a worker thread, keeps the first
interactive draw waiting for nothing: the truncated lobe is drawn meanwhile, also where the
reflection rays traced the last frame); the gold shown with the seed's truncated Phong lobe instead
is further off, the plastic shown as one Phong lobe of its colour (the add-on before the split)
far off, and the rough plastic with its layer folded into Lambert (no prefiltered light) further off.
The gold's lobe is sampled (live/shader_variant.SAMPLED_ROUGHNESS), the half metal's half of it,
and every sphere's at its rims (SAMPLED_N_DOT_V): with one prefiltered lookup alone the gold and
the half metal were 6.1 and 2.3 % off, over these limits.
Shading normals that mirror the view below their own triangle (BENT; a coarse smooth mesh's rims,
here a closed slab whose front face's custom normals lean 60 degrees from it, seen head-on under
forest.exr): Cycles turns such a normal towards the triangle's until the reflection grazes it, and
the object hides the lobe's lower half; the preview does the same (sd_glossy_normal,
sd_triangle_horizon) within BENT's limits (relative RMS of block averages, bias per channel; the
lobe's hidden half is a share of the lookup, not its own light: 8.7 and 4.7 % measured). Read
about the leaning normals instead, the light came from behind the face, 32-39 % darker than Cycles.
Where the view grazes a glossy lobe (GRAZING; Debian's assimp Wuson at the panel's defaults, the
scenes of benchmark_glossy.py --matrix at 160 pixels): a smooth red plastic (roughness 0.2) under
studio.exr, whose layer reflects the softboxes at its rims, and a faceted gold near-mirror (0.05)
under forest.exr, within GRAZING's limits and no block darker than a quarter of Cycles' where
Cycles is lit. With the grazing lobe read by one prefiltered lookup and the levels blended
linearly in roughness instead of in alpha they were 16.6 and 17.7 % off (3.4.1).
--quick (the quick tier): of GLOSSY the plastic and the gold only (4 of 8 glossy Cycles
references), no GRAZING.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_material_colour.py -- --zip Z --out DIR [--quick]
"""

import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

SIZE = 120
BLOCK = 6
# Cycles' samples per reference (a glossy one: the two seeds of sdtest.cycles_pair together). Its
# noise over BLOCK x BLOCK blocks is about 0.5 % at these counts, well under the limits below;
# each render's set-up is seconds, so fewer samples would save little more.
SAMPLES = 256
RED = (0.8, 0.15, 0.05, 1.0)
GLOSSY = [  # name, base colour, roughness, metallic, largest relative RMS, largest |bias| per channel
    ("plastic", RED, 0.3, 0.0, 0.03, 0.04),
    ("gold", (1.0, 0.7, 0.3, 1.0), 0.4, 1.0, 0.045, 0.03),
    ("half metal", (0.3, 0.5, 0.9, 1.0), 0.3, 0.5, 0.02, 0.03),
    ("rough plastic", (0.3, 0.45, 0.8, 1.0), 0.6, 0.0, 0.03, 0.04)]
GRAZING_SIZE = 160
GRAZING = [  # Debian's assimp model, material, base colour, roughness, metallic, HDRI, largest relative RMS, largest |bias| per channel
    ("OBJ/WusonOBJ.obj", "red plastic", RED, 0.2, 0.0, "studio.exr", 0.06, 0.03),
    ("PLY/Wuson.ply", "gold", (1.0, 0.7, 0.3, 1.0), 0.05, 1.0, "forest.exr", 0.07, 0.03)]
BENT_TILT = 60.0   # degrees between the slab's front face's normal and its shading normals
BENT = [  # metal's roughness (0.2: one prefiltered lookup; 0.5: the sampled lobe), largest relative RMS, largest |bias| per channel
    (0.2, 0.11, 0.04),
    (0.5, 0.08, 0.07)]


def uv_sphere(scene):
    import bmesh
    mesh = bpy.data.meshes.new("Ball")
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")   # calc_uvs fills the active UV layer: there must be one
    kwargs = {"u_segments": 48, "v_segments": 24, "calc_uvs": True}
    kwargs["radius" if bpy.app.version >= (3, 0, 0) else "diameter"] = 1.0
    bmesh.ops.create_uvsphere(bm, **kwargs)
    bm.to_mesh(mesh)
    bm.free()
    count = len(mesh.polygons)
    mesh.polygons.foreach_set("use_smooth", [True] * count)
    centres = np.empty(3 * count, dtype=np.float32)
    mesh.polygons.foreach_get("center", centres)
    mesh.polygons.foreach_set("material_index", (centres[2::3] < 0.0).astype(np.int32))
    return sdtest.add_object(scene, "Ball", mesh)


def main():
    checks = sdtest.Checks("test_material_colour")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)

    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ball = uv_sphere(scene)
    grid = bpy.data.images.new("Grid", 256, 256)
    grid.generated_type = 'COLOR_GRID'
    red = sdtest.diffuse_material("Red", RED)
    ball.data.materials.append(red)
    ball.data.materials.append(sdtest.diffuse_material("Grid", image=grid))
    cube = sdtest.flat_cube(scene, location=(0.0, 0.0, -5.0))
    sdtest.camera(scene, location=(0.0, -4.2, 0.6), target=(0.0, 0.0, 0.0), lens=55.0)

    # Corner data
    sdtest.bake_settings(scene, 'ambient_occlusion', 'LAMBERT', 2, rays=16, select=[cube])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake the flat cube")
    baked = package.store.baked.baked_mesh(cube)
    normals = package.store.attributes.read_normals(baked)
    positions = package.store.attributes.read_positions(baked)
    face_normal = np.sign(positions) * (np.abs(positions) == np.abs(positions).max(axis=1)[:, None])
    checks.check(len(baked.vertices) == 24, "a flat cube bakes one vertex per face corner",
                 "%d vertices (the cube has %d)" % (len(baked.vertices), len(cube.data.vertices)))
    checks.check(len(normals) == 24 and np.abs(np.abs(normals).max(axis=1) - 1.0).max() < 1e-6,
                 "each corner vertex has its face's normal", "largest component %s" % np.abs(normals).max(axis=1)[:4])
    checks.check(np.all(np.sum(normals * face_normal, axis=1) > 0.999),
                 "the corner normals point out of their faces")
    checks.check("sd_material_slot" not in baked.attributes and "sd_uv" not in baked.attributes,
                 "one material without a texture stores no slots or UVs")
    cube.hide_set(True)
    cube.hide_render = True

    sdtest.bake_settings(scene, 'unshadowed', 'LAMBERT', 8, rays=16, select=[ball])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake the sphere")
    baked = package.store.baked.baked_mesh(ball)
    rings, segments = 24, 48
    # two poles, 23 rings of 48; the equator ring splits by slot, one meridian by the UV seam
    expected = 2 + (rings - 1) * segments + segments + (rings - 1) + 1 + 2 * segments
    checks.check(len(ball.data.vertices) < len(baked.vertices) <= expected,
                 "the smooth sphere splits only along the material boundary and UV seams",
                 "%d of %d vertices (at most %d)" % (len(baked.vertices), len(ball.data.vertices), expected))
    slots, uvs, _ = package.store.attributes.read_surface(baked)
    checks.check(slots is not None and uvs is not None and set(np.unique(slots)) == {0.0, 1.0},
                 "the baked sphere keeps its slots and UVs")

    def preview(name):
        path = os.path.join(args.out, name)
        assert bpy.ops.sd_lighting.render_preview(filepath=path, width=SIZE, height=SIZE) == {'FINISHED'}
        return sdtest.load_exr(path)

    ours = preview("colour_preview.exr")
    cycles = sdtest.cycles_render(scene, os.path.join(args.out, "colour_cycles.exr"), SIZE, SAMPLES)
    red.node_tree.nodes["Diffuse BSDF"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    grid_link = ball.data.materials[1].node_tree.links[0]
    ball.data.materials[1].node_tree.links.remove(grid_link)
    white = preview("colour_preview_white.exr")
    red.node_tree.nodes["Diffuse BSDF"].inputs["Color"].default_value = (0.1, 0.7, 0.2, 1.0)
    green = preview("colour_preview_green.exr")

    mask = sdtest.covered(ours, cycles)
    checks.check(mask.mean() > 0.3, "both images show the sphere", "%.0f %% of pixels" % (100 * mask.mean()))
    relative, wrong = sdtest.block_differences((ours, white), cycles, mask, BLOCK)
    a, b = (sdtest.block_averages(image, mask, BLOCK) for image in (ours, cycles))
    checks.check(np.median(relative) < 0.04 and np.percentile(relative, 90) < 0.10,
                 "preview = Cycles channel by channel (colour and image texture, block averages)",
                 "median %.1f %%, 90th pct %.1f %% over %d blocks; mean RGB %s vs Cycles %s" % (
                     100 * np.median(relative), 100 * np.percentile(relative, 90), len(relative),
                     np.round(a.mean(axis=0), 3), np.round(b.mean(axis=0), 3)))
    checks.check(np.median(wrong) > 3 * np.median(relative), "a white preview differs from Cycles",
                 "median %.1f %%" % (100 * np.median(wrong)))
    top = mask & (np.arange(SIZE)[:, None] < SIZE // 3)
    green_top, white_top = green[top, :3].mean(axis=0), white[top, :3].mean(axis=0)
    checks.check(np.allclose(green_top / white_top, (0.1, 0.7, 0.2), rtol=0.02),
                 "a colour changed after the bake shows without baking again",
                 "top third / white: %s" % np.round(green_top / white_top, 3))

    # Flat faces shade flat, as in Cycles (corner normals); the same mesh baked smooth does not.
    ball.hide_set(True)
    ball.hide_render = True
    facets = sdtest.ico_sphere(scene, "Facets", subdivisions=1, location=(0.0, 0.0, 0.0), smooth=False)
    facets.data.materials.append(sdtest.diffuse_material("White"))
    sdtest.bake_settings(scene, 'unshadowed', 'LAMBERT', 8, rays=16, select=[facets])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake the flat-shaded icosphere")
    flat = preview("facets_preview.exr")
    cycles = sdtest.cycles_render(scene, os.path.join(args.out, "facets_cycles.exr"), SIZE, SAMPLES)
    facets.data.polygons.foreach_set("use_smooth", [True] * len(facets.data.polygons))
    facets.data.update()
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake it shaded smooth")
    smooth = preview("facets_preview_smooth.exr")
    mask = sdtest.covered(flat, cycles)
    relative, wrong = sdtest.block_differences((flat, smooth), cycles, mask, BLOCK)
    checks.check(np.median(relative) < 0.03 and np.percentile(relative, 90) < 0.10,
                 "flat faces: preview = Cycles (block averages)",
                 "median %.1f %%, 90th pct %.1f %% over %d blocks" % (
                     100 * np.median(relative), 100 * np.percentile(relative, 90), len(relative)))
    checks.check(np.percentile(wrong, 90) > 2 * np.percentile(relative, 90),
                 "the same mesh shaded smooth differs from Cycles' flat faces",
                 "90th pct %.1f %%" % (100 * np.percentile(wrong, 90)))
    facets.hide_set(True)
    facets.hide_render = True
    glossy(checks, package, scene, preview, args.out, GLOSSY[:2] if args.quick else GLOSSY)
    left_out(checks, package)
    mixed_slots(checks, package, scene)
    bent_normals(checks, args.out)
    if not args.quick:
        grazing(checks, args.out)
    return checks.summary()


def grazing(checks, out):
    """GRAZING against Cycles (see the module's doc): real models at the panel's defaults."""
    for path, name, colour, roughness, metallic, hdri, limit, bias_limit in GRAZING:
        scene, model = sdtest.glossy_model_scene(hdri, path, name, colour, roughness, metallic)
        sdtest.default_settings(scene)
        stem = os.path.join(out, "grazing_%s_%s_%g_%s" % (os.path.basename(path), name.replace(" ", "_"), roughness, hdri))
        cycles, noise = sdtest.cycles_pair(scene, stem, GRAZING_SIZE, 2 * SAMPLES, 4)
        sdtest.select_only([model])
        if not checks.check(bpy.ops.sd_lighting.bake(go_ahead=True) == {'FINISHED'}, "bake %s" % os.path.basename(path)):
            continue
        ours = sdtest.preview(stem + "_preview.exr", width=GRAZING_SIZE, height=GRAZING_SIZE)
        mask = sdtest.covered(ours, cycles)
        error, bias, a, b = sdtest.block_error(ours, cycles, 4, mask)
        darkest = sdtest.darkest_block(a, b)
        drawn = mask.sum() / max(sdtest.covered(cycles).sum(), 1)
        checks.check(drawn > 0.99 and error <= limit and np.abs(bias).max() <= bias_limit and darkest > 0.25,
                     "%s, %s (roughness %.2f), under %s = Cycles" % (os.path.basename(path), name, roughness, hdri),
                     "relative RMS %.1f %% (limit %.0f %%, Cycles' noise %.2f %%), bias per channel %s %% "
                     "(limit %.0f %%), darkest lit block %.2f x Cycles' (limit 0.25), %.1f %% of Cycles' pixels drawn" % (
                         100 * error, 100 * limit, 100 * noise, np.round(100 * bias, 1), 100 * bias_limit, darkest,
                         100 * drawn))


def bent_normals(checks, out):
    """BENT against Cycles (see the module's doc): a closed slab whose front face (facing -y) has
    custom normals leaning BENT_TILT degrees up from it, in polished metal, seen head-on."""
    scene = sdtest.empty_scene()
    depth = 0.3
    corners = [(-1.0, 0.0, -1.0), (1.0, 0.0, -1.0), (1.0, 0.0, 1.0), (-1.0, 0.0, 1.0)]
    mesh = bpy.data.meshes.new("Slab")
    mesh.from_pydata(corners + [(x, depth, z) for x, _, z in corners], [],
                     [(0, 1, 2, 3), (5, 4, 7, 6), (4, 0, 3, 7), (1, 5, 6, 2), (3, 2, 6, 7), (4, 5, 1, 0)])
    mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    if hasattr(mesh, "use_auto_smooth"):   # custom normals need it before 4.1
        mesh.use_auto_smooth = True
    tilt = np.radians(BENT_TILT)
    leaning = (0.0, -float(np.cos(tilt)), float(np.sin(tilt)))
    mesh.normals_split_custom_set([leaning if face.index == 0 else tuple(face.normal)
                                   for face in mesh.polygons for _ in face.loop_indices])
    slab = sdtest.add_object(scene, "Slab", mesh)
    sdtest.camera(scene, location=(0.0, -4.0, 0.0), target=(0.0, 0.0, 0.0), lens=90.0)
    for roughness, limit, bias_limit in BENT:
        mesh.materials.clear()
        mesh.materials.append(sdtest.principled_material("Polished", (1.0, 1.0, 1.0, 1.0), roughness, 1.0))
        stem = os.path.join(out, "bent_%g" % roughness)
        cycles, noise = sdtest.cycles_pair(scene, stem, SIZE // 2, SAMPLES, BLOCK)
        sdtest.bake_settings(scene, 'unshadowed', 'MATERIAL', 8, select=[slab])
        checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake the slab (roughness %g)" % roughness)
        for per_pixel in (False, True):
            scene.sd_lighting.per_pixel = per_pixel
            shading = "per pixel" if per_pixel else "per vertex"
            ours = sdtest.preview("%s_%s.exr" % (stem, shading.replace(" ", "_")), width=SIZE // 2, height=SIZE // 2)
            mask = sdtest.covered(ours, cycles)
            error, bias, _, _ = sdtest.block_error(ours, cycles, BLOCK, mask)
            checks.check(mask.all() and error <= limit and np.abs(bias).max() <= bias_limit,
                         "normals that mirror the view below their face (metal, roughness %g, %s) = Cycles"
                         % (roughness, shading),
                         "relative RMS %.1f %% (limit %.0f %%, Cycles' noise %.2f %%), bias per channel %s %% "
                         "(limit %.0f %%)" % (100 * error, 100 * limit, 100 * noise, np.round(100 * bias, 1),
                                              100 * bias_limit))
        scene.sd_lighting.per_pixel = False


def mixed_slots(checks, package, scene):
    """An object's lobes from slots of different kinds: a rough dielectric's specular layer beside
    a Diffuse BSDF keeps the Lambert bake; beside a glossy plastic, the Phong lobe is baked (and
    the rough slot is folded into Lambert wherever the prefiltered light is missing)."""
    ball = sdtest.ico_sphere(scene, "Slots", subdivisions=1)
    lobes_of = package.scene.materials.lobes_from_material
    ball.data.materials.append(sdtest.principled_material("Rough", roughness=0.6))
    ball.data.materials.append(sdtest.diffuse_material("Matte"))
    layered, why = lobes_of(ball)
    ball.data.materials[1] = sdtest.principled_material("Glossy", roughness=0.2)
    glossy, _ = lobes_of(ball)
    checks.check(layered.layer and why == "Rough: rough dielectric -> Lambert + specular layer"
                 and glossy.lobe == "phong" and glossy.diffuse and not glossy.layer,
                 "a rough dielectric beside a Diffuse BSDF bakes Lambert with its layer; beside a "
                 "glossy plastic, Lambert + Phong", "%s (%s); %s" % (layered.label, why, glossy.label))
    mesh = ball.data
    bpy.data.objects.remove(ball)
    bpy.data.meshes.remove(mesh)


def left_out(checks, package):
    """The panel's note names the Principled layers and node-driven inputs the lobes leave out,
    by their names in this Blender version (3.x: Clearcoat, Transmission; 4.x: Coat Weight, ...)."""
    material = sdtest.principled_material("Layered", roughness=0.3)
    plain = package.scene.materials.albedo(material).note
    checks.check("left out" not in plain and "opaque" not in plain,
                 "a default Principled BSDF leaves nothing out", repr(plain))
    bsdf = next(n for n in material.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
    codes = {}
    for distribution in ('GGX', 'MULTI_GGX'):   # 3.x's default scatters once, 4.0's keeps the bounces
        bsdf.distribution = distribution
        codes[distribution] = package.scene.materials.albedo(material).weights[3]
    checks.check(codes['GGX'] == -codes['MULTI_GGX'] < 0.0,
                 "the shader adds multiple scattering only for Multiscatter GGX", repr(codes))
    for names, value in ((("Coat Weight", "Clearcoat"), 0.5), (("Transmission Weight", "Transmission"), 1.0),
                         (("Alpha",), 0.5)):
        bsdf.inputs[next(name for name in names if name in bsdf.inputs)].default_value = value
    tint = bsdf.inputs["Specular Tint"]
    tint.default_value = (1.0, 0.5, 0.5, 1.0) if tint.type == 'RGBA' else 0.5
    bsdf.inputs["Anisotropic"].default_value = 0.5
    value = material.node_tree.nodes.new("ShaderNodeValue")
    material.node_tree.links.new(value.outputs[0], bsdf.inputs["Roughness"])
    note = package.scene.materials.albedo(material).note
    checks.check(all(part in note for part in ("coat left out", "transmission left out", "shown opaque",
                                                "specular tint left out", "anisotropy left out",
                                                "Roughness from node")),
                 "coat, transmission, alpha, specular tint, anisotropy and a node-driven roughness are noted",
                 repr(note))


def glossy(checks, package, scene, preview, out, materials):
    """The `materials` (GLOSSY's rows) against Cycles (see the module's doc)."""
    ball = sdtest.ico_sphere(scene, "Glossy", subdivisions=5, location=(0.0, 0.0, 0.0))
    for name, colour, roughness, metallic, limit, bias_limit in materials:
        ball.data.materials.clear()
        ball.data.materials.append(sdtest.principled_material(name, colour, roughness, metallic))
        stem = os.path.join(out, name.replace(" ", "_"))
        cycles, noise = sdtest.cycles_pair(scene, stem, SIZE, SAMPLES, BLOCK)
        sdtest.bake_settings(scene, 'unshadowed', 'MATERIAL', 12, select=[ball])
        checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake the %s sphere" % name)
        ours = preview(name.replace(" ", "_") + "_preview.exr")
        mask = sdtest.covered(ours, cycles)
        error, bias, a, b = sdtest.block_error(ours, cycles, BLOCK, mask)
        checks.check(error <= limit and np.abs(bias).max() <= bias_limit,
                     "%s (roughness %.1f, metallic %.1f) = Cycles" % (name, roughness, metallic),
                     "relative RMS %.1f %% (limit %.0f %%, Cycles' noise %.2f %%), bias per channel "
                     "%s %% (limit %.0f %%)" % (100 * error, 100 * limit, 100 * noise,
                                                np.round(100 * bias, 1), 100 * bias_limit))
        if metallic == 1.0:   # the seed's truncated Phong lobe instead of the prefiltered GGX
            scene.sd_lighting.prefiltered_glossy = False
            truncated_error = sdtest.block_error(preview(name + "_truncated.exr"), cycles, BLOCK, mask)[0]
            scene.sd_lighting.prefiltered_glossy = True
            checks.check(error < 0.75 * truncated_error,
                         "the prefiltered glossy light is closer to Cycles than the truncated lobe",
                         "relative RMS %.1f %% against %.1f %%" % (100 * error, 100 * truncated_error))
            # the prefilter runs in a worker thread: the interactive draw does not wait for it
            env, shading = package.scene.environment, package.live.gpu_shading
            env.clear_cache()
            shading.clear_cache()
            start = time.perf_counter()
            first = shading.prefiltered_texture(env.source(scene), False)
            seconds = time.perf_counter() - start
            checks.check(first is None and len(env.prefiltered_atlases().pending()) == 1
                         and len(env.prefilter_status()) == 1,
                         "the interactive draw does not wait for the prefiltered environment",
                         "%.2f s; %s" % (seconds, env.prefilter_status()))
            view = package.scene.view.View.from_camera(scene.camera, bpy.context.evaluated_depsgraph_get(), SIZE, SIZE)
            drawing = package.live.drawing
            data = drawing.object_data(ball, prefiltered=True)
            _, textures = drawing._frame(scene, ball, data, view, 1.0, False)
            checks.check(not data.variant.prefiltered_lookup and not textures,
                         "meanwhile the object is drawn with the truncated lobe")
            checks.check(env.prefiltered_atlases().wait(120) and not env.prefilter_status()
                         and shading.prefiltered_texture(env.source(scene), False) is not None,
                         "the prefiltered environment is drawn once it is there")
            _, textures = drawing._frame(scene, ball, data, view, 1.0, False)
            checks.check(data.variant.prefiltered_lookup and len(textures) == 1,
                         "then the object is drawn with it")
            # traced too; while a new environment's atlas is made, neither (the variant of the
            # last frame's rays without the atlas raised, every frame)
            rays = drawing.reflection_rays(scene, True)
            drawing._frame(scene, ball, data, view, 1.0, False, rays=rays)
            traced = data.variant.reflection_rays
            scene.sd_lighting.reflection_ray_count = "8"
            drawing._frame(scene, ball, data, view, 1.0, False, rays=rays)
            checks.check(traced == package.live.shader_variant.REFLECTION_RAYS and data.variant.reflection_rays == 8,
                         "the scene's Rays set the rays each pixel casts", "%d, then %d" % (traced, data.variant.reflection_rays))
            scene.sd_lighting.reflection_ray_count = str(traced)
            env.clear_cache()
            shading.clear_cache()
            _, textures = drawing._frame(scene, ball, data, view, 1.0, False, rays=rays)
            checks.check(traced and not data.variant.reflection_rays and not data.variant.prefiltered_lookup
                         and env.prefiltered_atlases().wait(120),
                         "a traced object is drawn with the truncated lobe while a new environment is prefiltered")
            # the world turned and tilted: the prefiltered lookup turns with it, as Cycles' does
            mapping = scene.world.node_tree.nodes["Mapping"]
            mapping.inputs["Rotation"].default_value = (0.4, 0.0, 1.9)
            # one seed (the unturned pair measured the noise at these samples): one render's set-up less
            turned_cycles = sdtest.cycles_render(scene, stem + "_turned_cycles.exr", SIZE, SAMPLES)
            turned = sdtest.block_averages(preview(name + "_turned_world.exr"), mask, BLOCK)
            mapping.inputs["Rotation"].default_value = (0.0, 0.0, 0.0)
            # the world's strength: applied in the shader, the atlas made once without it
            strength = scene.world.node_tree.nodes["Background"].inputs["Strength"]
            strength.default_value = 2.0
            brighter = sdtest.block_averages(preview(name + "_strength_2.exr"), mask, BLOCK)
            strength.default_value = 1.0
            checks.check(abs(brighter.mean() / a.mean() - 2.0) < 0.01,
                         "twice the world's strength shows the metal twice as bright",
                         "%.4f x" % (brighter.mean() / a.mean()))
            expected = sdtest.block_averages(turned_cycles, mask, BLOCK)
            turned_error, unturned_error = sdtest.relative_rms(turned, expected), sdtest.relative_rms(a, expected)
            checks.check(turned_error <= limit and unturned_error > 2 * turned_error,
                         "%s with the world turned and tilted = Cycles" % name,
                         "relative RMS %.1f %% (limit %.0f %%; the unturned preview: %.1f %%)"
                         % (100 * turned_error, 100 * limit, 100 * unturned_error))
        if metallic == 1.0:   # one glossy lobe with weights; the material turned diffuse since
            ball.data.materials[0] = sdtest.diffuse_material("Turned diffuse", colour)
            turned = sdtest.block_averages(preview(name + "_turned_diffuse.exr"), mask, BLOCK)
            checks.check(turned.mean() > 0.5 * b.mean(),
                         "a material changed to a Diffuse BSDF after a metal's bake shows its lobe "
                         "times the colour, not black", "mean %.3f (Cycles' metal %.3f)" % (
                             turned.mean(), b.mean()))
        if metallic == 0.0 and roughness >= package.scene.lobes.LAYER_MIN_ROUGHNESS:
            # baked as Lambert, the specular layer lit live; folded into Lambert without the
            # prefiltered light
            scene.sd_lighting.prefiltered_glossy = False
            folded_error = sdtest.block_error(preview(name.replace(" ", "_") + "_folded.exr"), cycles, BLOCK, mask)[0]
            scene.sd_lighting.prefiltered_glossy = True
            checks.check(ball["sd_bake"]["lobe"] == "lambert" and error < 0.75 * folded_error,
                         "a rough plastic's Lambert bake with its specular layer is closer to Cycles "
                         "than with the layer folded", "relative RMS %.1f %% against %.1f %%"
                         % (100 * error, 100 * folded_error))
        elif metallic == 0.0:
            sdtest.bake_settings(scene, 'unshadowed', 'PHONG', 12,
                                 phong_exponent=package.scene.lobes.exponent_from_roughness(roughness),
                                 select=[ball])
            checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake it as one Phong lobe")
            one_error = sdtest.block_error(preview(name + "_one_lobe.exr"), cycles, BLOCK, mask)[0]
            checks.check(one_error > 5 * error, "one Phong lobe of its colour is far off",
                         "relative RMS %.1f %%" % (100 * one_error))


sdtest.run(main)
