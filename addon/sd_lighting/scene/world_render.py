"""Worlds the add-on cannot read directly, rendered by Cycles into an equirectangular image, so that
the environment is what Cycles sees (issue 32, item 3).

Read directly (scene/environment.py): the active World Output's Surface fed by a Background node
whose Strength is a number, and whose Color is a colour or an Environment Texture (equirectangular)
whose Vector is unlinked or a Mapping node's on Generated coordinates (or none). Any other world - a
Sky Texture, a Mix, a gradient, a Strength or colour computed by nodes, two Backgrounds added - is
`rendered`: a temporary scene with this world alone and a panoramic equirectangular camera at the
origin, turned so that the image has the Environment Texture's orientation (+X at the centre, +Z up,
-Y to the right), Cycles on the CPU at WIDTH x WIDTH/2 and SAMPLES samples (every camera ray sees
the world alone: only the pixel filter's jitter varies), written as an EXR to Blender's temporary
folder and read as an HDRI file. A world is rendered again only when its digest changes: every
node's settings, inputs and links, and the images it names.

Rendering needs the main thread outside drawing: a bake and a preview render it when they start;
the viewport's draw asks for it (`request`) and shows the world once a timer has rendered it.
"""

import hashlib
import math
import os

from .. import compat, redraw

WIDTH = 512       # of the rendered image (its height is half): detail to s = 16 and more
SAMPLES = 16
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


def reason(world, output, background, texture, mapping):
    """Why the world must be rendered (a few words for the panel), or None when the add-on reads
    it directly; `output`, `background`, `texture`, `mapping`: the nodes environment.world_nodes
    found on the Surface path (each None when absent)."""
    if not compat.uses_nodes(world):
        return None
    if output is None:
        return "no World Output"
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
    coordinates = _linked_node(mapping.inputs["Vector"])
    if coordinates is None:
        return None
    if coordinates.type == 'TEX_COORD' and mapping.inputs["Vector"].links[0].from_socket.name == "Generated":
        return None
    return "%s coordinates" % coordinates.name


def _value(value):
    """A property's value as something repr() keeps apart: images by name and file."""
    if hasattr(value, "filepath") and hasattr(value, "name"):
        return ("image", value.name, value.filepath)
    if hasattr(value, "name"):
        return ("id", value.name)
    if hasattr(value, "__len__") and not isinstance(value, str):
        try:
            return tuple(value)
        except TypeError:
            return None
    return value


def digest(world):
    """A digest of everything the world's rendered image depends on."""
    hasher = hashlib.blake2b(digest_size=16)
    hasher.update(repr((world.name, tuple(world.color), WIDTH, SAMPLES)).encode())
    tree = world.node_tree
    for node in sorted(tree.nodes, key=lambda n: n.name):
        values = [node.bl_idname, node.name, node.mute]
        for prop in node.bl_rna.properties:
            if prop.identifier not in _LAYOUT and prop.type != 'COLLECTION':
                values.append((prop.identifier, _value(getattr(node, prop.identifier, None))))
        for socket in node.inputs:
            if not socket.is_linked and hasattr(socket, "default_value"):
                values.append((socket.identifier, _value(socket.default_value)))
        hasher.update(repr(values).encode())
    for link in tree.links:
        hasher.update(repr((link.from_node.name, link.from_socket.identifier, link.to_node.name,
                            link.to_socket.identifier, link.is_muted if hasattr(link, "is_muted") else False)).encode())
    return hasher.hexdigest()


def rendered(world):
    """(the EXR of the world as it is now or None until it is rendered, why its render failed or
    None)."""
    key = digest(world)
    path = _rendered.get(key)
    return (path if path is not None and os.path.isfile(path) else None), _failed.get(key)


def render(world):
    """Renders the world (the module's doc) unless its image is there; returns the EXR's path.
    A failure is raised, and kept for `rendered` until the world changes."""
    key = digest(world)
    path = _rendered.get(key)
    if path is not None and os.path.isfile(path):
        return path
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
        bpy.ops.render.render(write_still=True, scene=scene.name)
    finally:
        bpy.data.scenes.remove(scene)
        bpy.data.objects.remove(camera)
        bpy.data.cameras.remove(camera_data)
    if not os.path.isfile(path):
        raise RuntimeError("Cycles wrote no image of world '%s'" % world.name)
    return path


def request(world):
    """Asks for the world's image from where rendering is not allowed (the draw): a timer renders
    it and redraws the viewports."""
    import bpy
    _requested.add(world.name)
    if not bpy.app.timers.is_registered(_render_requested):
        bpy.app.timers.register(_render_requested, first_interval=0.0)


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
