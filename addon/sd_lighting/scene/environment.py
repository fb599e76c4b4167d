"""The environment L that lights the scene, and its rotation g (eq. 1).

Source (the scene's settings, `environment_source`):
- 'WORLD' (default): the image of the Environment Texture node feeding the active World
  Output through a Background node, times the Background's Strength; a Background of a plain
  colour (an Environment Texture elsewhere in the tree does not light) or a world without nodes
  lights with its uniform colour. Any other world - a Sky Texture, mixes, a Strength from nodes -
  is rendered by Cycles into an equirectangular image and read as an HDRI (world_render.py).
- 'FILE': an image file (EXR/HDR), in Blender's equirectangular orientation.
What is missing or cannot be read - the world, the texture's image, its file - raises
Unavailable, whose message names it (the bake refuses, the panel and the live shading show it).

Rotation g: the world's Mapping node feeding the Environment Texture's Vector input turns the
environment (scene/transforms.mapping_rotation; location and scale are ignored). Without a Mapping
node (or for 'FILE', or a rendered world, whose image has its Mapping in it), g is the settings'
own `environment_rotation`. The panel's rotation slider
writes the Mapping node when there is one.

SH coefficients are cached per (source, order): loading and projecting an HDRI takes a moment, the
draw handler asks for them every frame. Every method shades with L windowed against ringing
(windowed_light; scene/ringing.py): the window of the scene's `ringing_window` setting for the
bake's lobe and order, chosen once per (source, lobe, exponent, order, setting) in a worker thread
(`window_choices`) and cached; the draw does not wait for it (no window until it is there).
"""

import os
import threading

import numpy as np

from .. import background, compat, native
from . import light_sources, ringing, transforms, world_render

_cache = {}          # source key -> sdnative.Environment
_sh_cache = {}       # (source key or (key, "remainder"), order) -> float64 [(order+1)^2, 3]
_workers = {}        # name -> the session's background.Background of that work, made on first use
RINGING_WINDOWS = "sd_lighting ringing windows"
PREFILTERED_ATLASES = "sd_lighting prefiltered environments"
LIGHT_SOURCES = "sd_lighting light sources"


def clear_cache():
    _cache.clear()
    _sh_cache.clear()
    world_render.clear()
    for work in _workers.values():
        work.close()
    _workers.clear()


def _worker(name):
    """The session's Background of the work `name` (made on first use)."""
    if name not in _workers:
        _workers[name] = background.Background(name)
    return _workers[name]


# --------------------------------------------------------------------------------------------
# World nodes

def _active_output(tree):
    outputs = [n for n in tree.nodes if n.type == 'OUTPUT_WORLD']
    for node in outputs:
        if getattr(node, "is_active_output", False):
            return node
    return outputs[0] if outputs else None


def _linked_node(socket):
    if socket is None or not socket.is_linked:
        return None
    return socket.links[0].from_node


def _surface_nodes(world):
    """(active World Output, Background, Environment Texture, Mapping) on the Surface path
    Output <- Background.Color <- Environment Texture.Vector <- Mapping, each None when absent."""
    if not compat.uses_nodes(world):
        return None, None, None, None
    output = _active_output(world.node_tree)
    background = _linked_node(output.inputs.get("Surface")) if output is not None else None
    if background is not None and background.type != 'BACKGROUND':
        background = None
    texture = _linked_node(background.inputs.get("Color")) if background is not None else None
    if texture is not None and texture.type != 'TEX_ENVIRONMENT':
        texture = None
    mapping = _linked_node(texture.inputs.get("Vector")) if texture is not None else None
    if mapping is not None and mapping.type != 'MAPPING':
        mapping = None
    return output, background, texture, mapping


def world_nodes(world):
    """(environment texture node, background node, mapping node) on the active World Output's
    Surface path, each None when absent; an Environment Texture elsewhere in the tree does not
    light the scene."""
    _, background, texture, mapping = _surface_nodes(world)
    return texture, background, mapping


def render_reason(world):
    """Why the world is rendered by Cycles to be read (scene/world_render.py), or None."""
    return world_render.reason(world, *_surface_nodes(world))


def mapping_node(scene):
    """The Mapping node that turns the world's environment, or None (also for a rendered world,
    whose image has the Mapping's rotation in it)."""
    settings = scene.sd_lighting
    if settings.environment_source != 'WORLD' or scene.world is None or render_reason(scene.world):
        return None
    return world_nodes(scene.world)[2]


def rotation_matrix(scene):
    """g as a float64 [3, 3] numpy array (eq. 1: the scene is lit by L(g x))."""
    mapping = mapping_node(scene)
    if mapping is not None:
        return transforms.mapping_rotation(mapping.inputs["Rotation"].default_value,
                                          mapping.vector_type)
    return transforms.euler_xyz(scene.sd_lighting.environment_rotation)


