"""The layout of the band-limited texture L~ (MSD's band-limited texture option): six cube faces,
each n x n texels over the face's gnomonic coordinates (u, v) in [-1, 1]^2 with a one-texel gutter
that continues the face's own projection past its edges, so that bilinear interpolation stays
second-order accurate up to the edges whatever face a direction picks; stored by bilinear cell:
cell (i, j) of a face holds its four texels' RGB in three RGBA32F texels, so that the shader's
lookup (sd_shading_lib.glsl, sd_light_at) is three fetches, a division and no trigonometry (the
equirect map's atan2 and acos, wrapping and four fetches were most of MSD (13)'s frame on the
software rasteriser: docs/msd-notes.md, "Band-limited texture"). Nothing here needs Blender; the
shader mirrors face_coordinates() and lookup().

Faces: 0, 1 the +x, -x faces with (u, v) = (y, z) / |x|; 2, 3 +y, -y with (x, z) / |y|; 4, 5 +z, -z
with (x, y) / |z|. The texture is 3 (n + 1) texels wide and 6 (n + 1) high: face f's cell (i, j),
i, j in [0, n], is texels (3 i .. 3 i + 2, f (n + 1) + j), holding texels (i, j), (i + 1, j),
(i, j + 1), (i + 1, j + 1) of the face with its gutter, where texel k is centred at
-1 + (k - 0.5) 2 / n.
"""

import numpy as np

_OTHERS = np.array([[1, 2], [0, 2], [0, 1]])   # a face's (u, v) axes by its major axis


def side(order):
    """Texels per face edge for L~ of order s (its gutter not counted): bilinear interpolation is
    then within about 5e-4 of max |L~| (docs/msd-notes.md, "Band-limited texture")."""
    return (max(256, 64 * (order + 1)) + 2) // 3


def texture_size(order):
    """(width, height) of the cell texture of order s."""
    cells = side(order) + 1
    return 3 * cells, 6 * cells


def face_coordinates(directions):
    """Directions [N, 3] (any length) -> (face int [N], (u, v) float64 [N, 2] in [-1, 1]^2): the
    face of the largest component, the first of equal ones."""
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    rows = np.arange(len(d))
    major = np.argmax(np.abs(d), axis=1)
    face = 2 * major + (d[rows, major] < 0.0)
    others = _OTHERS[major]
    uv = np.c_[d[rows, others[:, 0]], d[rows, others[:, 1]]] / np.abs(d[rows, major])[:, None]
    return face, uv


def texel_directions(n):
    """The unit directions of every face's texel centres, gutter included: [6, n + 2, n + 2, 3],
    indexed [face, j, i] (v along j)."""
    centres = -1.0 + (np.arange(n + 2) - 0.5) * 2.0 / n
    u, v = np.meshgrid(centres, centres)
    out = np.zeros((6, n + 2, n + 2, 3))
    for face in range(6):
        major = face // 2
        out[face, :, :, major] = -1.0 if face % 2 else 1.0
        out[face, :, :, _OTHERS[major][0]] = u
        out[face, :, :, _OTHERS[major][1]] = v
    return out / np.linalg.norm(out, axis=3)[..., None]


def cell_texels(faces):
    """Face images with their gutter [6, n + 2, n + 2, 3] -> the cell texture's float32
    [6 (n + 1), 3 (n + 1), 4] texels, rows bottom-first as GPU textures hold them."""
    faces = np.asarray(faces, dtype=np.float32)
    cells = faces.shape[1] - 1
    corners = np.concatenate([faces[:, :-1, :-1], faces[:, :-1, 1:], faces[:, 1:, :-1], faces[:, 1:, 1:]], axis=3)
    return corners.reshape(6 * cells, 3 * cells, 4)


def lookup(texels, directions):
    """The shader's lookup of the cell texture (cell_texels) at directions [N, 3], in float64:
    bilinear between the four texel centres around the direction's point on its face."""
    cells = texels.shape[1] // 3
    face, uv = face_coordinates(directions)
    t = (uv + 1.0) * (0.5 * (cells - 1)) + 0.5
    corner = np.clip(np.floor(t).astype(np.int64), 0, cells - 1)
    f = t - corner
    rows = face * cells + corner[:, 1]
    values = np.concatenate([texels[rows, 3 * corner[:, 0] + k] for k in range(3)], axis=1).astype(np.float64)
    t00, t10, t01, t11 = values[:, 0:3], values[:, 3:6], values[:, 6:9], values[:, 9:12]
    fx, fy = f[:, :1], f[:, 1:]
    return (t00 * (1.0 - fx) + t10 * fx) * (1.0 - fy) + (t01 * (1.0 - fx) + t11 * fx) * fy
