"""Worlds the add-on cannot read directly, rendered by Cycles into an equirectangular image, so that
the environment is what Cycles sees (issue 32, item 3).

Read directly (scene/environment.py): the active World Output's Surface fed by a Background node
whose Strength is a number, and whose Color is a colour or an Environment Texture (equirectangular)
whose Vector is unlinked or a Mapping node's (a rotation only) on Generated coordinates (or none),
nothing muted. Any other world - a Sky Texture, a Mix, a gradient, a Strength or colour computed by
nodes, two Backgrounds added, a Mapping's location or scale, a Light Path node (lit then as camera
rays see it), muted nodes or links - is
`rendered`: a temporary scene with this world alone and a panoramic equirectangular camera at the
origin, turned so that the image has the Environment Texture's orientation (+X at the centre, +Z up,
-Y to the right), Cycles on the CPU at WIDTH x WIDTH/2 and SAMPLES samples (every camera ray sees
the world alone: only the pixel filter's jitter varies), written as an EXR to Blender's temporary
folder and read as an HDRI file. A world is rendered again only when its digest changes: every
node's settings, inputs and links, and the images it names.

Rendering needs the main thread outside drawing: a bake and a preview render it when they start;
the viewport's draw asks for it (`request`) and shows the world once a timer has rendered it.
"""

import contextlib
import hashlib
import math
import os

from .. import compat, redraw

WIDTH = 512       # of the rendered image (its height is half): detail to s = 16 and more
SAMPLES = 16
REQUEST_DELAY = 0.3   # seconds after the draw's last request (a slider being dragged) before rendering
# Node properties that change how the node editor shows a node, not what it computes.
_LAYOUT = {"rna_type", "name", "label", "location", "width", "width_hidden", "height", "dimensions",
           "select", "show_options", "show_preview", "show_texture", "hide", "color",
           "use_custom_color", "parent", "is_active_output", "bl_idname", "bl_label",
           "bl_description", "bl_icon", "bl_static_type", "bl_width_default", "bl_width_min",
           "bl_width_max", "bl_height_default", "bl_height_min", "bl_height_max", "type",
           "internal_links", "inputs", "outputs", "warning_propagation", "color_tag"}

_rendered = {}        # digest -> path of the rendered EXR
_failed = {}          # digest -> why its render failed
_requested = set()    # world names the draw asked for


def _linked_node(socket):
    return socket.links[0].from_node if socket is not None and socket.is_linked else None


# Sky Texture types whose light on a surface in Cycles is more than their camera-ray image (README,
# "Any other world"; test_world_render measures the others).
SCATTERING_SKIES = {"SINGLE_SCATTERING", "MULTIPLE_SCATTERING"}


def reason(world, output, background, texture, mapping):
    """Why the world must be rendered (a few words for the panel), or None when the add-on reads
    it directly; `output`, `background`, `texture`, `mapping`: the nodes environment.world_nodes
    found on the Surface path (each None when absent)."""
    if not compat.uses_nodes(world):
        return None
    if output is None:
        return "no World Output"
    tree = world.node_tree
    if any(node.type == 'LIGHT_PATH' for node in tree.nodes):
        return "a Light Path node: lit as camera rays see it"
    if any(node.mute for node in tree.nodes) or any(getattr(link, "is_muted", False) for link in tree.links):
        return "muted nodes or links"
    surface = _linked_node(output.inputs.get("Surface"))
    if surface is None:
        return None          # black, as Cycles renders it: read as a uniform colour
    if background is None:
        return "a %s node on the World Output" % surface.name
    if background.inputs["Strength"].is_linked:
        return "a Strength from nodes"
    colour = _linked_node(background.inputs["Color"])
    if colour is None:
        return None
    if texture is None:
        if getattr(colour, "sky_type", "") in SCATTERING_SKIES:
            return ("a %s node - Blender 5's scattering skies light Cycles' shading 8-20 %% more than "
                    "their image shows: shaded that much darker here" % colour.name)
        return "a %s node" % colour.name
    if texture.projection != 'EQUIRECTANGULAR':
        return "a %s projection" % texture.projection.lower().replace("_", " ")
    vector = _linked_node(texture.inputs["Vector"])
    if vector is None:
        return None
    if mapping is None:
        return "a %s node before the Environment Texture" % vector.name
    if any(socket.is_linked for socket in mapping.inputs if socket.name != "Vector"):
        return "a Mapping node driven by nodes"
    location, scale = mapping.inputs.get("Location"), mapping.inputs.get("Scale")
    if ((location is not None and any(abs(x) > 0.0 for x in location.default_value)) or
            (scale is not None and any(x != 1.0 for x in scale.default_value))):
        return "a Mapping location or scale"
    coordinates = _linked_node(mapping.inputs["Vector"])
    if coordinates is None:
        return None
    if coordinates.type == 'TEX_COORD' and mapping.inputs["Vector"].links[0].from_socket.name == "Generated":
        return None
    return "%s coordinates" % coordinates.name


