"""Shared helpers of the Blender-run tests: arguments, installing the add-on zip, test scenes,
checks with a one-line summary, and a crash-free exit.

Every test script is run by Blender:
    blender [-b] --factory-startup --python-exit-code 1 --python blender_tests/<test>.py -- \
        --zip build/sd_lighting.zip --out build/blender_tests
or by the Python of Blender as a module (the bpy wheel), which behaves like `blender -b`:
    VENV/bin/python blender_tests/<test>.py -- --zip build/sd_lighting.zip --out DIR
(run.py does that for all of them; GPU tests run under xvfb-run with a Blender binary).
"""

import argparse
import faulthandler
import gc
import os
import sys
import time
import traceback
import warnings

import bpy

BLENDER_HDRI_DIR = "/usr/share/blender/datafiles/studiolights/world"
EXTENSION_REPOSITORY = "user_default"

# The module name of the add-on the test installed: "sd_lighting" as a legacy add-on,
# "bl_ext.user_default.sd_lighting" as an extension (4.2+).
addon_module = "sd_lighting"


def hdri(name="forest.exr"):
    """A Blender-shipped HDRI (CC0): the running Blender's own, else Debian's."""
    candidates = []
    datafiles = bpy.utils.system_resource('DATAFILES')
    if datafiles:
        candidates.append(os.path.join(datafiles, "studiolights", "world", name))
    candidates.append(os.path.join(BLENDER_HDRI_DIR, name))
    for path in candidates:
        if os.path.isfile(path):
            return path
    raise FileNotFoundError("Blender's HDRI %s not found" % name)


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", default=None, help="the add-on zip to install")
    parser.add_argument("--out", default=os.path.join(os.getcwd(), "blender_test_output"))
    parser.add_argument("--quick", action="store_true", help="the quick tier's part of the test")
    # --no-numeric: leave out the test's version-independent numeric checks (numbers of the native
    # module against references - a Monte Carlo reference, the s = 16 ringing window, shading with
    # and without an applied scale - that no Blender version changes); the CTest suite runs them on
    # Debian's Blender only and passes --no-numeric on the others (tests/CMakeLists.txt).
    parser.add_argument("--no-numeric", dest="numeric", action="store_false",
                        help="leave out the version-independent numeric checks")
    args, _ = parser.parse_known_args(argv)
    args.out = os.path.abspath(args.out)
    os.makedirs(args.out, exist_ok=True)
    return args


def install_addon(zip_path):
    """Installs the zip as a legacy add-on and enables it; returns the add-on's package."""
    import addon_utils
    if not zip_path or not os.path.isfile(zip_path):
        raise FileNotFoundError("add-on zip not found: %r (pass --zip)" % zip_path)
    result = bpy.ops.preferences.addon_install(filepath=os.path.abspath(zip_path), overwrite=True)
    if result != {'FINISHED'}:
        raise RuntimeError("addon_install returned %s" % result)
    addon_utils.modules_refresh()
    bpy.ops.preferences.addon_enable(module="sd_lighting")
    import sd_lighting
    return sd_lighting


def install_extension(zip_path):
    """Installs the zip as an extension (Blender 4.2+: Get Extensions > Install from Disk) into the
    user repository and enables it; returns the add-on's package (bl_ext.user_default.sd_lighting)."""
    global addon_module
    import importlib
    if not zip_path or not os.path.isfile(zip_path):
        raise FileNotFoundError("add-on zip not found: %r (pass --zip)" % zip_path)
    result = bpy.ops.extensions.package_install_files(
        filepath=os.path.abspath(zip_path), repo=EXTENSION_REPOSITORY, enable_on_install=True)
    if result != {'FINISHED'}:
        raise RuntimeError("extensions.package_install_files returned %s" % result)
    addon_module = "bl_ext.%s.sd_lighting" % EXTENSION_REPOSITORY
    return importlib.import_module(addon_module)


# Warnings raised by the add-on's own code (DeprecationWarning: an API that the next Blender drops,
# e.g. World.use_nodes in 5.0, vertex formats in 4.5); Checks.summary() fails on any. Python shows
# DeprecationWarning only in __main__ by default: show them all.
addon_warnings = []
_show_warning = warnings.showwarning