# --------------------------------------------------------------------------------------------
# Loading

class Source:
    """Where L comes from: a file, an image's pixels, or a uniform colour."""

    def __init__(self, kind, key, description, strength=1.0, path=None, image=None, colour=None):
        self.kind = kind              # "file", "pixels" or "uniform"
        self.key = key                # cache key
        self.description = description
        self.strength = strength
        self.path = path
        self.image = image
        self.colour = colour


def _file_key(path):
    try:
        st = os.stat(path)
        return ("file", path, st.st_mtime_ns, st.st_size)
    except OSError:
        return ("file", path, 0, 0)


class Unavailable(Exception):
    """The scene's environment cannot be read; the message names what is missing."""


def _rendered_source(world, why, render):
    """The Source of a world Cycles renders (world_render.py): render=True renders it now if it
    is not there; otherwise a timer is asked to and Unavailable raised meanwhile."""
    path, failure = world_render.rendered(world)
    if path is None and render:   # a bake or a preview tries again what failed before
        try:
            path = world_render.render(world)
        except Exception:
            path, failure = world_render.rendered(world)
    if failure is not None:
        raise Unavailable("world '%s' (%s) could not be rendered by Cycles: %s" % (world.name, why, failure))
    if path is None:
        world_render.request(world)
        raise Unavailable("world '%s' (%s) is being rendered by Cycles" % (world.name, why))
    return Source("file", _file_key(path), "world '%s' rendered by Cycles (%s)" % (world.name, why),
                  path=path)


def source(scene, render=False):
    """The environment Source of the scene's settings. Raises Unavailable when what they name is
    missing: no world, an Environment Texture without an image, an image without its file; and
    for a world Cycles renders (world_render.py), until it is rendered - now with render=True
    (main thread, not while drawing), else by a timer it asks for."""
    import bpy
    settings = scene.sd_lighting
    if settings.environment_source == 'FILE':
        if not settings.environment_path:
            raise Unavailable("no HDRI file chosen (Environment: File)")
        path = bpy.path.abspath(settings.environment_path)
        if not os.path.isfile(path):
            raise Unavailable("the HDRI file %s is missing" % path)
        return Source("file", _file_key(path), path, path=path)
    if scene.world is None:
        raise Unavailable("the scene has no world: add one (Properties > World) or choose an "
                          "HDRI file (Environment: File)")
    why = render_reason(scene.world)
    if why:
        return _rendered_source(scene.world, why, render)
    env, background, _ = world_nodes(scene.world)
    strength = 1.0
    if background is not None:
        socket = background.inputs.get("Strength")
        if socket is not None and not socket.is_linked:
            strength = float(socket.default_value)
    if env is not None:
        image = env.image
        if image is None:
            raise Unavailable("the Environment Texture of world '%s' has no image" % scene.world.name)
        path = bpy.path.abspath(image.filepath, library=image.library) if image.filepath else ""
        if image.source == 'FILE' and image.packed_file is None:
            if path and os.path.isfile(path):
                return Source("file", _file_key(path), path, strength=strength, path=path)
            raise Unavailable("the image '%s' of world '%s' is missing: %s" % (
                image.name, scene.world.name, "file %s not found" % path if path else "no file path"))
        if 0 in tuple(image.size):  # reading the size loads the pixels
            raise Unavailable("the image '%s' of world '%s' has no pixels" % (image.name, scene.world.name))
        return Source("pixels", ("pixels", image.name, tuple(image.size)), "image " + image.name,
                      strength=strength, image=image)
    colour = (0.0, 0.0, 0.0)      # nothing on the World Output's Surface: black, as Cycles has it
    if not compat.uses_nodes(scene.world):
        colour = tuple(scene.world.color)
    elif background is not None:
        socket = background.inputs.get("Color")
        if socket is not None and not socket.is_linked:
            colour = tuple(socket.default_value)[:3]
    return Source("uniform", ("uniform",) + tuple(round(c, 9) for c in colour),
                  "uniform colour (%.3g, %.3g, %.3g)" % colour, strength=strength, colour=colour)


def _image_pixels(image):
    """The image's RGB as float32 [H, W, 3], rows top-first, scene-linear."""
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(height, width, 4)[::-1, :, :3].copy()
    if not image.is_float and image.colorspace_settings.name.lower().startswith("srgb"):
        rgb = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4).astype(np.float32)
    return rgb


