"""Texture-space data (issue 8, item 3b): the bake's quantities at the texel centres of a lightmap
over the baked copy, read per pixel by the live shading - where the vertices are too sparse for
the light (a shadow across a large face), the texels carry it without more vertices.

The lightmap UVs are Blender's Smart UV Project of the baked copy (unwrap.lightmap_uvs), charts
at least MARGIN_TEXELS texels apart. Texel (x, y) of a W x H lightmap is entry y W + x, its centre
at UV ((x + 1/2) / W, (y + 1/2) / H): `texels` finds the texel centres inside each UV triangle
(a triangle too small to hold one gives its centroid to the texel under it, if no other triangle
has that texel) and their points on the surface (`sample_points`); those are baked as points
without faces (their rays start along their normal, traced_scene.h) against the copy's own
triangles and the other objects. `dilation_sources` then gives each texel within DILATION texels
of a chart the value of its nearest baked texel, so that bilinear lookups at a chart's border
never blend in empty texels. Only those texels are stored (`spread`: baked and dilated, by
entry), each with its entry; the shader finds a texel's row through an index map of the whole
lightmap (its row, -1 for a texel not stored), blends the four texels around a pixel's
lightmap UV (shaders/sd_shading_frag.glsl), evaluating B at each with the pixel's normal and
view, and divides by the weight of those stored (all four wherever a chart is).

Which methods: those whose data are linear in the rays and the same size at every point
(least_squares.FITTED: AO, V~, T, M); MSD (13)'s per-point designs cost milliseconds each.

Nothing here needs Blender.
"""

import numpy as np

from . import least_squares
from ..store.bake_data import TEXTURE_WIDTH

SIZES = (256, 512, 1024, 2048, 4096)   # the panel's lightmap sizes (square)
DEFAULT_SIZE = 1024
MARGIN_TEXELS = 4        # between charts: bilinear taps and dilation stay in their own chart
DILATION = 3             # texels around a chart that get its nearest baked value
ANGLE_LIMIT_DEGREES = 66.0   # Smart UV Project's default: a chart ends at a sharper fold
_CHUNK = 1 << 22         # candidate texels rasterized at once (memory bound)
COVERAGE = 0.4           # texels a map's charts cover, of its size^2, for the time prediction
                         # (baked by benchmark_refine at 1024 / 2048: engine 0.36 / 0.44, house
                         # 0.42 / 0.48, Wuson 0.24 / 0.36)
UNWRAP_TRIES = 3         # unwraps until the charts' scale leaves the margin (unwrap.lightmap_uvs)
MARGIN_SLACK = 1.1       # the margin asked for, over what the expected scale needs
GPU_TEXTURE_ROWS = 16384   # the data texture's rows a GPU is counted on for (OpenGL 4.1's minimum)
MAX_DATA_TEXELS = TEXTURE_WIDTH * GPU_TEXTURE_ROWS


def data_entries(method, light_order, visibility_order, stored):
    """The data texels (RGBA) `stored` lightmap texels of the method's data take in the shader's
    data texture: each its array's vec4 groups."""
    array = method.data
    floats = int(np.prod(array.shape(light_order, visibility_order))) if array.shape else 1
    return stored * ((floats + 3) // 4)


def applies(method):
    """Whether texels can hold a method's data (methods.Method): the arrays linear in the
    rays and of one size at every point, as least squares fits them."""
    return least_squares.applies(method)


def expected_scale(area):
    """The scale (UV units per surface unit) a surface of this area is expected to get in a map
    whose charts cover COVERAGE of it."""
    return np.sqrt(COVERAGE / area) if area > 0.0 else 1.0


def add_margin(size, scale):
    """The 'ADD' margin, in the unwrapped surface's units, that leaves MARGIN_TEXELS texels of a
    size x size map between charts at this scale, with MARGIN_SLACK (the scale shrinks a little as
    the margins grow). Blender pads each chart's box by the margin on every side before scaling
    the packing into the map (uv_pack.cc), so two charts are two margins apart."""
    return MARGIN_SLACK * MARGIN_TEXELS / (2.0 * size * scale)


def gap_texels(margin, scale, size):
    """The texels of a size x size map between charts unwrapped with an 'ADD' margin that got
    this scale (at least: uv_scale is at most the packing's scale)."""
    return 2.0 * margin * scale * size


def uv_scale(corner_uvs, area):
    """The scale the charts got: sqrt(UV area / surface area), from each triangle corner's UV
    [T, 3, 2] and the surface's area."""
    uv = np.asarray(corner_uvs, dtype=np.float64)
    d, e = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    uv_area = 0.5 * np.abs(d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]).sum()
    return float(np.sqrt(uv_area / area)) if area > 0.0 else 0.0


