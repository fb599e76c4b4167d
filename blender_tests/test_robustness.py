"""What users do to baked scenes, and bad input, from the operators: every case ends in a report
that says what happened, and a refused bake changes nothing.

- a selection with objects that cannot be baked (a mesh without faces, an empty mesh, a curve, an
  empty, a mesh scaled to zero on an axis): those are skipped with a warning each, the rest is
  baked; only such objects: refused;
- the environment: no world, an Environment Texture without an image, an image whose file is
  missing, a file that is no image, an HDRI file path that is empty or missing (each refused with
  a report naming it), a world without an Environment Texture (baked, with a warning);
- vertices for which Blender has no normal (zero: docs/blender-notes.md, "Zero vertex normals"):
  baked with their faces' area-weighted normal (+Z without faces), stored as the baked normal,
  with a warning naming the object and how many;
- duplicated baked objects (Shift+D and Alt+D): they share the baked mesh; a clear or a rebake
  of either leaves the other's bake intact, and the last one to let go removes the baked mesh;
- library-linked data (a library written by the test): a linked object and a library override
  are skipped with a reason (their properties are not saved), a local object with a linked mesh
  is baked and its bake survives save and reload; an object baked in its library shows that bake
  and Clear Bake refuses it with the reason;
- a .blend with baked data reopens and saves without the add-on, and the bake still shades the
  same after the add-on is enabled again;
- undo and redo of a bake and of Clear Bake (where Blender has an undo stack: a window, i.e. the
  binary under Xvfb; Blender as a module has none).
Run: xvfb-run -a blender --factory-startup --python-exit-code 1 --python blender_tests/test_robustness.py -- --zip Z --out DIR
"""

import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

ADDON = "sd_lighting"


def bake():
    return sdtest.operator_reports(bpy.ops.sd_lighting.bake)


def clear_bake(objects):
    sdtest.select_only(objects)
    return sdtest.operator_reports(bpy.ops.sd_lighting.clear_bake)


def baked_state(package, obj):
    """(baked mesh name, bake id, AO) of the object's bake, or None."""
    mesh = package.store.baked.baked_mesh(obj)
    if mesh is None:
        return None
    return (mesh.name, mesh["sd_bake"]["bake_id"],
            package.store.attributes.read(mesh)["ambient_occlusion"].tobytes())


def bake_exists(bake_id):
    return any(dict(m.get("sd_bake", {})).get("bake_id") == bake_id for m in bpy.data.meshes)


def orphans():
    """Baked meshes no object links."""
    linked = {o.get("sd_baked_mesh").name for o in bpy.data.objects if o.get("sd_baked_mesh")}
    return sorted(m.name for m in bpy.data.meshes if "sd_bake" in m and m.name not in linked)


def remove(obj):
    """Removes an object, and its mesh unless another object uses it (an Alt+D copy)."""
    mesh = obj.data
    bpy.data.objects.remove(obj)
    if mesh.users == 0:
        bpy.data.meshes.remove(mesh)


def duplicate(obj, linked):
    sdtest.select_only([obj])
    result = bpy.ops.object.duplicate(linked=linked)
    assert result == {'FINISHED'}, result
    return bpy.context.selected_objects[0]


