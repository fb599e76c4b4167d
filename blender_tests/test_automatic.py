"""The automatic mode (issue 10): per object, the cheapest setting within the target error, with
the reasons, through the add-on's bake.

Under forest.exr: a lone sphere high above everything (convex, nothing around it) and a sphere
resting on a ground plane, both white Diffuse BSDF, baked together with the default method
(Automatic, target 2 %). The lone sphere stores no visibility (unshadowed); the resting one gets a
method with visibility; so the two get different choices, each recorded with its reasons and
predicted error. The resting sphere's predicted error is within a factor 2 of its bake's error
measured at every vertex against sdnative.reference. Its diffuse material compiles a shader
variant without the glossy path. Before a bake, the bake-time predictor measures a chosen
method's error too (the panel's line). An override of the object (method and s') is kept while the rest
is still chosen. A cancel while the settings are being chosen stops within a second and leaves
every bake as it was. A red plastic (Principled, roughness 0.3) is measured as what it shows, a
Lambert lobe with most of the light and a glossy Phong lobe: its predicted error is far below that
of the same sphere shaded as the Phong lobe alone, at no higher s.
Run (headless, GPU through a Workbench render):
    blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_automatic.py -- --zip Z --out DIR
"""

import os
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402


def measured_error(package, scene, obj):
    """The bake's relative RMS error at every vertex against the reference of eq. (1)."""
    sd = package.native.get()
    mesh = package.store.baked.baked_mesh(obj)
    data = package.store.attributes.read(mesh)
    positions = package.store.attributes.read_positions(mesh).astype(np.float64)
    triangles = package.store.attributes.read_triangle_loops(mesh)
    loops = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", loops)
    ground = bpy.data.objects["Ground"]
    occluder = np.array([tuple(ground.matrix_world @ v.co) for v in ground.data.vertices]) - np.array(obj.location)
    occluder_triangles = package.store.attributes.read_triangle_loops(ground.data)
    ground_loops = np.empty(len(ground.data.loops), dtype=np.int32)
    ground.data.loops.foreach_get("vertex_index", ground_loops)
    view = package.scene.view.View.from_camera(scene.camera, bpy.context.evaluated_depsgraph_get(), 64, 64, scene)
    shaded = package.live.drawing.cpu_reference(scene, obj, view)
    env = package.scene.environment.environment(package.scene.environment.source(scene))
    reference, error = sd.reference(env, positions, data["normals"], loops[triangles], samples=4096,
                                    occluder_vertices=occluder,
                                    occluder_triangles=ground_loops[occluder_triangles].astype(np.int32))
    return package.plan.accuracy.relative_error(shaded, reference, error ** 2)