def expected_texels(size):
    """The texels a size x size map is expected to bake (before its unwrap): COVERAGE of them."""
    return int(COVERAGE * size * size)


def texels(corner_uvs, width, height):
    """The texel centres inside the UV triangles: (texel entry y W + x, int64 [S]; triangle,
    int64 [S]; barycentric coordinates there, float64 [S, 3]), sorted by entry, each entry
    once (a centre on an edge two triangles share goes to the first). corner_uvs: float [T, 3, 2],
    each triangle corner's UV in [0, 1]."""
    uv = np.asarray(corner_uvs, dtype=np.float64).reshape(-1, 3, 2) * np.array([width, height], dtype=np.float64)
    count = len(uv)
    low = np.clip(np.ceil(uv.min(axis=1) - 0.5), 0, [width - 1, height - 1]).astype(np.int64)
    high = np.clip(np.floor(uv.max(axis=1) - 0.5), -1, [width - 1, height - 1]).astype(np.int64)
    spans = np.maximum(high - low + 1, 0)
    # The texels of each triangle's bounding box are its candidates, numbered one after the other
    # over all triangles, and tested _CHUNK at a time (a triangle's may span chunks).
    ends = np.cumsum(spans[:, 0] * spans[:, 1])
    found_entries, found_triangles, found_barycentric = [], [], []
    for first in range(0, int(ends[-1]) if count else 0, _CHUNK):
        candidate = np.arange(first, min(first + _CHUNK, int(ends[-1])))
        triangle = np.searchsorted(ends, candidate, side="right")
        within = candidate - (ends[triangle] - spans[triangle, 0] * spans[triangle, 1])
        x = low[triangle, 0] + within % spans[triangle, 0]
        y = low[triangle, 1] + within // spans[triangle, 0]
        barycentric, inside = _barycentric(uv[triangle], np.stack([x + 0.5, y + 0.5], axis=1))
        found_entries.append((y * width + x)[inside])
        found_triangles.append(triangle[inside])
        found_barycentric.append(barycentric[inside])
    entries = np.concatenate(found_entries) if found_entries else np.zeros(0, np.int64)
    triangles = np.concatenate(found_triangles) if found_triangles else np.zeros(0, np.int64)
    barycentric = np.concatenate(found_barycentric) if found_barycentric else np.zeros((0, 3))
    # Triangles without a texel centre (smaller than a texel): their centroid, in the texel under it.
    empty = np.setdiff1d(np.arange(count), triangles)
    if len(empty):
        centre = uv[empty].mean(axis=1)
        x = np.clip(np.floor(centre[:, 0]), 0, width - 1).astype(np.int64)
        y = np.clip(np.floor(centre[:, 1]), 0, height - 1).astype(np.int64)
        entries = np.concatenate([entries, y * width + x])
        triangles = np.concatenate([triangles, empty])
        barycentric = np.concatenate([barycentric, np.full((len(empty), 3), 1.0 / 3.0)])
    entries, first = np.unique(entries, return_index=True)
    return entries, triangles[first], barycentric[first]