def check_selection(checks, package, scene, ball):
    wire_mesh = bpy.data.meshes.new("Wire")
    wire_mesh.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0)], [(0, 1), (1, 2)], [])
    wire = sdtest.add_object(scene, "Wire", wire_mesh)
    hollow = sdtest.add_object(scene, "Hollow", bpy.data.meshes.new("Hollow"))
    curve_data = bpy.data.curves.new("Curve", 'CURVE')
    curve_data.splines.new('POLY').points.add(2)
    curve = sdtest.add_object(scene, "Curve", curve_data)
    empty = sdtest.add_object(scene, "Empty", None)
    flat = sdtest.ico_sphere(scene, "Flat", subdivisions=1, location=(3.0, 0.0, 1.0))
    flat.scale = (1.0, 0.0, 1.0)

    sdtest.bake_settings(scene, 'ambient_occlusion', 'LAMBERT', 2, 1, rays=64,
                         select=[ball, wire, hollow, curve, empty, flat])
    before = sdtest.snapshot()
    result, text = bake()
    checks.check(result == {'FINISHED'} and package.store.baked.baked_mesh(ball) is not None,
                 "a selection with unbakeable objects bakes the rest", text.strip())
    for name, reason in (("Wire", "has no faces"), ("Hollow", "has no faces"),
                         ("Curve", "is not a mesh (curve)"), ("Empty", "is not a mesh (empty)"),
                         ("Flat", "has a zero scale")):
        checks.check("skipped: %s %s" % (name, reason) in text and
                     sdtest.snapshot()[name, False] == before[name, False],
                     "%s is skipped with a warning, unchanged" % name)
    sdtest.select_only([wire, hollow, curve])
    before = sdtest.snapshot()
    result, text = bake()
    checks.check(result == {'CANCELLED'} and "nothing to bake: Wire has no faces; Hollow has no "
                 "faces; Curve is not a mesh" in text and sdtest.snapshot() == before,
                 "only unbakeable objects: refused with the reasons, nothing changed", text.strip())
    for obj in (wire, hollow, curve, empty, flat):
        bpy.data.objects.remove(obj)


def check_environment(checks, package, scene, ball, hdri_path, out):
    settings = sdtest.bake_settings(scene, 'ambient_occlusion', 'LAMBERT', 2, 1, rays=64,
                                    select=[ball])
    world = scene.world
    env_node = package.scene.environment.world_nodes(world)[0]
    image = env_node.image

    def refused(what, expected):
        package.scene.environment.clear_cache()
        before = sdtest.snapshot()
        result, text = bake()
        checks.check(result == {'CANCELLED'} and expected in text and sdtest.snapshot() == before,
                     "%s: refused with a report naming it, nothing changed" % what, text.strip())

    scene.world = None
    refused("no world", "the scene has no world")
    scene.world = world

    env_node.image = None
    refused("an Environment Texture without an image",
            "the Environment Texture of world 'SD World' has no image")

    moved = os.path.join(out, "moved_forest.exr")
    shutil.copy(hdri_path, moved)
    env_node.image = bpy.data.images.load(moved)
    os.remove(moved)
    refused("an image whose file is missing",
            "the image 'moved_forest.exr' of world 'SD World' is missing: file %s not found" % moved)

    broken = os.path.join(out, "broken.exr")
    with open(broken, "wb") as f:
        f.write(b"not an image" * 100)
    env_node.image = bpy.data.images.load(broken)
    refused("a file that is no image", "cannot read the environment (%s)" % broken)

    env_node.image = image
    settings.environment_source = 'FILE'
    settings.environment_path = ""
    refused("no HDRI file chosen", "no HDRI file chosen")
    settings.environment_path = moved
    refused("a missing HDRI file", "the HDRI file %s is missing" % moved)
    settings.environment_source = 'WORLD'

    plain = bpy.data.worlds.new("Plain")
    sdtest.use_nodes(plain)
    scene.world = plain
    result, text = bake()
    checks.check(result == {'FINISHED'} and "world 'Plain' has no Environment Texture: lit by its "
                 "uniform colour" in text, "a world without an Environment Texture: baked, with a "
                 "warning", text.strip())
    scene.world = world
    package.scene.environment.clear_cache()
    result, text = bake()
    checks.check(result == {'FINISHED'} and "Warning" not in text, "the HDRI world bakes without warnings",
                 text.strip())


