"""The layout of the band-limited texture L~ (MSD's band-limited texture option): six cube faces,
each n x n texels over the face's gnomonic coordinates (u, v) in [-1, 1]^2 with a one-texel gutter
that continues the face's own projection past its edges, so that bilinear interpolation stays
second-order accurate up to the edges whatever face a direction picks; stored by bilinear cell:
cell (i, j) of a face holds its four texels' RGB in two RGBA32F texels, so that the shader's
lookup (sd_shading_lib.glsl, sd_light_at) is two fetches, a division and no trigonometry (the
equirect map's atan2 and acos, wrapping and four fetches were most of MSD (13)'s frame on the
software rasteriser, and each fetch of a cell of three float texels a sixth of it: docs/msd-notes.md,
"Band-limited texture"). Nothing here needs Blender; the shader mirrors face_coordinates() and
lookup().

Faces: 0, 1 the +x, -x faces with (u, v) = (y, z) / |x|; 2, 3 +y, -y with (x, z) / |y|; 4, 5 +z, -z
with (x, y) / |z|. The texture is 2 (n + 1) texels wide and 6 (n + 1) high: face f's cell (i, j),
i, j in [0, n], is texels (2 i, 2 i + 1; f (n + 1) + j), holding texels t00 = (i, j), t10 = (i + 1, j),
t01 = (i, j + 1), t11 = (i + 1, j + 1) of the face with its gutter, where texel k is centred at
-1 + (k - 0.5) 2 / n.

Twelve values in eight floats: each value is a 16-bit code q = round(v / scale) + 32768, scale =
max |L~| / 32767 for the whole map (rounding costs 2^-16 of max |L~|, a thirtieth of the
interpolation's error bound), and each float an integer below 2^24 - exact in float32, no NaN or
denormal for a driver to alter; Blender uploads float data only - carrying 24 bits of the codes.
Along each row of the cell (p = 0: v = j, p = 1: v = j + 1) the six codes A B C = (r_0p, r_1p,
g_0p) and (g_1p, b_0p, b_1p) (r_xp: red at u = i + x) go into two floats of texel 2 i and of
texel 2 i + 1 respectively: A | (B & 255) << 16 and B >> 8 | C << 8; texel = (row 0's two floats,
row 1's two).
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
    return 2 * cells, 6 * cells


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
    """Face images with their gutter [6, n + 2, n + 2, 3] -> (the cell texture's float32
    [6 (n + 1), 2 (n + 1), 4] texels, rows bottom-first as GPU textures hold them; its scale)."""
    faces = np.asarray(faces, dtype=np.float64)
    cells = faces.shape[1] - 1
    largest = np.abs(faces).max()
    scale = largest / 32767.0 if largest > 0.0 else 1.0
    codes = (np.clip(np.rint(faces / scale), -32767, 32767) + 32768).astype(np.int64)
    # [6, cells (j), cells (i), row p, 6 codes: (x, channel) as r0 r1 g0 g1 b0 b1]
    rows = np.stack([np.stack([codes[:, p:cells + p, x:cells + x] for x in (0, 1)], axis=-1)
                     for p in (0, 1)], axis=3).reshape(6, cells, cells, 2, 6)
    a, b, c = rows[..., 0::3], rows[..., 1::3], rows[..., 2::3]          # [..., row, texel]
    low, high = a | (b & 255) << 16, b >> 8 | c << 8
    texels = np.stack([low, high], axis=-1)                               # [..., row, texel, 2]
    texels = texels.transpose(0, 1, 2, 4, 3, 5).reshape(6, cells, cells, 2, 4)   # [..., texel, row * 2]
    return texels.reshape(6 * cells, 2 * cells, 4).astype(np.float32), scale


def cell_values(texels, scale):
    """A cell's two texels [..., 2, 4] (cell_texels) -> its four corners' RGB [..., 4, 3] in float64,
    t00, t10, t01, t11: what the shader decodes."""
    words = np.asarray(texels, dtype=np.float64).astype(np.int64)
    low, high = words[..., 0::2], words[..., 1::2]                        # [..., texel, row]
    a, b, c = low & 0xFFFF, low >> 16 | (high & 255) << 8, high >> 8
    # per texel and row the codes (A, B, C): texel 0 r0 r1 g0, texel 1 g1 b0 b1
    codes = np.stack([a, b, c], axis=-1)                                  # [..., texel, row, 3]
    codes = codes.swapaxes(-3, -2).reshape(codes.shape[:-3] + (2, 6))      # [..., row, r0 r1 g0 g1 b0 b1]
    values = (codes.reshape(codes.shape[:-1] + (3, 2)) - 32768.0) * scale  # [..., row, channel, x]
    return values.swapaxes(-2, -1).reshape(values.shape[:-3] + (4, 3))     # (row, x) -> 00, 10, 01, 11


def lookup(texels, scale, directions):
    """The shader's lookup of the cell texture (cell_texels) at directions [N, 3], in float64:
    bilinear between the four texel centres around the direction's point on its face."""
    cells = texels.shape[1] // 2
    face, uv = face_coordinates(directions)
    t = (uv + 1.0) * (0.5 * (cells - 1)) + 0.5
    corner = np.clip(np.floor(t).astype(np.int64), 0, cells - 1)
    f = t - corner
    rows = face * cells + corner[:, 1]
    values = cell_values(np.stack([texels[rows, 2 * corner[:, 0] + k] for k in range(2)], axis=1), scale)
    t00, t10, t01, t11 = values[:, 0], values[:, 1], values[:, 2], values[:, 3]
    fx, fy = f[:, :1], f[:, 1:]
    return (t00 * (1.0 - fx) + t10 * fx) * (1.0 - fy) + (t01 * (1.0 - fx) + t11 * fx) * fy
