"""Still images of the live shading: the baked objects drawn from the scene camera, offscreen.

What is drawn is what the viewport's live shading shows (drawing.draw_objects, the same shader
and data), plus the scene's other visible meshes in flat grey (the viewport shows them in
Blender's own shading), on a transparent background - or, with the World Background option, in
front of the environment (opaque), as Cycles renders without a transparent film. It waits for
the ringing window's choice (the viewport shades without one until it is made): an image made
once shows what the viewport ends with, whenever it is asked for.

Files: `.exr` holds the scene-linear radiance B (float, no exposure, like a Cycles EXR); any
other extension gets 8-bit RGBA PNG with 2^exposure applied and the sRGB transfer curve - the
Standard view transform, the one the live shading uses in the viewport.
"""

import os
import struct
import zlib

import numpy as np

from .. import compat
from ..bake import geometry
from . import drawing, gpu_context
from ..scene import environment
from ..scene.view import View

OTHER_MESH_GREY = 0.18


def _other_mesh_batches(depsgraph, view_layer, drawn):
    """(shader, batch) of the visible geometry not drawn shaded (drawn: the baked objects' names,
    whose instances are drawn shaded too), for a grey depth-tested draw."""
    from gpu_extras.batch import batch_for_shader
    shader = compat.uniform_color_shader()
    return [(shader, batch_for_shader(shader, 'TRIS', {"pos": part.vertices.astype(np.float32)},
                                      indices=part.triangles))
            for part in geometry.scene_parts(depsgraph, view_layer)
            if part.name not in drawn]


def render(scene, depsgraph, view_layer, width, height, camera=None):
    """Scene-linear RGBA float32 [height, width, 4], rows top-first, exposure NOT applied."""
    import gpu
    camera = camera or scene.camera
    if camera is None:
        raise RuntimeError("the scene has no camera")
    try:
        environment.source(scene, render=True)   # a world Cycles renders: now, not while drawing
    except environment.Unavailable:
        pass                                     # the drawing below says what is missing
    gpu_context.ensure()
    view = View.from_camera(camera, depsgraph, width, height, scene)
    objects = drawing.baked_objects(scene, view_layer)
    instances = drawing.baked_instances(scene, objects, view_layer)
    others = _other_mesh_batches(depsgraph, view_layer, {o.name_full for o in objects})

    def draw():
        drawing.draw_objects(scene, objects, view, 1.0, scene.sd_lighting.per_pixel, wait=True,
                             instances=instances, view_layer=view_layer)
        if scene.sd_lighting.world_background:
            drawing.draw_background(scene, view, 1.0)
        if others:
            with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
                from mathutils import Matrix
                gpu.matrix.load_matrix(Matrix.Identity(4))
                gpu.matrix.load_projection_matrix(Matrix(view.view_projection.tolist()))
                for shader, batch in others:
                    shader.bind()
                    shader.uniform_float("color", (OTHER_MESH_GREY,) * 3 + (1.0,))
                    batch.draw(shader)

    offscreen = gpu.types.GPUOffScreen(width, height, format='RGBA32F')
    try:
        image = drawing.draw_offscreen(offscreen, draw)
    finally:
        offscreen.free()
    return image[::-1].copy()


def srgb_encode(linear):
    """The sRGB transfer curve (IEC 61966-2-1) on [0, 1]-clamped values."""
    c = np.clip(linear, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def display_rgba8(linear_rgba, exposure):
    """8-bit RGBA under the Standard view transform: sRGB(2^exposure B), alpha kept."""
    out = np.empty(linear_rgba.shape, dtype=np.uint8)
    out[..., :3] = np.round(255.0 * srgb_encode(linear_rgba[..., :3] * 2.0 ** exposure))
    out[..., 3] = np.round(255.0 * np.clip(linear_rgba[..., 3], 0.0, 1.0))
    return out


def write_png(path, rgba8):
    """A minimal RGBA8 PNG writer (rows top-first), independent of Blender's colour management."""
    height, width, _ = rgba8.shape
    raw = b"".join(b"\x00" + rgba8[y].tobytes() for y in range(height))

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data +
                struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 6)))
        f.write(chunk(b"IEND", b""))


def read_png(path):
    """Reads back what write_png writes (8-bit RGBA, no interlace): uint8 [H, W, 4]."""
    with open(path, "rb") as f:
        data = f.read()
    pos, idat, width, height = 8, b"", 0, 0
    while pos < len(data):
        length, tag = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if tag == b"IHDR":
            width, height = struct.unpack(">II", body[:8])
        elif tag == b"IDAT":
            idat += body
        pos += 12 + length
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(height, 4 * width + 1)
    if np.any(raw[:, 0] != 0):
        raise ValueError("only unfiltered PNGs are read")
    return raw[:, 1:].reshape(height, width, 4).copy()


def write_exr(path, linear_rgba):
    """Float RGBA OpenEXR through a temporary Blender image (holds the values as given)."""
    import bpy
    height, width, _ = linear_rgba.shape
    image = bpy.data.images.new("sd_lighting preview", width, height, alpha=True, float_buffer=True)
    # Saving an image tagged 'Linear' applies the display transform on 3.4; 'Non-Color' writes the
    # values as they are.
    image.colorspace_settings.name = 'Non-Color'
    try:
        image.pixels.foreach_set(np.ascontiguousarray(linear_rgba[::-1], dtype=np.float32).ravel())
        image.filepath_raw = path
        image.file_format = 'OPEN_EXR'
        image.save()
    finally:
        bpy.data.images.remove(image)


def save(path, linear_rgba, exposure):
    """Writes the image: EXR (scene-linear) or PNG (Standard view transform)."""
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    if path.lower().endswith(".exr"):
        write_exr(path, linear_rgba)
    else:
        write_png(path, display_rgba8(linear_rgba, exposure))
