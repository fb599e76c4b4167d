"""The main job: the default scene, baked and shaded by the add-on, headless.

Builds Suzanne (Subdivision modifier, a rough Principled material, so the lobe read from the
material is Lambert, its specular layer lit live) sitting on a subdivided ground plane, under a
Blender-shipped HDRI (forest) turned by a Mapping node, with a camera; installs and enables the
add-on from its zip; bakes both objects against each other in the add-on's default automatic mode
(per object the cheapest method, s, s' and rays whose error, measured on sampled vertices, is
within 2 %; printed with the reasons), so Suzanne shadows herself and the ground (contact
shadows); saves the .blend (the bake lives in it: open it with the add-on enabled and the viewport
shades it live) and renders the live shading from the scene camera to a PNG (Standard view
transform) and an EXR (scene-linear), plus a PNG with the world turned by 120 degrees. Prints the
paths.

Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/run_default_scene.py -- \
         --zip build/sd_lighting.zip --out out/
     (set BLENDER_USER_SCRIPTS to a scratch folder to keep the install out of ~/.config/blender)
Options after --: --hdri forest.exr --width 960 --height 540 --exposure -1
                  --cuts 72 (the ground's grid) --subdivisions 1 (Suzanne's Subdivision levels)
                  --max-vertices N (the panel's Max Verts; 0, the default: the panel's own)
"""

import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402


def options():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    out = {"hdri": "forest.exr", "width": 960, "height": 540, "exposure": -1.0,
           "cuts": 72, "subdivisions": 1, "max_vertices": 0}
    for i, arg in enumerate(argv[:-1]):
        key = arg.lstrip("-").replace("-", "_")
        if key in out:
            out[key] = type(out[key])(argv[i + 1])
    return out


def suzanne(scene, subdivisions=1):
    bpy.ops.mesh.primitive_monkey_add(size=2.0, location=(0.0, 0.0, 0.0))
    monkey = bpy.context.active_object
    monkey.name = "Suzanne"
    monkey.rotation_euler = (math.radians(-20.0), 0.0, math.radians(-25.0))
    subdivision = monkey.modifiers.new("Subdivision", 'SUBSURF')
    subdivision.levels = subdivision.render_levels = subdivisions   # Cycles renders what is baked
    bpy.ops.object.shade_smooth()
    material = bpy.data.materials.new("Clay")
    sdtest.use_nodes(material)
    principled = next(n for n in material.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
    principled.inputs["Roughness"].default_value = 0.7
    monkey.data.materials.append(material)
    # Sit her on the ground: the lowest point of the evaluated mesh at z = 0.
    bpy.context.view_layer.update()
    evaluated = monkey.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    matrix = np.array(monkey.matrix_world)
    lowest = (co.reshape(-1, 3) @ matrix[:3, :3].T)[:, 2].min()
    evaluated.to_mesh_clear()
    monkey.location.z = -lowest
    return monkey


def build_scene(opts):
    """The default scene, its bake settings chosen and both objects selected: (scene, mapping,
    Suzanne, ground)."""
    scene = sdtest.empty_scene()
    _, mapping = sdtest.hdri_world(scene, sdtest.hdri(opts["hdri"]), rotation_z=math.radians(30.0))
    monkey = suzanne(scene, opts["subdivisions"])
    ground = sdtest.grid(scene, name="Ground", cuts=opts["cuts"], size=6.0)
    sdtest.camera(scene, location=(3.2, -6.2, 3.0), target=(0.0, 0.0, 0.75), lens=45.0)
    scene.render.resolution_x, scene.render.resolution_y = opts["width"], opts["height"]
    scene.render.resolution_percentage = 100
    # The live shading shows the Standard view transform; make Blender's own views agree, and
    # bring the bright forest sky (B up to about 1.5) into range.
    scene.view_settings.view_transform = 'Standard'
    scene.view_settings.exposure = opts["exposure"]

    settings = scene.sd_lighting   # the add-on's defaults: the automatic mode, material from the material
    settings.method = 'automatic'
    settings.material_source = 'MATERIAL'
    if opts["max_vertices"]:
        settings.refine_max_vertices = opts["max_vertices"]
    settings.live_shading = True
    sdtest.select_only([monkey, ground])
    return scene, mapping, monkey, ground


def main():
    args = sdtest.arguments()
    opts = options()
    start = time.perf_counter()
    sdtest.install_addon(args.zip)
    scene, mapping, monkey, ground = build_scene(opts)
    print("sd_lighting: baking %s and %s (the automatic mode, target error %.0f %%)..."
          % (monkey.name, ground.name, 100 * scene.sd_lighting.target_error), flush=True)
    if bpy.ops.sd_lighting.bake(go_ahead=True) != {'FINISHED'}:
        raise RuntimeError("the bake failed")
    for obj in (monkey, ground):
        info = dict(obj["sd_bake"])
        print("  %-8s %6d vertices, %s (%s), s = %d, s' = %d, %d rays, %d bytes per vertex, %.1f s"
              % (obj.name, info["vertices"], info["method"], info["lobe"], info["light_order"],
                 info["visibility_order"], info["rays"], info["bytes_per_vertex"], info["seconds"]),
              flush=True)
        for line in str(info.get("automatic", "")).splitlines():
            print("           " + line)
        if "unrefined_vertices" in info:
            print("           Refine: %d -> %d vertices in %d levels, interpolation error left about %.1f %%"
                  % (info["unrefined_vertices"], info["vertices"], info["refine_levels"],
                     100 * info["refine_estimated_left"]))

    blend = os.path.join(args.out, "sd_default_scene.blend")
    png = os.path.join(args.out, "sd_preview.png")
    exr = os.path.join(args.out, "sd_preview.exr")
    rotated = os.path.join(args.out, "sd_preview_world_turned_120.png")
    for path in (png, exr):
        if bpy.ops.sd_lighting.render_preview(filepath=path) != {'FINISHED'}:
            raise RuntimeError("render_preview failed for " + path)
    mapping.inputs["Rotation"].default_value[2] += math.radians(120.0)
    if bpy.ops.sd_lighting.render_preview(filepath=rotated) != {'FINISHED'}:
        raise RuntimeError("render_preview failed for " + rotated)
    mapping.inputs["Rotation"].default_value[2] -= math.radians(120.0)
    bpy.ops.wm.save_as_mainfile(filepath=blend)

    print("\nsd_lighting main job done in %.1f s" % (time.perf_counter() - start))
    print("blend file:    %s" % blend)
    print("preview (PNG): %s" % png)
    print("preview (EXR): %s" % exr)
    print("world turned:  %s" % rotated)
    return 0


if __name__ == "__main__":
    sdtest.run(main)