def _barycentric(corners, points):
    """Barycentric coordinates of points [N, 2] in triangles [N, 3, 2], and whether each is
    inside (a degenerate triangle contains nothing)."""
    d = corners[:, 1] - corners[:, 0]
    e = corners[:, 2] - corners[:, 0]
    q = points - corners[:, 0]
    area = d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]
    safe = np.where(area != 0.0, area, 1.0)
    b1 = (q[:, 0] * e[:, 1] - q[:, 1] * e[:, 0]) / safe
    b2 = (d[:, 0] * q[:, 1] - d[:, 1] * q[:, 0]) / safe
    b0 = 1.0 - b1 - b2
    tolerance = -1e-12
    inside = (area != 0.0) & (b0 >= tolerance) & (b1 >= tolerance) & (b2 >= tolerance)
    return np.stack([b0, b1, b2], axis=1), inside


def blend(values, triangles, triangle, barycentric):
    """Per texel sample, the barycentric blend of per-vertex `values` [V, k] over the corners of
    its triangle: [S, k] float64."""
    corners = np.asarray(triangles, np.int64)[triangle]
    return (np.asarray(values, np.float64)[corners] * np.asarray(barycentric, np.float64)[:, :, None]).sum(axis=1)


def sample_points(vertices, normals, triangles, triangle, barycentric):
    """(points [S, 3], unit normals [S, 3]) of texel samples on a mesh: the barycentric blend of
    their triangle's corners; where the corners' normals cancel, the triangle's own normal (by
    its winding)."""
    vertices = np.asarray(vertices, np.float64)
    points = blend(vertices, triangles, triangle, barycentric)
    blended = blend(normals, triangles, triangle, barycentric)
    corners = np.asarray(triangles, np.int64)[triangle]
    a, c, d = (vertices[corners[:, k]] for k in range(3))
    faces = np.cross(c - a, d - a)
    length = np.linalg.norm(blended, axis=1)
    usable = length > 1e-6
    out = np.where(usable[:, None], blended / np.where(usable, length, 1.0)[:, None], faces)
    length = np.linalg.norm(out, axis=1)
    return points, np.divide(out, length[:, None], out=np.zeros_like(out), where=length[:, None] > 0.0)


def dilation_sources(entries, width, height, radius=DILATION):
    """For every texel of the W x H lightmap (int64 [W H], by entry): the baked texel whose value
    it holds - itself when baked (`entries`), else the nearest baked one within `radius` texels
    (steps to the 8 neighbours, the 4 edge neighbours first), else -1."""
    source = np.full((height, width), -1, dtype=np.int64)
    entries = np.asarray(entries, dtype=np.int64)
    source.reshape(-1)[entries] = entries
    steps = ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1))
    for _ in range(int(radius)):
        grown = source.copy()
        for dy, dx in steps:
            neighbour = np.full_like(source, -1)
            neighbour[max(dy, 0):height + min(dy, 0), max(dx, 0):width + min(dx, 0)] = \
                source[max(-dy, 0):height + min(-dy, 0), max(-dx, 0):width + min(-dx, 0)]
            fill = (grown < 0) & (neighbour >= 0)
            grown[fill] = neighbour[fill]
        if np.array_equal(grown, source):
            break
        source = grown
    return source.reshape(-1)


def stored(sources):
    """The entries of the texels stored: those dilation_sources reached, in entry order."""
    return np.flatnonzero(np.asarray(sources) >= 0)


def spread(values, entries, sources):
    """The baked texels' values [S, ...] (in `entries` order) given to the stored texels by
    dilation_sources: [len(stored(sources)), ...], in entry order."""
    values = np.asarray(values)
    row = np.full(int(np.max(entries)) + 1 if len(entries) else 0, -1, dtype=np.int64)
    row[entries] = np.arange(len(entries))
    return values[row[np.asarray(sources)[stored(sources)]]]


def index_map(stored_entries, width, height):
    """The shader's index map: float32 [H, W] holding each stored texel's row (exact in float32
    below 2^24 texels: a 4096 x 4096 map at most) and -1 elsewhere."""
    out = np.full(width * height, -1.0, dtype=np.float32)
    out[np.asarray(stored_entries, dtype=np.int64)] = np.arange(len(stored_entries), dtype=np.float32)
    return out.reshape(height, width)