def _record_warning(message, category, filename, lineno, file=None, line=None):
    if "sd_lighting" in os.path.normpath(filename).split(os.sep):
        addon_warnings.append("%s:%d: %s: %s" % (os.path.basename(filename), lineno,
                                                 category.__name__, message))
    _show_warning(message, category, filename, lineno, file, line)


warnings.showwarning = _record_warning
warnings.simplefilter("always")


def registration_state():
    """What registering the add-on adds to Blender: unregistering must take all of it back."""
    def operator_exists(name):
        try:
            getattr(bpy.ops.sd_lighting, name).get_rna_type()
            return True
        except (AttributeError, KeyError):
            return False
    return {"scene_property": hasattr(bpy.types.Scene, "sd_lighting"),
            "panel": hasattr(bpy.types, "SD_PT_lighting"),
            "panels": sorted(name for name in dir(bpy.types) if name.startswith("SD_PT_")),
            "bake_operator": operator_exists("bake"),
            "preview_operator": operator_exists("render_preview"),
            "handlers": {name: len(getattr(bpy.app.handlers, name)) for name in HANDLER_LISTS}}


# The handler lists the add-on adds to: while it is enabled, and those Live Re-bake adds to while
# a scene has it on.
HANDLER_LISTS = ("load_post", "save_pre", "depsgraph_update_post", "frame_change_post", "undo_post",
                 "redo_post")
LIVE_REBAKE_HANDLERS = ("depsgraph_update_post", "undo_post", "redo_post")


class LayoutStub:
    """Accepts any layout call, to run a panel's draw() without a visible sidebar; `texts` collects
    the text= of every call (labels, operator buttons)."""

    def __init__(self, texts=None):
        object.__setattr__(self, "texts", [] if texts is None else texts)

    def __getattr__(self, name):
        return LayoutStub(self.texts)

    def __call__(self, *args, **kwargs):
        if "text" in kwargs:
            self.texts.append(kwargs["text"])
        return LayoutStub(self.texts)

    def __setattr__(self, name, value):
        pass


def panel_texts(context=None):
    """The texts the add-on's sidebar panel and its sub-panels draw now, in their order, into one
    LayoutStub: every sub-panel whose poll() passes (and its parent's), open or closed."""
    import importlib
    context = context or bpy.context
    stub = LayoutStub()
    drawn = set()
    for cls in importlib.import_module(addon_module + ".ui.panels").CLASSES:
        parent = getattr(cls, "bl_parent_id", "")
        if (parent and parent not in drawn) or (hasattr(cls, "poll") and not cls.poll(context)):
            continue
        drawn.add(cls.bl_idname)
        if hasattr(cls, "draw_header"):
            cls.draw_header(stub, context)
        cls.draw(stub, context)
    return stub.texts


class Checks:
    """Collects named checks; `summary()` prints one line and returns the exit code."""

    def __init__(self, name):
        self.name = name
        self.failed = []
        self.passed = 0
        self.start = time.perf_counter()

    def check(self, ok, what, detail=""):
        tag = "PASS" if ok else "FAIL"
        print("[%s] %s%s" % (tag, what, (": " + detail) if detail else ""), flush=True)
        if ok:
            self.passed += 1
        else:
            self.failed.append(what)
        return ok

    def summary(self):
        self.check(not addon_warnings, "the add-on raised no warnings (deprecated API)",
                   "; ".join(addon_warnings[:3]))
        seconds = time.perf_counter() - self.start
        if self.failed:
            print("%s: FAILED %d of %d checks (%s) in %.1f s" % (
                self.name, len(self.failed), len(self.failed) + self.passed,
                "; ".join(self.failed), seconds), flush=True)
            return 1
        print("%s: OK, %d checks passed in %.1f s" % (self.name, self.passed, seconds), flush=True)
        return 0