def _file_pixels(path):
    """The RGB of an image file as _image_pixels gives it, read by Blender: the add-on's sdnative
    reads no files, so that it links no image library (issue 31). Raises OSError, also off the
    main thread (a worker finding the cache emptied by a file load): bpy is the main thread's."""
    import bpy
    if threading.current_thread() is not threading.main_thread():
        raise OSError("%s is read on Blender's main thread only: bake again" % path)
    try:
        image = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as exc:
        raise OSError("Blender cannot read %s: %s" % (path, exc)) from exc
    try:
        if 0 in tuple(image.size):   # reading the size loads the pixels
            raise OSError("Blender cannot read %s: it finds no pixels in it" % path)
        return _image_pixels(image)
    finally:
        bpy.data.images.remove(image)


def environment(src):
    """The sdnative.Environment of a file or pixel Source (cached)."""
    env = _cache.get(src.key)
    if env is None:
        sd = native.get()
        try:
            rgb = _file_pixels(src.path) if src.kind == "file" else _image_pixels(src.image)
            env = sd.environment_from_pixels(rgb)
        except (OSError, ValueError) as exc:
            raise Unavailable("cannot read the environment (%s): %s" % (src.description, exc)) from exc
        _cache[src.key] = env
    return env


def load_file(path):
    """The sdnative.Environment of an image file (cached; for scripts). Raises Unavailable."""
    return environment(Source("file", _file_key(path), path, path=path))


BACKGROUND_MAX_WIDTH = 2048   # the world background's texture: finer maps are sampled down