def check_zero_normals(checks, package, scene):
    # Vertex 0 (at the origin) is the right-angled corner of a large face facing +X and of a small
    # one facing -X, both smooth: Blender's angle-weighted normal sums to zero there, and a zero sum
    # at the origin stays zero (3.4 and 5.0), in its vertex and corner normals alike; vertex 5 is a
    # loose vertex at the origin (zero on both), which the baked copy leaves out (no face draws it).
    # The faces' area-weighted normal of vertex 0 is +X.
    mesh = bpy.data.meshes.new("Fan")
    mesh.from_pydata([(0, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0.25), (0, 0.25, 0), (0, 0, 0)], [],
                     [(0, 1, 2), (0, 3, 4)])
    mesh.polygons.foreach_set("use_smooth", [True, True])
    culled = sdtest.diffuse_material("Front only")
    culled.use_backface_culling = True   # one side: no reverse copies (bake/sides.py)
    mesh.materials.append(culled)
    mesh.update()
    fan = sdtest.add_object(scene, "Fan", mesh)
    fan.location = (3.0, 0.0, 0.5)
    given = package.compat.vertex_normals(mesh)
    corner = package.compat.corner_normals(mesh)
    checks.check(np.all(given[[0, 5]] == 0.0) and np.all(corner[[0, 3]] == 0.0) and
                 np.all(np.linalg.norm(given[1:5], axis=1) > 0.99),
                 "Blender gives the test mesh's vertices 0 and 5 a zero normal", str(given.tolist()))
    sdtest.bake_settings(scene, 'prt_diffuse', 'LAMBERT', 2, 1, rays=64, select=[fan])
    result, text = bake()
    checks.check(result == {'FINISHED'} and "Bake: 1 vertex of Fan had no usable normal; their "
                 "faces' normal was used" in text, "zero normals: baked, with a warning", text.strip())
    baked = package.store.baked.baked_mesh(fan)
    normals = package.store.attributes.read_normals(baked) if baked is not None else np.zeros((5, 3))
    checks.check(len(normals) == 5 and np.allclose(normals[0], (1, 0, 0)) and
                 np.allclose(normals[1:5], given[1:5]),
                 "the baked normals are the fallback the bake used (+X), the others Blender's; the "
                 "loose vertex is left out", str(normals.tolist()))
    view = package.scene.view.View.from_camera(scene.camera, bpy.context.evaluated_depsgraph_get(),
                                            320, 240, scene)
    checks.check(baked is not None and np.isfinite(package.live.drawing.cpu_reference(scene, fan, view)).all(),
                 "the repaired bake shades (finite)")
    package.store.baked.clear(fan)
    remove(fan)


def check_duplicates(checks, package, scene, ball):
    sdtest.bake_settings(scene, 'ambient_occlusion', 'LAMBERT', 2, 1, rays=64, select=[ball])
    assert bake()[0] == {'FINISHED'}
    for linked, kind in ((False, "Shift+D"), (True, "Alt+D")):
        original = baked_state(package, ball)
        copy = duplicate(ball, linked)
        checks.check(baked_state(package, copy) == original,
                     "%s: the copy shares the original's bake" % kind)
        result, text = clear_bake([copy])
        checks.check(result == {'FINISHED'} and baked_state(package, copy) is None and
                     baked_state(package, ball) == original,
                     "%s: clearing the copy leaves the original's bake" % kind, text.strip())
        remove(copy)

        copy = duplicate(ball, linked)
        sdtest.select_only([copy])
        result, text = bake()
        copied = baked_state(package, copy)
        checks.check(result == {'FINISHED'} and copied is not None and copied[:2] != original[:2]
                     and baked_state(package, ball) == original,
                     "%s: rebaking the copy bakes it into a new mesh and leaves the original's"
                     % kind, "%s, %s" % (copied[:2] if copied else None, original[:2]))

        third = duplicate(ball, linked)
        sdtest.select_only([ball])
        result, text = bake()
        rebaked = baked_state(package, ball)
        checks.check(result == {'FINISHED'} and rebaked[:2] != original[:2] and
                     baked_state(package, third) == original and baked_state(package, copy) == copied,
                     "%s: rebaking the original leaves the copies' bakes" % kind,
                     "%s; %s; %s" % ((baked_state(package, third) or "-")[:2], original[:2], text.strip()))
        result, text = clear_bake([third])
        checks.check(result == {'FINISHED'} and not bake_exists(original[1]) and not orphans(),
                     "%s: the last object to let go of a baked mesh removes it" % kind,
                     "orphans: %s" % orphans())
        result, text = clear_bake([copy])
        checks.check(not bake_exists(copied[1]) and baked_state(package, ball) == rebaked,
                     "%s: clearing the copy's own bake removes only it" % kind)
        remove(copy)
        remove(third)

    # Copies baked together: their shared old baked mesh goes once.
    copy = duplicate(ball, False)
    sdtest.select_only([ball, copy])
    result, text = bake()
    checks.check(result == {'FINISHED'} and baked_state(package, ball)[0] != baked_state(package, copy)[0]
                 and not orphans(), "an object and its copy baked together get a mesh each",
                 text.strip())
    remove(copy)