def finish(code):
    """Disables the add-on (freeing its GPU data while the context lives) and exits with `code`
    without running Blender's exit path (no crash at exit can change the test's result)."""
    try:
        import addon_utils
        if addon_module:
            addon_utils.disable(addon_module)
    except Exception:
        traceback.print_exc()
        code = code or 1
    gc.collect()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def run(main):
    """Runs main() -> exit code; any exception fails the test. A crash prints the Python stack
    of every thread first (faulthandler), so that the log says where it happened."""
    faulthandler.enable(all_threads=True)
    try:
        code = main()
    except Exception:
        traceback.print_exc()
        print("test aborted by an exception", flush=True)
        code = 1
    finish(code)


# ----------------------------------------------------------------------------------------------
# Scenes

def empty_scene():
    """The current scene emptied of objects and their data (read_factory_settings would also
    disable the add-on)."""
    scene = bpy.context.scene
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    for collection in (bpy.data.meshes, bpy.data.cameras, bpy.data.lights, bpy.data.materials):
        for block in list(collection):
            collection.remove(block)
    return scene


def use_nodes(idblock):
    """Shades a world or material with its node tree (5.0 always does; its use_nodes is
    deprecated)."""
    if bpy.app.version < (5, 0, 0):
        idblock.use_nodes = True


def hdri_world(scene, path, rotation_z=0.0, strength=1.0):
    """World: Texture Coordinate > Mapping > Environment Texture > Background."""
    world = bpy.data.worlds.new("SD World")
    use_nodes(world)
    scene.world = world
    tree = world.node_tree
    background = tree.nodes["Background"]
    background.inputs["Strength"].default_value = strength
    coords = tree.nodes.new("ShaderNodeTexCoord")
    mapping = tree.nodes.new("ShaderNodeMapping")
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(path, check_existing=True)
    tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    tree.links.new(env.outputs["Color"], background.inputs["Color"])
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, rotation_z)
    return world, mapping


def add_object(scene, name, mesh):
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj


def ico_sphere(scene, name="Ball", subdivisions=2, radius=1.0, location=(0.0, 0.0, 1.0), smooth=True):
    """An icosphere, shaded smooth by default: its baked copy then keeps its vertices (flat faces
    give each face corner a vertex of its own: bake/corners.py)."""
    import bmesh
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    kwargs = {"subdivisions": subdivisions}
    kwargs["radius" if bpy.app.version >= (3, 0, 0) else "diameter"] = radius
    bmesh.ops.create_icosphere(bm, **kwargs)
    bm.to_mesh(mesh)
    bm.free()
    mesh.polygons.foreach_set("use_smooth", [smooth] * len(mesh.polygons))
    obj = add_object(scene, name, mesh)
    obj.location = location
    return obj


def flat_cube(scene, name="Cube", size=1.0, location=(0.0, 0.0, 0.0)):
    """A cube of flat faces (six charts of a lightmap; 24 corner copies in a bake)."""
    import bmesh
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=size)
    bm.to_mesh(mesh)
    bm.free()
    obj = add_object(scene, name, mesh)
    obj.location = location
    return obj


def _material(name, bsdf_type):
    """A material whose node tree is one new BSDF node of `bsdf_type` feeding the output:
    (material, the BSDF node)."""
    material = bpy.data.materials.new(name)
    use_nodes(material)
    tree = material.node_tree
    for node in list(tree.nodes):
        if node.type != 'OUTPUT_MATERIAL':
            tree.nodes.remove(node)
    bsdf = tree.nodes.new(bsdf_type)
    tree.links.new(bsdf.outputs["BSDF"], tree.nodes["Material Output"].inputs["Surface"])
    return material, bsdf