def _value(value, depth=0):
    """A property's value as something repr() keeps apart: an image by name, file, colour space and
    the file's time; another ID by name (a node group by its nodes); a struct (a colour ramp, a
    curve mapping, a texture mapping) or collection by what it holds."""
    import bpy
    if isinstance(value, bpy.types.Image):
        path = bpy.path.abspath(value.filepath, library=value.library) if value.filepath else ""
        return ("image", value.name, path, value.source, value.colorspace_settings.name,
                os.path.getmtime(path) if path and os.path.isfile(path) else 0.0)
    if isinstance(value, bpy.types.NodeTree):
        return ("tree", value.name, _tree_values(value, depth + 1)) if depth < 4 else ("tree", value.name)
    if isinstance(value, bpy.types.ID):
        return ("id", value.name)
    if isinstance(value, bpy.types.bpy_struct):
        return _struct_values(value, depth + 1) if depth < 4 else None
    if isinstance(value, bpy.types.bpy_prop_collection):
        return tuple(_value(item, depth + 1) for item in value) if depth < 4 else None
    if hasattr(value, "__len__") and not isinstance(value, str):
        try:
            return tuple(value)
        except TypeError:
            return None
    return value


def _struct_values(struct, depth):
    values = []
    for prop in struct.bl_rna.properties:
        if prop.identifier not in _LAYOUT:
            try:
                values.append((prop.identifier, _value(getattr(struct, prop.identifier), depth)))
            except (AttributeError, RuntimeError, TypeError, ValueError):   # unreadable here: left out
                continue
    return values


def _tree_values(tree, depth=0):
    """Every node's settings, inputs and outputs (the values of RGB and Value nodes), and the
    links, of a node tree."""
    values = []
    for node in sorted(tree.nodes, key=lambda n: n.name):
        values.append((node.bl_idname, node.name, node.mute, _struct_values(node, depth)))
        for socket in list(node.inputs) + list(node.outputs):
            if hasattr(socket, "default_value") and not (socket.is_output is False and socket.is_linked):
                values.append((socket.identifier, socket.is_output, _value(socket.default_value, depth)))
    for link in tree.links:
        values.append((link.from_node.name, link.from_socket.identifier, link.to_node.name,
                       link.to_socket.identifier, getattr(link, "is_muted", False)))
    return values


def digest(world):
    """A digest of everything the world's rendered image depends on."""
    hasher = hashlib.blake2b(digest_size=16)
    hasher.update(repr((world.name, tuple(world.color), WIDTH, SAMPLES)).encode())
    hasher.update(repr(_tree_values(world.node_tree)).encode())
    return hasher.hexdigest()


def rendered(world):
    """(the EXR of the world as it is now or None until it is rendered, why its render failed or
    None)."""
    key = digest(world)
    path = _rendered.get(key)
    return (path if path is not None and os.path.isfile(path) else None), _failed.get(key)


