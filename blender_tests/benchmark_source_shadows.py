"""What the bright sources' own shadows cost a frame of the live shading (issue 29), as ratios to the
same frame through SH alone (Sharp Source Shadows off), measured in one run.

Scene: assimp's 2CylinderEngine (a CAD model, about 93k vertices baked) standing on a ground grid,
white, both baked with PRT (8) (what the automatic mode gives the engine under sunrise.exr in
test_cycles_parity), 256 rays, without refinement: the frame's cost follows the vertices drawn
and what each pixel evaluates. Frames of 1280 x 720 (benchmark_viewport.time_frames: the mean over
several after a warm-up, each ending with a readback that waits for the GPU) from a camera above
the front, per vertex (the seed's way), under
- sunrise.exr (one source, the sun) and studio.exr (four softboxes: the most the map gives);
- columns: SH alone; with the sources, their shadow maps kept (a still world); with the world
  turning a degree every frame (every map rendered again each frame); and a frame after the engine
  moved (the casters read again from the depsgraph, then the maps).
Run: xvfb-run -a blender --factory-startup --python-exit-code 1 --python blender_tests/benchmark_source_shadows.py -- --zip Z
     Options after --: --frames 3
"""

import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402

import benchmark_viewport as viewport  # noqa: E402

ENGINE = "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"
HDRIS = ("sunrise.exr", "studio.exr")


def main():
    args = sdtest.arguments()
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    frames = int(argv[argv.index("--frames") + 1]) if "--frames" in argv else 3
    package = sdtest.install_addon(args.zip)
    from sd_lighting.live import drawing, gpu_context
    from sd_lighting.scene.view import View
    scene = sdtest.empty_scene()
    sdtest.default_settings(scene)
    world, mapping = sdtest.hdri_world(scene, sdtest.hdri(HDRIS[0]))
    engine = sdtest.sized_model(ENGINE, 4.0, (0.0, 0.0, 0.0))
    bpy.context.view_layer.update()
    engine.location.z -= min((engine.matrix_world @ v.co).z for v in engine.data.vertices)
    ground = sdtest.grid(scene, cuts=60, size=10.0)
    white = sdtest.diffuse_material("White")
    for obj in (engine, ground):
        obj.data.materials.clear()
        obj.data.materials.append(white)
    camera = sdtest.camera(scene, location=(0.0, -9.0, 6.0), target=(0.0, 0.0, 1.0))
    settings = sdtest.bake_settings(scene, 'prt_diffuse', 'LAMBERT', 8, rays=256, select=[engine, ground])
    start = time.perf_counter()
    assert bpy.ops.sd_lighting.bake(go_ahead=True) == {'FINISHED'}
    vertices = sum(len(package.store.baked.baked_mesh(o).vertices) for o in (engine, ground))
    print("baked %d vertices in %.1f s" % (vertices, time.perf_counter() - start), flush=True)
    gpu_context.ensure()
    view = View.from_camera(camera, bpy.context.evaluated_depsgraph_get(), viewport.WIDTH, viewport.HEIGHT, scene)
    objects = [engine, ground]

    def draw(per_pixel):
        return lambda: drawing.draw_objects(scene, objects, view, 1.0, per_pixel, wait=True)

    def turning(per_pixel):
        def frame():
            mapping.inputs["Rotation"].default_value[2] += math.radians(1.0)
            drawing.draw_objects(scene, objects, view, 1.0, per_pixel, wait=True)
        return frame

    def moved(per_pixel):
        def frame():
            engine.location.x += 1e-4
            bpy.context.view_layer.update()   # a depsgraph update: the casters are read again
            drawing.draw_objects(scene, objects, view, 1.0, per_pixel, wait=True)
        return frame

    print("\nFrame time, %d x %d, llvmpipe (ms; ratio to SH alone)" % (viewport.WIDTH, viewport.HEIGHT))
    print("| HDRI | shading | SH alone | sources, still | world turning | after a move |")
    print("|---|---|---|---|---|---|")
    for hdri in HDRIS:
        world.node_tree.nodes["Environment Texture"].image = bpy.data.images.load(sdtest.hdri(hdri), check_existing=True)
        found = package.scene.environment.bright_sources(package.scene.environment.source(scene), wait=True)
        for per_pixel in (False,):
            settings.source_shadows = False
            base = viewport.time_frames(draw(per_pixel), frames)
            settings.source_shadows = True
            cells = [viewport.time_frames(f(per_pixel), frames) for f in (draw, turning, moved)]
            print("| %s (%d sources) | %s | %.0f | %s |" % (
                hdri, len(found), "per pixel" if per_pixel else "per vertex", 1000 * base,
                " | ".join("%.0f (%.2fx)" % (1000 * t, t / base) for t in cells)), flush=True)
    return 0


if __name__ == "__main__":
    sdtest.run(main)