def diffuse_material(name, colour=(1.0, 1.0, 1.0, 1.0), image=None):
    """A material of one Diffuse BSDF (Lambert in the add-on and in Cycles) of the colour, or of the
    image plugged into its colour. A white one makes the live shading show B itself (an object
    without a material has Blender's default 0.8 grey surface)."""
    material, diffuse = _material(name, "ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = colour
    if image is not None:
        texture = material.node_tree.nodes.new("ShaderNodeTexImage")
        texture.image = image
        material.node_tree.links.new(texture.outputs["Color"], diffuse.inputs["Color"])
    return material


def principled_material(name, colour=(1.0, 1.0, 1.0, 1.0), roughness=0.5, metallic=0.0):
    """A material of one Principled BSDF (its other inputs at their defaults)."""
    material, bsdf = _material(name, "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = colour
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    return material


def grid(scene, name="Ground", cuts=10, size=4.0, location=(0.0, 0.0, 0.0)):
    import bmesh
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    bmesh.ops.create_grid(bm, x_segments=cuts, y_segments=cuts, size=size / 2.0)
    bm.to_mesh(mesh)
    bm.free()
    obj = add_object(scene, name, mesh)
    obj.location = location
    return obj


def camera(scene, location=(0.0, -6.0, 3.0), target=(0.0, 0.0, 0.7), lens=40.0):
    from mathutils import Vector
    data = bpy.data.cameras.new("Camera")
    data.lens = lens
    obj = add_object(scene, "Camera", data)
    obj.location = location
    direction = Vector(target) - Vector(location)
    obj.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()
    scene.camera = obj
    return obj


def select_only(objects):
    bpy.context.view_layer.update()  # creates the bases of newly linked objects
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj in objects)
    if objects:
        bpy.context.view_layer.objects.active = objects[0]


def default_settings(scene):
    """Puts the scene's add-on settings back to the panel's defaults (bake_settings leaves its
    choices in the scene, and empty_scene keeps them); returns them."""
    settings = scene.sd_lighting
    for prop in settings.bl_rna.properties:
        if prop.identifier != "rna_type" and not prop.is_readonly and prop.type not in ('POINTER', 'COLLECTION'):
            settings.property_unset(prop.identifier)
    return settings


def bake_settings(scene, method, material, light_order, visibility_order=None, rays=256,
                  phong_exponent=None, select=(), refine=False, least_squares=False):
    """Sets what the next bake uses (fixed orders, no automatic s; no refinement unless asked:
    the baked copy then has the evaluated mesh's vertices; no least-squares fit unless asked: the
    vertices keep the values baked at them) and selects `select`; returns the scene's settings."""
    settings = scene.sd_lighting
    settings.refine = refine
    settings.least_squares = least_squares
    settings.method = method
    settings.material_source = material
    if phong_exponent is not None:
        settings.phong_exponent = phong_exponent
    settings.automatic_orders = False
    settings.light_order = light_order
    if visibility_order is not None:
        settings.visibility_order = visibility_order
    settings.rays = rays
    if select:
        select_only(list(select))
    return settings


def operator_reports(operator, **kwargs):
    """Runs an operator from the script: (its result, the text of its reports). Blender prints the
    reports of an operator a script runs to sys.stdout, and raises RuntimeError (with the error
    reports) when one is an error; the text is echoed to the log. With a window (Blender under
    Xvfb) a file opened by the script leaves the context without one: the operator gets the
    first window back."""
    import contextlib
    import io
    text = io.StringIO()
    windows = bpy.context.window_manager.windows
    override = (bpy.context.temp_override(window=windows[0])
                if bpy.context.window is None and len(windows) else contextlib.nullcontext())
    with contextlib.redirect_stdout(text), override:
        try:
            result = operator(**kwargs)
        except RuntimeError as exc:
            result = {'CANCELLED'}
            print(exc)
    sys.stdout.write(text.getvalue())
    return result, text.getvalue()


def snapshot():
    """What a failed or cancelled bake must leave unchanged: the meshes, and per object its baked
    mesh, bake id, vertex count and attribute names."""
    out = {"meshes": sorted(m.name for m in bpy.data.meshes)}
    for obj in bpy.data.objects:
        mesh = obj.get("sd_baked_mesh")
        out[obj.name, obj.library is not None] = (
            mesh.name if mesh else None,
            dict(obj["sd_bake"]).get("bake_id") if "sd_bake" in obj else None,
            len(obj.data.vertices) if obj.type == 'MESH' else None,
            sorted(a.name for a in obj.data.attributes) if obj.type == 'MESH' else None)
    return out


def bilinear(image, x, y):
    """RGB at sub-pixel positions (pixel centres at i + 0.5): Gouraud shading is linear inside a
    triangle, so this recovers a vertex's value up to the triangles' kinks."""
    import numpy as np
    fx, fy = x - 0.5, y - 0.5
    x0, y0 = np.floor(fx).astype(int), np.floor(fy).astype(int)
    tx, ty = (fx - x0)[:, None], (fy - y0)[:, None]
    c = lambda yy, xx: image[yy, xx, :3]  # noqa: E731
    return ((1 - ty) * ((1 - tx) * c(y0, x0) + tx * c(y0, x0 + 1)) +
            ty * ((1 - tx) * c(y0 + 1, x0) + tx * c(y0 + 1, x0 + 1)))


def relative_error(gpu_values, cpu_values):
    """max |gpu - cpu| / max |cpu| (over all vertices and channels) and the per-vertex worst
    |gpu - cpu| / max(|cpu|, 1 % of the largest)."""
    import numpy as np
    cpu_values = np.asarray(cpu_values, dtype=np.float64)
    diff = np.abs(np.asarray(gpu_values, dtype=np.float64) - cpu_values)
    scale = max(float(np.abs(cpu_values).max()), 1e-30)
    per_vertex = diff / np.maximum(np.abs(cpu_values), 0.01 * scale)
    return float(diff.max() / scale), float(per_vertex.max())


# ----------------------------------------------------------------------------------------------
# Images: Cycles against the preview

def load_exr(path):
    """An EXR's RGBA as float32 [H, W, 4], rows top-first."""
    import numpy as np
    image = bpy.data.images.load(path)
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)[::-1]