def background_texels(src):
    """The environment as the world background draws it: L times the strength at the texel
    centres of an equirect map (scene/transforms.equirect_directions: Blender's orientation, rows
    bottom-first), nearest texel of the source, at most BACKGROUND_MAX_WIDTH wide (a cube map: 2 x
    its face size); a uniform colour as 2 x 1. float32 [H, W, 3]."""
    if src.kind == "uniform":
        return np.broadcast_to(np.asarray(src.colour, dtype=np.float32) * src.strength, (1, 2, 3)).copy()
    env = environment(src)
    width = int(min(BACKGROUND_MAX_WIDTH, max(2 * env.height, 2)))
    directions = transforms.equirect_directions(width, width // 2)
    radiance = np.asarray(env.radiance(directions.reshape(-1, 3)), dtype=np.float32)
    return (radiance * src.strength).reshape(width // 2, width, 3)


def prefiltered_atlases():
    """The session's prefiltered atlases (prefiltered_atlas: made in a worker thread)."""
    return _worker(PREFILTERED_ATLASES)


def prefilter_status():
    """Lines for the panel: the environments being prefiltered or whose prefilter failed."""
    work = _workers.get(PREFILTERED_ATLASES)
    if work is None:
        return []
    return (["Prefiltering the environment for glossy light (the truncated lobe meanwhile)"] * bool(work.pending())
            + ["Prefiltering the environment failed: %s" % why for why in work.failures().values()])


def prefiltered_atlas(src, width0, levels, wait, remainder=False):
    """The environment prefiltered by the GGX lobe per roughness level, without the strength (the
    shader applies it: a changed strength needs no new prefilter), in the atlas layout of
    sdnative's Environment.prefiltered_ggx (rows bottom-first); a uniform colour is that colour at
    every roughness. float32 [rows, width0, 3] (sdnative.prefilter_atlas_shape). remainder: of the
    map without the bright sources whose highlights the shader adds on their own
    (light_sources.without_highlights; source_split must be there). Computed in a worker thread
    (seconds: README, *Prefiltered Glossy*) and cached: wait=False (the interactive draw) gives None
    until it is there or when it failed; wait=True waits (raises background.Failed)."""
    sd = native.get()
    if src.kind == "uniform":
        shape = sd.prefilter_atlas_shape(width0, levels)
        return np.broadcast_to(np.asarray(src.colour, dtype=np.float32), (*shape, 3)).copy()
    env = environment(src)   # read here: the pixels come from bpy
    remainder = remainder and has_highlights(src, wait)
    if remainder is None:
        return None
    split = source_split(src, wait) if remainder else None

    def compute():
        shown = env if split is None else sd.environment_from_pixels(light_sources.without_highlights(
            env.pixels(), split["remainder"].pixels(), split["sources"]))
        return np.asarray(shown.prefiltered_ggx(width0, levels), dtype=np.float32)

    key = (src.key, remainder, width0, levels)
    work = prefiltered_atlases()
    return work.result(key, compute) if wait else work.get(key, compute)


def bright_source_searches():
    """The session's bright-source searches (bright_sources: made in a worker thread)."""
    return _worker(LIGHT_SOURCES)


def source_split(src, wait):
    """The map's bright compact sources split off (Environment.light_sources at
    light_sources.SPLIT_ORDER) with the highlights' points (with_highlight_points), found in a
    worker thread (about 0.25 s for 1024 x 512) and cached:
    {"sources": [light_sources.Source], "remainder": the Environment without them, "found":
    light_sources.found's list}. wait=False (the panel, the interactive draw) gives None until it is
    there; a failed search raises background.Failed (wait=True too). A uniform colour has no
    sources (and no remainder: None)."""
    if src.kind == "uniform":
        return {"sources": [], "remainder": None, "found": []}
    env = environment(src)

    def compute():
        split = env.light_sources(light_sources.SPLIT_ORDER)
        sources = [light_sources.Source.from_split(s) for s in split["sources"]]
        return {"sources": light_sources.with_highlight_points(sources, env.pixels(), split["remainder"].pixels()),
                "remainder": split["remainder"],
                "found": light_sources.found(split, float(env.mass[3]))}

    work = bright_source_searches()
    if wait:
        return work.result(src.key, compute)
    split = work.get(src.key, compute)
    failed = work.failures().get(src.key)
    if failed is not None:
        raise background.Failed("finding the map's bright sources failed: %s" % failed)
    return split


def has_highlights(src, wait):
    """Whether the prefiltered atlas of the map's remainder (prefiltered_atlas) differs from the
    whole map's: some source is a highlight the shader adds on its own (light_sources.Source.highlight).
    None while the split is found (wait=False)."""
    split = source_split(src, wait)
    return None if split is None else any(source.highlight for source in split["sources"])


def bright_sources(src, wait):
    """The map's bright compact sources as scene/light_sources.found lists them (source_split;
    None while they are found)."""
    split = source_split(src, wait)
    return None if split is None else split["found"]


def _shaded_environment(src, remainder):
    """(key, Environment) of the map, or with remainder=True of what source_split leaves of it
    (the split must be there)."""
    if remainder:
        return (src.key, "remainder"), source_split(src, wait=True)["remainder"]
    return src.key, environment(src)


def light_coefficients(src, order, remainder=False):
    """Unrotated SH coefficients of L of order s, float64 [(s+1)^2, 3], strength applied;
    remainder: of the map without its bright sources (source_split, which must be there)."""
    if src.kind == "uniform":
        light = np.zeros(((order + 1) ** 2, 3))
        light[0] = np.asarray(src.colour, dtype=np.float64)
    else:
        key, env = _shaded_environment(src, remainder)
        light = _sh_cache.get((key, order))
        if light is None:
            light = np.asarray(env.sh(order), dtype=np.float64).reshape(-1, 3)
            _sh_cache[(key, order)] = light
    return light * src.strength


def smallest_order(src, lobe, exponent, target_error, max_order):
    """Automatic s: the smallest order whose lobe-filtered relative error is within the target
    (max_order when none up to it is)."""
    if src.kind == "uniform":
        return 0
    order = environment(src).smallest_order(lobe, float(exponent), float(target_error), int(max_order))
    return int(max_order) if order is None else int(order)


def window_choices():
    """The session's ringing window choices (scene/ringing.choice: made in a worker thread)."""
    return _worker(RINGING_WINDOWS)


def ringing_window_status():
    """Lines for the panel: the ringing windows being chosen or whose choice failed."""
    return ringing.status(_workers[RINGING_WINDOWS]) if RINGING_WINDOWS in _workers else []


def ringing_window(src, lobe, exponent, order, setting, wait, remainder=False):
    """The window against ringing of L for the lobe and order s: sdnative's
    Environment.ringing_window dict (setting: one of scene/ringing.WINDOWS), chosen in a worker
    thread and cached. wait=False (the interactive draw, the panel): None until it is there or when
    its choice failed; wait=True: waits for it (raises background.Failed when it failed). The choice
    does not depend on the strength. A uniform environment (L_00 alone, which no window changes):
    none. remainder: the window of the map without its bright sources (light_coefficients)."""
    if src.kind == "uniform":
        return ringing.unwindowed(order)
    key, env = _shaded_environment(src, remainder)
    return ringing.choice(window_choices(), key, env, lobe, exponent, order, setting, wait)


def windowed_light(src, lobe, exponent, order, setting, wait, remainder=False):
    """light_coefficients with the ringing window's sigma_l on band l: the L every method shades
    with and the band-limited texture holds; without a window while its choice is not there
    (wait=False, ringing_window). remainder: as light_coefficients."""
    light = light_coefficients(src, order, remainder)
    choice = ringing_window(src, lobe, exponent, order, setting, wait, remainder)
    return light if choice is None else ringing.windowed(light, choice["factors"])
