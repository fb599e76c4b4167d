"""The four scenes of the accuracy-cost report (blender_tests/accuracy_report.py), each with a
camera and a white Diffuse BSDF on every object (Lambert in the add-on and in Cycles):

- sphere:  an icosphere alone (convex: no self-shadowing);
- suzanne: the main job's scene (blender_tests/run_default_scene.py: Suzanne on a ground plane);
- bowl:    a hemispherical bowl opening upwards, walls made solid by a Solidify modifier (strongly
           concave: its inside sees a cap of the sky);
- house:   a real asset the project did not make, with hard edges and flat faces: Debian's
           assimp-testmodels OBJ/regr01.obj (a 3ds Max export of a small house: walls, doors,
           rafters, a roof), faces shaded flat, scaled to about 4 units.

Each builder returns (objects measured - the first is the one the vertex grid measures - , camera).
"""

import math
import os

import bpy
import numpy as np

import run_default_scene
import sdtest

HOUSE_OBJ = "/usr/share/assimp/models/OBJ/regr01.obj"


def white(objects):
    material = sdtest.diffuse_material("White")
    for obj in objects:
        obj.data.materials.clear()
        obj.data.materials.append(material)


def sphere(scene):
    ball = sdtest.ico_sphere(scene, "Sphere", subdivisions=4, location=(0.0, 0.0, 0.0))
    camera = sdtest.camera(scene, location=(0.0, -4.2, 0.6), target=(0.0, 0.0, 0.0), lens=55.0)
    return [ball], camera


def suzanne(scene):
    monkey = run_default_scene.suzanne(scene, subdivisions=1)
    ground = sdtest.grid(scene, name="Ground", cuts=24, size=6.0)
    camera = sdtest.camera(scene, location=(3.2, -6.2, 3.0), target=(0.0, 0.0, 0.75), lens=45.0)
    return [monkey, ground], camera


def bowl(scene):
    import bmesh
    mesh = bpy.data.meshes.new("Bowl")
    bm = bmesh.new()
    kwargs = {"u_segments": 48, "v_segments": 24}
    kwargs["radius" if bpy.app.version >= (3, 0, 0) else "diameter"] = 1.0
    bmesh.ops.create_uvsphere(bm, **kwargs)
    bmesh.ops.delete(bm, geom=[v for v in bm.verts if v.co.z > 1e-6], context='VERTS')
    bm.to_mesh(mesh)
    bm.free()
    mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    obj = sdtest.add_object(scene, "Bowl", mesh)
    obj.location = (0.0, 0.0, 1.0)
    solidify = obj.modifiers.new("Solidify", 'SOLIDIFY')
    solidify.thickness = 0.08
    camera = sdtest.camera(scene, location=(0.0, -3.2, 3.4), target=(0.0, 0.0, 0.6), lens=45.0)
    return [obj], camera


def house(scene):
    if not os.path.isfile(HOUSE_OBJ):
        raise FileNotFoundError("%s not found: apt-get install assimp-testmodels "
                                "(scripts/install_dependencies.sh)" % HOUSE_OBJ)
    before = set(bpy.data.objects)
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=HOUSE_OBJ)
    else:
        bpy.ops.import_scene.obj(filepath=HOUSE_OBJ)
    parts = [o for o in bpy.data.objects if o not in before and o.type == 'MESH']
    for obj in list(bpy.context.view_layer.objects):
        obj.select_set(obj in parts)
    bpy.context.view_layer.objects.active = parts[0]
    if len(parts) > 1:
        bpy.ops.object.join()
    obj = bpy.context.view_layer.objects.active
    obj.name = "House"
    mesh = obj.data
    mesh.polygons.foreach_set("use_smooth", [False] * len(mesh.polygons))
    co = np.empty(3 * len(mesh.vertices))
    mesh.vertices.foreach_get("co", co)
    world = co.reshape(-1, 3) @ np.array(obj.matrix_world)[:3, :3].T
    low, high = world.min(axis=0), world.max(axis=0)
    scale = 4.0 / float((high - low).max())
    obj.scale = [scale * s for s in obj.scale]
    centre = 0.5 * (low + high) * scale
    obj.location = (-centre[0], -centre[1], -low[2] * scale)
    bpy.context.view_layer.update()
    camera = sdtest.camera(scene, location=(4.5, -5.5, 4.0), target=(0.0, 0.0, 0.6), lens=35.0)
    return [obj], camera


SCENES = {"sphere": sphere, "suzanne": suzanne, "bowl": bowl, "house": house}


def build(name, hdri_path):
    """An empty scene with the HDRI world and the named scene's objects (white Lambert) and
    camera: (scene, objects, camera, environment texture node)."""
    scene = sdtest.empty_scene()
    world, _ = sdtest.hdri_world(scene, hdri_path, rotation_z=math.radians(30.0))
    objects, camera = SCENES[name](scene)
    white(objects)
    bpy.context.view_layer.update()
    texture = next(n for n in world.node_tree.nodes if n.type == 'TEX_ENVIRONMENT')
    return scene, objects, camera, texture


def set_hdri(texture, path):
    texture.image = bpy.data.images.load(path, check_existing=True)
