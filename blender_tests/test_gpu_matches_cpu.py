"""The viewport shader agrees with the CPU evaluator (sdnative.shade) on every method.

Each vertex of a baked test scene is drawn as one pixel of an RGBA32F target by the live-shading
shader (per-vertex path, and the per-pixel path evaluated at the vertex), read back, and compared
with sdnative.shade on the same stored (float32) data, the same view, environment and rotation
g R (a rotated world Mapping node and a rotated object with a mirrored, non-uniform scale).
Passes when max |gpu - cpu| / max |cpu| <= 1e-3 for every method (float32 on the GPU vs float64 on
the CPU). The objects' material, a Principled BSDF of roughness 0.4 and metallic 0.2, gives the
"MATERIAL" cases a Lambert lobe besides a Phong one; the target shows the two lobes' sum.

The methods that can read it (MSD 12, 13) are also checked with the band-limited texture option
(L~ looked up in the band-limited equirect texture, bilinear, instead of its SH sum) against the
same exact sdnative.shade, with TEXTURE_TOLERANCE: the texture's own interpolation error, measured pointwise
as max |bilinear - L~| / max |L~| over 2e5 directions at the chosen size (64 (s+1) x 32 (s+1),
at least 256 x 128), is 4.3e-4 at s = 4, 4.7e-4 at s = 6, 4.8e-4 at s = 8 (forest.exr); B is a
weighted average of L~ at the nodes; measured on B here: 1.3e-4 .. 2.3e-4 at s = 4, 6 and
3.7e-4 at s = 8. 1e-3 (twice the pointwise error) leaves room for other scenes and float32, and
still fails on a wrong orientation, row order, rotation, seam or pole (errors of O(1)).
--quick (the quick tier): QUICK_CASES, each method once (at its higher orders where it has them) and
the material's two lobes once.
Run: xvfb-run -a blender --factory-startup --python-exit-code 1 --python blender_tests/test_gpu_matches_cpu.py -- --zip Z [--quick]
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402

TOLERANCE = 1e-3
TEXTURE_TOLERANCE = 1e-3
BASIC_CASES = [  # (method, lobe, sigma, s, s')
    ("unshadowed", "LAMBERT", 1.0, 4, 2),
    ("unshadowed", "PHONG", 8.0, 4, 2),
    ("ambient_occlusion", "LAMBERT", 1.0, 4, 2),
    ("prt_diffuse", "LAMBERT", 1.0, 4, 2),
    ("prt_matrix", "LAMBERT", 1.0, 4, 2),
    ("prt_matrix", "PHONG", 8.0, 4, 2),
    ("prt_gaunt", "LAMBERT", 1.0, 4, 2),
    ("prt_gaunt", "PHONG", 8.0, 4, 2),
    ("msd_lobe", "LAMBERT", 1.0, 4, 2),
    ("msd_lobe", "PHONG", 8.0, 4, 2),
    ("msd_visibility", "LAMBERT", 1.0, 4, 2),
    ("msd_visibility", "PHONG", 8.0, 4, 2),
    ("msd_visibility", "PHONG", 50.0, 4, 2),
]
HIGHER_ORDER_CASES = [  # bigger SH tables, Gaunt lists, lobe designs and per-vertex designs
    ("unshadowed", "PHONG", 30.0, 12, 0),
    ("prt_matrix", "PHONG", 20.0, 6, 3),
    ("prt_gaunt", "PHONG", 20.0, 6, 3),
    ("msd_lobe", "PHONG", 20.0, 8, 3),
    ("msd_visibility", "PHONG", 20.0, 6, 2),
]
MATERIAL_CASES = [  # Lambert + Phong from the material (sigma from its roughness)
    ("unshadowed", "MATERIAL", 0.0, 4, 2),
    ("ambient_occlusion", "MATERIAL", 0.0, 4, 2),
    ("prt_matrix", "MATERIAL", 0.0, 4, 2),
    ("prt_gaunt", "MATERIAL", 0.0, 4, 2),
    ("msd_lobe", "MATERIAL", 0.0, 4, 2),
    ("msd_visibility", "MATERIAL", 0.0, 4, 2),
]
CASES = BASIC_CASES + HIGHER_ORDER_CASES + MATERIAL_CASES
QUICK_CASES = HIGHER_ORDER_CASES + [case for case in BASIC_CASES if case[1] == "LAMBERT" and case[0] not in
                                    {higher[0] for higher in HIGHER_ORDER_CASES}] + MATERIAL_CASES[-1:]


def main():
    checks = sdtest.Checks("test_gpu_matches_cpu")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    drawing = package.live.drawing
    package.live.gpu_context.ensure()

    scene = sdtest.empty_scene()
    _, mapping = sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    mapping.inputs["Rotation"].default_value = (0.3, -0.2, 1.1)
    ball = sdtest.ico_sphere(scene, subdivisions=2, location=(0.2, 0.1, 0.9))
    ball.rotation_euler = (0.4, 0.1, -0.7)
    ball.scale = (0.8, -0.9, 0.7)
    ground = sdtest.grid(scene, cuts=8, size=4.0)
    glossy = sdtest.principled_material("Glossy", (0.8, 0.3, 0.1, 1.0), roughness=0.4, metallic=0.2)
    for obj in (ball, ground):
        obj.data.materials.append(glossy)
    sdtest.camera(scene)
    settings = scene.sd_lighting
    settings.automatic_orders = False
    settings.rays = 256
    sdtest.select_only([ball, ground])
    depsgraph = bpy.context.evaluated_depsgraph_get()
    view = package.scene.view.View.from_camera(scene.camera, depsgraph, 640, 480, scene)

    table = []
    for method, material, sigma, s, sv in QUICK_CASES if args.quick else CASES:
        settings.light_order, settings.visibility_order = s, sv
        settings.method = method
        settings.material_source = material
        settings.phong_exponent = sigma
        result = bpy.ops.sd_lighting.bake(go_ahead=True)   # GPU = CPU here, not the confirmation
        name = "%s %s%s s=%d s'=%d" % (method, material.lower(),
                                       " %g" % sigma if material == "PHONG" else "", s, sv)
        if not checks.check(result == {'FINISHED'}, "bake " + name):
            continue
        if material == "MATERIAL":
            record = package.store.baked.record(ball)
            checks.check(record.lobe == "phong" and record.diffuse_lobe and
                         abs(record.exponent - 19.03) < 0.01, "the material bakes Lambert + Phong: "
                         + name, "%s sigma %.2f, diffuse lobe %s" % (record.lobe, record.exponent,
                                                                      record.diffuse_lobe))
        textures = (False, True) if package.methods.get(method).band_limited_texture else (False,)
        for texture in textures:
            settings.band_limited_texture = texture
            worst = 0.0
            for obj in (ball, ground):
                cpu = drawing.cpu_reference(scene, obj, view)
                for per_pixel in (False, True):
                    gpu = drawing.gpu_vertex_values(scene, obj, view, per_pixel=per_pixel)
                    relative, per_vertex = sdtest.relative_error(gpu, cpu)
                    worst = max(worst, relative)
                    label = "%s%s %s %s" % (name, " texture" if texture else "", obj.name,
                                            "per-pixel" if per_pixel else "per-vertex")
                    checks.check(relative <= (TEXTURE_TOLERANCE if texture else TOLERANCE),
                                 "GPU = CPU: " + label,
                                 "max rel %.2e (per-vertex rel %.2e), |B| max %.3g" % (
                                     relative, per_vertex, abs(cpu).max()))
            table.append((name + (" texture %dx%d" % package.live.band_limited_map.texture_size(s)
                                  if texture else ""), worst))
        settings.band_limited_texture = False
    print("\nGPU vs CPU, max |gpu - cpu| / max |cpu| over both objects and both paths:")
    for name, worst in table:
        print("  %-56s %.2e" % (name, worst))
    return checks.summary()


sdtest.run(main)