def write_library(scene, out):
    """A .blend holding the objects LibBall, LibOverride, LibMeshOnly and LibBaked (baked here,
    its baked mesh written with it), each with its mesh."""
    import bmesh
    path = os.path.join(out, "test_robustness_library.blend")
    written = set()
    for name in ("LibBall", "LibOverride", "LibMeshOnly", "LibBaked"):
        mesh = bpy.data.meshes.new(name + "Mesh")
        bm = bmesh.new()
        bmesh.ops.create_icosphere(bm, subdivisions=1, radius=0.5)
        bm.to_mesh(mesh)
        bm.free()
        written.add(sdtest.add_object(scene, name, mesh))
    sdtest.select_only([bpy.data.objects["LibBaked"]])
    assert bake()[0] == {'FINISHED'}
    baked = bpy.data.objects["LibBaked"]["sd_baked_mesh"]
    bpy.data.libraries.write(path, written, fake_user=True)
    for obj in written:
        remove(obj)
    bpy.data.meshes.remove(baked)
    return path


def check_library(checks, package, scene, args):
    library = write_library(scene, args.out)
    with bpy.data.libraries.load(library, link=True) as (source, linked):
        linked.objects = ["LibBall", "LibOverride", "LibBaked"]
        linked.meshes = ["LibMeshOnlyMesh"]
    lib_ball, lib_override, lib_baked = linked.objects
    lib_mesh = linked.meshes[0]
    scene.collection.objects.link(lib_ball)
    lib_ball.location = (3.0, 0.0, 1.0)
    scene.collection.objects.link(lib_override)
    override = lib_override.override_create(remap_local_usages=True)
    local = sdtest.add_object(scene, "LocalWithLinkedMesh", lib_mesh)
    local.location = (-3.0, 0.0, 1.0)
    checks.check(lib_ball.library is not None and override.override_library is not None and
                 local.library is None and local.data.library is not None,
                 "linked object, library override and local object with a linked mesh")

    sdtest.bake_settings(scene, 'ambient_occlusion', 'LAMBERT', 2, 1, rays=64, select=[lib_ball])
    before = sdtest.snapshot()
    result, text = bake()
    checks.check(result == {'CANCELLED'} and "LibBall is linked from %s" % lib_ball.library.filepath
                 in text and "make it local" in text and sdtest.snapshot() == before,
                 "a linked object alone: refused with the reason, nothing changed", text.strip())
    sdtest.select_only([lib_ball, override, local])
    result, text = bake()
    checks.check(result == {'FINISHED'} and "skipped: LibBall is linked from" in text and
                 "skipped: LibOverride is a library override" in text and
                 "sd_bake" not in lib_ball and "sd_bake" not in override and
                 package.store.baked.baked_mesh(local) is not None,
                 "linked object and override skipped with a reason, the local object with a linked "
                 "mesh baked", text.strip())
    scene.collection.objects.link(lib_baked)
    state = baked_state(package, lib_baked)
    before = sdtest.snapshot()
    result, text = clear_bake([lib_baked])
    checks.check(state is not None and package.store.baked.baked_mesh(lib_baked).library is not None and
                 result == {'CANCELLED'} and "its bake can only be cleared there" in text and
                 sdtest.snapshot() == before and baked_state(package, lib_baked) == state,
                 "a linked object baked in its library: its bake is used, Clear Bake refuses with "
                 "the reason", text.strip())
    scene.collection.objects.unlink(lib_baked)

    state = baked_state(package, local)
    path = os.path.join(args.out, "test_robustness_library_user.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    local = bpy.data.objects[("LocalWithLinkedMesh", None)]
    checks.check(baked_state(package, local) == state and local.data.library is not None,
                 "the bake of a local object with a linked mesh survives save and reload")
    return bpy.context.scene


def check_without_addon(checks, package, scene, ball, args):
    import addon_utils
    sdtest.bake_settings(scene, 'msd_visibility', 'PHONG', 3, 1, rays=64, phong_exponent=8.0,
                         select=[ball])
    assert bake()[0] == {'FINISHED'}
    view = package.scene.view.View.from_camera(scene.camera, bpy.context.evaluated_depsgraph_get(),
                                            320, 240, scene)
    shaded = package.live.drawing.cpu_reference(scene, ball, view)
    state = baked_state(package, ball)
    path = os.path.join(args.out, "test_robustness_baked.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)

    addon_utils.disable(ADDON)
    try:
        bpy.ops.wm.open_mainfile(filepath=path)
        ball = bpy.data.objects["Ball"]
        mesh = ball.get("sd_baked_mesh")
        checks.check(not hasattr(bpy.types.Scene, "sd_lighting") and mesh is not None and
                     "sd_design_count" in mesh.attributes and ball["sd_bake"]["method"] == "msd_visibility" and
                     isinstance(mesh.get("sd_design_nodes"), bpy.types.Mesh),
                     "the .blend opens without the add-on, its bake data present (with the designs' nodes)")
        path = os.path.join(args.out, "test_robustness_saved_without.blend")
        bpy.ops.wm.save_as_mainfile(filepath=path)
    finally:
        addon_utils.enable(ADDON)
    package = sys.modules[ADDON]
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    ball = bpy.data.objects["Ball"]
    again = package.live.drawing.cpu_reference(scene, ball, view)
    checks.check(baked_state(package, ball) == state and np.array_equal(again, shaded) and
                 scene.sd_lighting.method == 'msd_visibility',
                 "saved without the add-on, reopened with it: the same bake, shading and settings")


def check_undo(checks, package):
    def ed(name, **kwargs):
        return sdtest.operator_reports(getattr(bpy.ops.ed, name), **kwargs)[0] == {'FINISHED'}

    ball = bpy.data.objects["Ball"]
    clear_bake([ball])
    # What the UI does: an undo step before and after each operator.
    ed("undo_push", message="before the bake")
    assert bake()[0] == {'FINISHED'}
    state = baked_state(package, ball)
    ed("undo_push", message="SD Lighting Bake")
    if not ed("undo"):
        print("undo: Blender has no undo stack here (a bpy module, or no window): not tested")
        return
    ball = bpy.data.objects["Ball"]
    checks.check(package.store.baked.baked_mesh(ball) is None and "sd_bake" not in ball and
                 not bake_exists(state[1]), "undo of a bake removes it")
    ed("redo")
    ball = bpy.data.objects["Ball"]
    scene = bpy.context.scene
    view = package.scene.view.View.from_camera(scene.camera, bpy.context.evaluated_depsgraph_get(),
                                            320, 240, scene)
    checks.check(baked_state(package, ball) == state and
                 np.isfinite(package.live.drawing.cpu_reference(scene, ball, view)).all(),
                 "redo brings the bake back, and it shades")
    clear_bake([ball])
    ed("undo_push", message="Clear Bake")
    ed("undo")
    ball = bpy.data.objects["Ball"]
    checks.check(baked_state(package, ball) == state, "undo of Clear Bake brings the bake back")


def main():
    checks = sdtest.Checks("test_robustness")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)

    scene = sdtest.empty_scene()
    hdri_path = sdtest.hdri("forest.exr")
    sdtest.hdri_world(scene, hdri_path)
    ball = sdtest.ico_sphere(scene, subdivisions=1, location=(0.0, 0.0, 0.8))
    sdtest.grid(scene, cuts=6, size=4.0)
    sdtest.camera(scene)

    check_selection(checks, package, scene, ball)
    check_environment(checks, package, scene, ball, hdri_path, args.out)
    check_zero_normals(checks, package, scene)
    check_duplicates(checks, package, scene, ball)
    scene = check_library(checks, package, scene, args)
    ball = bpy.data.objects["Ball"]
    check_without_addon(checks, package, scene, ball, args)
    check_undo(checks, sys.modules[ADDON])
    return checks.summary()


sdtest.run(main)