def preview(path, **size):
    """sd_lighting.render_preview into the EXR `path` (size: width=, height=; else the scene's
    resolution), read back as load_exr reads it."""
    assert bpy.ops.sd_lighting.render_preview(filepath=path, **size) == {'FINISHED'}, path
    return load_exr(path)


def flip_module():
    """NVIDIA's FLIP (flip-evaluator), from the tools venv (blender_tests/bpy_modules.py install):
    CPython 3.11 only. Raises ImportError saying how to install it; a test that measures with it
    calls this first, so that it fails before its renders."""
    import bpy_modules
    if sys.version_info[:2] == (3, 11) and bpy_modules.tools_site_packages() not in sys.path:
        sys.path.append(bpy_modules.tools_site_packages())
    try:
        import flip_evaluator
    except ImportError:
        raise ImportError("NVIDIA's FLIP: flip-evaluator (blender_tests/tools_requirements.txt) on CPython 3.11 "
                          "in %s: `python3 blender_tests/bpy_modules.py install`; this is CPython %d.%d"
                          % ((bpy_modules.tools_site_packages(),) + sys.version_info[:2])) from None
    return flip_evaluator


def perceptual_error(ours, theirs):
    """Mean HDR-FLIP (NVIDIA's FLIP for linear images: Andersson et al. 2021; flip-evaluator's
    defaults: 67 pixels per degree, ACES tone mapping over the exposures the reference spans) of
    `ours` against the reference `theirs`, RGBA images, averaged over the pixels both cover
    (covered; FLIP itself sees the whole frame: its filters reach across an object's edge, and the
    reference's background counts towards its exposures): 0 identical, 1 as different as can be.
    Per pixel, where relative RMS averages blocks: it sees a highlight's shape and a shadow's edge."""
    import numpy as np
    mask = covered(ours, theirs)
    errors, _, _ = flip_module().evaluate(
        np.ascontiguousarray(np.maximum(theirs[..., :3], 0.0), dtype=np.float32),
        np.ascontiguousarray(np.maximum(ours[..., :3], 0.0), dtype=np.float32), "HDR",
        applyMagma=False, computeMeanError=False)
    return float(np.asarray(errors)[mask].mean())


def covered(*images):
    """The pixels every one of the RGBA `images` covers (alpha > 0.99: inside the object, not at
    its antialiased or filtered edge): bool [H, W]."""
    mask = images[0][..., 3] > 0.99
    for image in images[1:]:
        mask = mask & (image[..., 3] > 0.99)
    return mask


def block_averages(image, mask, block):
    """RGB averages over the block x block tiles that lie wholly inside the mask: [K, 3]."""
    n, m = image.shape[0] // block, image.shape[1] // block
    rgb = image[:n * block, :m * block, :3].reshape(n, block, m, block, 3).mean(axis=(1, 3))
    full = mask[:n * block, :m * block].reshape(n, block, m, block).all(axis=(1, 3))
    return rgb[full]