def main():
    checks = sdtest.Checks("test_automatic")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    sdtest.camera(scene)
    white = sdtest.diffuse_material("White")
    lone = sdtest.ico_sphere(scene, "Lone", subdivisions=3, location=(0.0, 0.0, 60.0))
    resting = sdtest.ico_sphere(scene, "Resting", subdivisions=3, location=(0.0, 0.0, 1.0))
    ground = sdtest.grid(scene, cuts=4, size=40.0)
    for obj in (lone, resting, ground):
        obj.data.materials.append(white)
    settings = scene.sd_lighting
    checks.check(settings.method == "automatic" and abs(settings.target_error - 0.02) < 1e-9,
                 "the default method is Automatic with a 2 % target")

    # A cancel while the settings are chosen: within a second, nothing changed.
    sdtest.select_only([resting])
    tasks, _ = package.bake.prepare.prepare(bpy.context, [resting])
    # The choice is held at its start until the test has looked (a fast machine chose within the
    # half second the test used to wait), then released and cancelled while it runs.
    entered, release, choose = threading.Event(), threading.Event(), tasks[0].choose

    def held_choose(stop, progress=None):
        entered.set()
        release.wait(10.0)
        return choose(stop, progress)
    tasks[0].choose = held_choose
    job = package.bake.job.BakeJob(tasks)
    job.start()
    entered.wait(10.0)
    checks.check(job.choosing, "the bake starts by choosing the settings", job.status_text())
    release.set()
    start = time.perf_counter()
    job.cancel()
    job.join(10.0)
    took = time.perf_counter() - start
    checks.check(job.finished and job.cancelled and took < 1.0 and
                 package.store.baked.baked_mesh(resting) is None,
                 "a cancel while choosing stops within a second and bakes nothing", "%.2f s" % took)

    sdtest.select_only([lone, resting])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake both with the automatic mode")
    lone_info, resting_info = (dict(obj["sd_bake"]) for obj in (lone, resting))
    for name, info in (("Lone", lone_info), ("Resting", resting_info)):
        print("%s: %s s=%d s'=%d rays=%d predicted %.4f" % (
            name, info["method"], info["light_order"], info["visibility_order"], info["rays"],
            info["predicted_error"]))
        print("   " + info["automatic"].replace("\n", "\n   "))
    lone_mesh = package.store.baked.baked_mesh(lone)
    checks.check(lone_info["method"] == "unshadowed" and
                 not any(a.name.startswith(("sd_visibility", "sd_transfer", "sd_design", "sd_product"))
                         for a in lone_mesh.attributes),
                 "the lone sphere stores no visibility", lone_info["method"])
    method = package.methods.get(resting_info["method"])
    checks.check(method.data is not None and resting_info["automatic"].startswith("Visibility: needed"),
                 "the resting sphere gets its visibility", resting_info["method"])
    # The predicted error is a Monte Carlo estimate (plan/accuracy.py), and the resting sphere's
    # best setting sits near the 2 % target (its bake measures 2.2 %): the mode may then say that
    # no setting reaches it and take one near the most accurate.
    missed = "no setting reaches the 2.0 % target" in resting_info["automatic"]
    checks.check(lone_info["predicted_error"] <= 0.02 and
                 (resting_info["predicted_error"] <= 0.02 or missed and resting_info["predicted_error"] <= 0.025),
                 "both meet the target (or, for the resting sphere, come within its noise and say so)", "%.4f, %.4f" % (lone_info["predicted_error"],
                                                         resting_info["predicted_error"]))

    checks.check(all(("Evaluation: per pixel" in info["automatic"]) == bool(info["per_pixel"])
                     for info in (lone_info, resting_info)),
                 "per-vertex or per-pixel evaluation chosen from the triangles' size on screen",
                 "; ".join(info["automatic"].splitlines()[-1] for info in (lone_info, resting_info)))

    cost = package.plan.cost
    # exact but for designs, whose mean node count the model takes as the generic count
    checks.check(all(abs(info["floats_per_vertex"] - cost.stored_floats(
        package.methods.get(info["method"]), info["light_order"], info["visibility_order"])) <=
        (0.3 * info["floats_per_vertex"] if package.methods.get(info["method"]).designs_per_vertex else 0.0)
        for info in (lone_info, resting_info)),
        "the cost model's stored floats are what the bakes store",
        ", ".join(str(info["floats_per_vertex"]) for info in (lone_info, resting_info)))

    # The Monte Carlo reference is version-independent: with --no-numeric (tests/CMakeLists.txt:
    # every Blender but Debian's) it is left out.
    if args.numeric:
        measured = measured_error(package, scene, resting)
        ratio = measured / resting_info["predicted_error"]
        checks.check(0.5 <= ratio <= 2.0, "the predicted error is within a factor 2 of the measured one",
                     "predicted %.4f, measured %.4f" % (resting_info["predicted_error"], measured))

    package.live.gpu_context.ensure()
    data = package.live.drawing.object_data(resting)
    checks.check(not data.variant.glossy and "SD_GLOSSY" not in data.variant.defines(
        package.native.get().sh_recurrence_constants), "a diffuse material compiles no glossy path")

    # Before a bake, the predictor measures the chosen method's error too, for the panel.
    settings.method = "prt_diffuse"
    sdtest.select_only([resting])
    predictor = package.ui.prediction.start(bpy.context)
    predictor.join(120.0)
    predicted = package.ui.prediction.predicted_errors(bpy.context)
    checks.check(predictor.finished and len(predicted) == 1 and predicted[0][0] == "Resting" and
                 0.0 < predicted[0][2] < 0.2,
                 "the panel's prediction measures a chosen method's error before the bake",
                 str([(name, error) for name, _, error in predicted]))
    settings.method = "automatic"
    predictor = package.ui.prediction.start(bpy.context)
    predictor.join(120.0)
    chosen = package.ui.prediction.automatic_choices(bpy.context)["Resting"][0]["automatic"]
    package.store.baked.clear(resting)
    measure = package.plan.analysis.choose

    def measured_again(*args, **kwargs):
        raise AssertionError("measured again")
    package.plan.analysis.choose = measured_again
    try:
        checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'} and
                     dict(resting["sd_bake"])["automatic"] == chosen,
                     "a bake after the prediction takes over its choice (not measured again)")
    finally:
        package.plan.analysis.choose = measure
    # another HDRI in the world's own Environment Texture is another prediction, not the old one's
    # choice taken over
    key = package.ui.prediction.settings_key(bpy.context)
    texture = next(n for n in scene.world.node_tree.nodes if n.type == 'TEX_ENVIRONMENT')
    forest, texture.image = texture.image, bpy.data.images.load(sdtest.hdri("sunrise.exr"))
    checks.check(package.ui.prediction.settings_key(bpy.context) != key,
                 "the prediction follows the world's image")
    texture.image = forest

    # An override is kept per object; the rest is still chosen.
    resting.sd_lighting.use_method = True
    resting.sd_lighting.method = "prt_gaunt"
    resting.sd_lighting.use_visibility_order = True
    resting.sd_lighting.visibility_order = 3
    sdtest.select_only([resting])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake with overrides")
    info = dict(resting["sd_bake"])
    checks.check(info["method"] == "prt_gaunt" and info["visibility_order"] == 3 and
                 "automatic" not in info, "a method override bakes that method with the scene's s'"
                 " overridden too", str({k: info[k] for k in ("method", "visibility_order")}))
    resting.sd_lighting.use_method = False
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake with the s' override only")
    info = dict(resting["sd_bake"])
    chosen = package.methods.get(info["method"])
    checks.check("automatic" in info and info["automatic"].startswith("Overridden: visibility_order = 3")
                 and (not chosen.uses_visibility_order or info["visibility_order"] == 3),
                 "the automatic mode keeps the override", info.get("automatic", "")[:80])
    plastic(checks, package, scene)
    return checks.summary()