def render(world):
    """Renders the world (the module's doc) unless its image is there; returns the EXR's path.
    A failure is raised, and kept for `rendered` until the world changes or it is rendered again."""
    key = digest(world)
    path = _rendered.get(key)
    if path is not None and os.path.isfile(path):
        return path
    _failed.pop(key, None)
    try:
        _rendered[key] = _render(world, key)
    except Exception as exc:
        _failed[key] = "%s: %s" % (type(exc).__name__, exc)
        raise
    return _rendered[key]


def _render(world, key):
    import bpy
    path = os.path.join(bpy.app.tempdir or bpy.utils.user_resource('CACHE'), "sd_world_%s.exr" % key)
    scene = bpy.data.scenes.new("SD World Render")
    camera_data = bpy.data.cameras.new("SD World Render")
    camera = bpy.data.objects.new("SD World Render", camera_data)
    try:
        scene.world = world
        scene.collection.objects.link(camera)
        scene.camera = camera
        camera.rotation_euler = (0.5 * math.pi, 0.0, -0.5 * math.pi)   # looks along +X, +Z up
        compat.equirectangular_camera(camera_data)
        settings = scene.render
        settings.engine = 'CYCLES'
        scene.cycles.device = 'CPU'
        scene.cycles.samples = SAMPLES
        scene.cycles.use_denoising = False
        settings.film_transparent = False
        settings.resolution_x, settings.resolution_y = WIDTH, WIDTH // 2
        settings.resolution_percentage = 100
        settings.image_settings.file_format = 'OPEN_EXR'
        settings.image_settings.color_depth = '32'
        settings.filepath = path
        settings.use_file_extension = False
        scene.frame_current = bpy.context.scene.frame_current if bpy.context.scene else 1   # animated worlds
        with _camera_sees(world), _own_render_slot():
            bpy.ops.render.render(write_still=True, scene=scene.name)
    finally:
        bpy.data.scenes.remove(scene)
        bpy.data.objects.remove(camera)
        bpy.data.cameras.remove(camera_data)
    if not os.path.isfile(path):
        raise RuntimeError("Cycles wrote no image of world '%s'" % world.name)
    return path


@contextlib.contextmanager
def _camera_sees(world):
    """The world visible to camera rays while it is rendered (a user may hide it from the camera)."""
    visibility = getattr(world, "cycles_visibility", None)
    hidden = visibility is not None and not visibility.camera
    if hidden:
        visibility.camera = True
    try:
        yield
    finally:
        if hidden:
            visibility.camera = False


RENDER_SLOT = "SD World Render"


@contextlib.contextmanager
def _own_render_slot():
    """The render written to a Render Result slot of its own, so that the user's render in the
    active slot stays (slots cannot be removed: the one slot is reused)."""
    import bpy
    result = next((image for image in bpy.data.images if image.type == 'RENDER_RESULT'), None)
    slots = result.render_slots if result is not None else None
    if slots is None:
        yield
        return
    previous = slots.active_index
    names = [slot.name for slot in slots]
    if RENDER_SLOT in names:
        slots.active_index = names.index(RENDER_SLOT)
    else:
        slots.new(name=RENDER_SLOT)
        slots.active_index = len(slots) - 1
    try:
        yield
    finally:
        slots.active_index = previous


def request(world):
    """Asks for the world's image from where rendering is not allowed (the draw): a timer renders
    it and redraws the viewports."""
    import bpy
    _requested.add(world.name)
    if bpy.app.timers.is_registered(_render_requested):   # a world still being edited: wait for it
        bpy.app.timers.unregister(_render_requested)
    bpy.app.timers.register(_render_requested, first_interval=REQUEST_DELAY)


def _render_requested():
    import bpy
    names = sorted(_requested)
    _requested.clear()
    for name in names:
        world = bpy.data.worlds.get(name)
        if world is not None:
            try:
                render(world)
            except Exception:   # kept for `rendered`: said where the world is used
                pass
    redraw.viewports()
    return None


def clear():
    """Forgets the rendered images (their files stay until Blender's temporary folder goes)."""
    import bpy
    _rendered.clear()
    _failed.clear()
    _requested.clear()
    if bpy.app.timers.is_registered(_render_requested):
        bpy.app.timers.unregister(_render_requested)