def block_differences(images, reference, mask, block):
    """Per image, the worst channel's |image - reference| / the reference's largest channel, for
    each block x block tile wholly inside the mask: a list of [K] arrays."""
    import numpy as np
    expected = block_averages(reference, mask, block)
    scale = expected.max(axis=1)
    return [np.abs(block_averages(image, mask, block) - expected).max(axis=1) / scale for image in images]


def relative_rms(values, reference):
    """sqrt(mean((values - reference)^2) / mean(reference^2)) over every element."""
    import math
    import numpy as np
    return math.sqrt(float(np.mean((values - reference) ** 2)) / float(np.mean(reference ** 2)))


def block_error(ours, theirs, block, mask=None):
    """The measure every comparison with Cycles quotes: (relative RMS of the block x block RGB
    averages, the bias per channel as the ratio of their means less 1, our block averages [K, 3],
    theirs [K, 3]) over the blocks wholly inside mask (None: the pixels both cover)."""
    if mask is None:
        mask = covered(ours, theirs)
    a, b = block_averages(ours, mask, block), block_averages(theirs, mask, block)
    return relative_rms(a, b), a.mean(axis=0) / b.mean(axis=0) - 1.0, a, b


def darkest_block(ours, theirs):
    """The least ratio of our block's mean to theirs (block_error's block averages) over the blocks
    Cycles lights (above a tenth of its mean): under 1/4, a block drawn black where Cycles is lit."""
    a, b = ours.mean(axis=1), theirs.mean(axis=1)
    lit = b > 0.1 * b.mean()
    return float((a[lit] / b[lit]).min()) if lit.any() else 1.0


# The world's importance map of cycles_render: Cycles' automatic choice (4096 wide for Blender's
# HDRIs) costs about a second more per render than 2048 for the same noise on forest.exr.
FAST_IMPORTANCE_MAP = 2048


def cycles_render(scene, path, size, samples=512, seed=1, transparent=True, importance_map=FAST_IMPORTANCE_MAP):
    """Renders the scene with Cycles as a user comparing with the preview would (direct light
    only, pixel filter off, no denoising - Debian's Cycles has no OpenImageDenoise - transparent
    film unless asked for the world behind) at size x size into an EXR; returns load_exr's image.
    Two seeds give independent noise. importance_map: the world's importance map's width (None:
    Cycles' automatic choice)."""
    render = scene.render
    render.engine = 'CYCLES'
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    if hasattr(scene.cycles, "use_preview_denoising"):
        scene.cycles.use_preview_denoising = False
    scene.cycles.seed = seed
    scene.cycles.filter_width = 0.01
    scene.cycles.max_bounces = 0
    if scene.world is not None:
        scene.world.cycles.sampling_method = 'AUTOMATIC' if importance_map is None else 'MANUAL'
        if importance_map is not None:
            scene.world.cycles.sample_map_resolution = importance_map
    return render_still(scene, path, size, transparent)


def render_still(scene, path, size, transparent=True):
    """Renders the scene with its render engine at size x size (film transparent unless asked
    for the world behind) into a 32-bit EXR; returns load_exr's image."""
    render = scene.render
    render.film_transparent = transparent
    render.resolution_x = render.resolution_y = size
    render.resolution_percentage = 100
    render.image_settings.file_format = 'OPEN_EXR'
    render.image_settings.color_depth = '32'
    render.filepath = path
    bpy.ops.render.render(write_still=True)
    return load_exr(path)


def reused(path, size, reuse=True):
    """load_exr's image of a render a run before wrote to `path`, where `reuse`, the file is there
    and it is size x size; else None (render it again)."""
    if reuse and os.path.exists(path):
        image = load_exr(path)
        if image.shape[:2] == (size, size):
            return image
    return None