def plastic(checks, package, scene):
    """The red plastic's lobes and choice against the Phong lobe alone (see the module's doc)."""
    ball = sdtest.ico_sphere(scene, "Plastic", subdivisions=3, location=(30.0, 0.0, 60.0))
    ball.data.materials.append(sdtest.principled_material("Plastic", (0.8, 0.15, 0.05, 1.0), 0.3))
    settings = scene.sd_lighting
    sdtest.select_only([ball])
    settings.material_source = 'PHONG'
    settings.phong_exponent = package.scene.lobes.exponent_from_roughness(0.3)
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake the plastic as the Phong lobe alone")
    alone = dict(ball["sd_bake"])
    settings.material_source = 'MATERIAL'
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake the plastic sphere")
    mixed = dict(ball["sd_bake"])
    checks.check(mixed["lobe"] == "phong" and mixed["diffuse_lobe"] and mixed["lobe_weights"] and
                 0.8 < mixed["diffuse_share"] < 0.95 and abs(mixed["exponent"] - alone["exponent"]) < 1e-3,
                 "a plastic bakes a Lambert lobe besides the Phong one, with most of the light",
                 "%s sigma %.1f, Lambert's share %.2f" % (mixed["lobe"], mixed["exponent"],
                                                          mixed["diffuse_share"]))
    checks.check(mixed["predicted_error"] < 0.5 * alone["predicted_error"] and
                 mixed["light_order"] <= alone["light_order"],
                 "the plastic's error is measured on both lobes: far below the glossy lobe's alone",
                 "s = %d, %.1f %% against s = %d, %.1f %%" % (
                     mixed["light_order"], 100 * mixed["predicted_error"], alone["light_order"],
                     100 * alone["predicted_error"]))
    package.live.gpu_context.ensure()
    data = package.live.drawing.object_data(ball)
    data.frame_block(np.eye(4), np.eye(4), (0.0, 0.0, 1.0, 1.0), np.zeros(((mixed["light_order"] + 1) ** 2, 3)),
                     np.eye(3), 1.0, albedos=package.scene.materials.object_albedos(ball))
    defines = data.variant.defines(package.native.get().sh_recurrence_constants)
    checks.check({"SD_GLOSSY", "SD_DIFFUSE_LOBE", "SD_LOBE_WEIGHTS"} <= set(defines),
                 "its shader variant shades both lobes with the slot's weights")


sdtest.run(main)