def cycles_pair(scene, path_stem, size, samples, block, importance_map=FAST_IMPORTANCE_MAP, reuse=False):
    """Cycles from two seeds (samples // 2 each, cycles_render): (their mean, the relative RMS noise
    of the mean's block x block averages estimated from their difference, over the blocks where
    both cover the scene). reuse: read the two renders from path_stem's files where a run before
    wrote them (a benchmark run again on the same scenes)."""
    import math
    import numpy as np

    def render(seed):
        path = "%s_cycles_%s.exr" % (path_stem, "ab"[seed - 1])
        image = reused(path, size, reuse)
        if image is None:
            image = cycles_render(scene, path, size, samples // 2, seed=seed, importance_map=importance_map)
        return image
    a, b = render(1), render(2)
    mask = covered(a, b)
    block_a, block_b = block_averages(a, mask, block), block_averages(b, mask, block)
    noise = 0.5 * math.sqrt(float(np.mean((block_a - block_b) ** 2))) / math.sqrt(
        float(np.mean((0.5 * (block_a + block_b)) ** 2)))
    return 0.5 * (a + b), noise


def imported(path, join=True):
    """Imports a mesh file (glTF, OBJ, PLY, STL) with Blender's own importer, joins its meshes into
    one object with its transforms applied and removes the empties: (object, a description).
    join=False keeps the parts as the importer made them, as a user bakes them (their transforms
    and shared meshes kept, parents cleared): (the parts, a description)."""
    import numpy as np
    before = set(bpy.data.objects)
    ext = os.path.splitext(path)[1].lower()
    if ext in (".glb", ".gltf"):
        # Debian's Blender 3.4 glTF importer uses np.bool, which NumPy 1.24+ removed
        if "bool" not in np.__dict__:
            np.bool = bool
        bpy.ops.import_scene.gltf(filepath=path)
    elif ext == ".obj":
        if hasattr(bpy.ops.wm, "obj_import"):
            bpy.ops.wm.obj_import(filepath=path)
        else:
            bpy.ops.import_scene.obj(filepath=path)
    elif ext == ".ply":
        if bpy.app.version >= (3, 6, 0):   # bpy.ops.wm answers hasattr for any name
            bpy.ops.wm.ply_import(filepath=path)
        else:
            bpy.ops.import_mesh.ply(filepath=path)
    elif ext == ".stl":
        bpy.ops.import_mesh.stl(filepath=path)
    else:
        raise ValueError("unsupported mesh file %s" % path)
    new = [obj for obj in bpy.data.objects if obj not in before]
    others = [obj.name for obj in new if obj.type != 'MESH']
    meshes = [obj for obj in new if obj.type == 'MESH']
    if not meshes:
        raise ValueError("%s has no mesh" % path)
    bpy.ops.object.select_all(action='DESELECT')
    for obj in meshes:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]
    bpy.ops.object.parent_clear(type='CLEAR_KEEP_TRANSFORM')
    if len(meshes) > 1 and join:
        bpy.ops.object.join()
    for name in others:   # empties the importer made parents
        bpy.data.objects.remove(bpy.data.objects[name])
    if not join:
        return meshes, "%s (%d parts)" % (os.path.basename(path), len(meshes))
    obj = bpy.context.view_layer.objects.active
    bpy.ops.object.transform_apply(location=True, rotation=True, scale=True)
    return obj, "%s (%d parts joined)" % (os.path.basename(path), len(meshes))


def sized_model(path, size, location):
    """A model file imported (imported()), scaled to `size` units across (scale applied) and placed
    at `location`."""
    obj, _ = imported(path)
    obj.scale = (size / max(obj.dimensions),) * 3
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    obj.location = location
    return obj


ASSIMP_MODELS = "/usr/share/assimp/models/"   # Debian's assimp-testmodels


def glossy_model_scene(hdri_name, path, material, colour, roughness, metallic):
    """A new scene under Blender's HDRI `hdri_name` with the assimp model at `path` (relative to
    ASSIMP_MODELS) 2 units across in one Principled material, seen from the front: the glossy
    benchmarks' and tests' framing. Returns (scene, model)."""
    scene = empty_scene()
    hdri_world(scene, hdri(hdri_name))
    model = sized_model(ASSIMP_MODELS + path, 2.0, (0.0, 0.0, 1.0))
    model.data.materials.clear()
    model.data.materials.append(principled_material(material, colour, roughness, metallic))
    camera(scene, location=(0.0, -5.0, 2.0), target=(0.0, 0.0, 1.0), lens=110.0)
    return scene, model
