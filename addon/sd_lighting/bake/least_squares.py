"""Least-squares vertex values (issue 8, item 2): the baked per-vertex arrays fitted so that their
linear interpolation over each triangle best matches samples spread over it, after Kavan, Bargteil
and Sloan, "Least Squares Vertex Baking" (EGSR 2011); the solve is sdnative.fit_vertex_values
(a sparse Cholesky factorization, native/include/sdlighting/vertex_fit.h).

The samples: every vertex, and the centroid of every triangle, baked together as one mesh in
which each triangle is split at its centroid (`centroid_split`: the same surface, so each point's
rays start off its own faces as a vertex's do). Their weights are the quadrature rule that is exact
for quadratics over a triangle of area a - a/12 at each corner, 3a/4 at the centroid - so the fit
minimizes the interpolation's squared error integrated over the surface as far as a quadratic
signal goes. A light regulariser (SMOOTHNESS, relative to the samples' weight) against banding
penalizes the jump of the interpolant's gradient across each edge two triangles share
(`gradient_jumps`): zero for a linear signal, which the fit therefore keeps exactly, and absent
across hard edges and seams, whose sides are different vertices. The bake traces rays from V + T
points instead of V (about 3x the rays on a closed mesh).

Which arrays: the linear ones (ambient occlusion, V~, T, M - `FITTED`), so every method but MSD
(13), whose per-vertex design of V is a positive rule for the vertex's own rays (`applies`). The
fitted ambient occlusion is clamped to [0, 1]; SH coefficients keep the fit's values (the shading
clamps B at 0).

Nothing here needs Blender.
"""

import time

import numpy as np

from . import refine

SMOOTHNESS = 0.01
# Above this many vertices the fit is skipped: such a mesh is dense against the shading's signal,
# where the fit gains least, and its factorization takes minutes and gigabytes (a 2M-vertex
# Suzanne: over 7 minutes and 17 GB before it was stopped).
MAX_VERTICES = 300_000
FITTED = ("ambient_occlusion", "visibility", "transfer", "product_matrices")
CENTROID_WEIGHT = 0.75      # of a triangle's area, at its centroid (the rule above)
CORNER_WEIGHT = 1.0 / 12.0  # at each of its corners
ANCHOR = 1e-3               # the least weight of a vertex's own sample, of the mean one
TIMED_GRID_SIDE = 40        # predicted_seconds times the fit of this many squared vertices ...
TIME_EXPONENT = 1.25        # ... and scales its time as the vertex count to this power (measured
                            # on grids of 1.6k and 42k vertices, 1 to 225 channels: 1.24-1.31)


def applies(method):
    """Whether a method's baked data are fitted (methods.Method): all but the designs."""
    return method.data is not None and all(key in FITTED for key in method.data.keys)


def centroid_split(vertices, normals, triangles):
    """(points, normals, triangles): the V vertices followed by the T centroids (their normal the
    normalised mean of the corners'), and each triangle (a, b, c) as (p, a, b), (p, b, c),
    (p, c, a) around its centroid p - the same surface, winding kept."""
    vertices, normals = np.asarray(vertices, np.float64), np.asarray(normals, np.float64)
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    # each coordinate summed in sorted order: a face and its reverse copy (bake/sides.py) get the
    # same centroid to the bit, so that the bake still finds them one sheet
    centroids = np.sort(vertices[triangles], axis=1).sum(axis=1) / 3.0
    mean = normals[triangles].sum(axis=1)
    length = np.linalg.norm(mean, axis=1, keepdims=True)
    centroid_normals = np.divide(mean, length, out=np.zeros_like(mean), where=length > 0.0)
    p = len(vertices) + np.arange(len(triangles))
    a, b, c = triangles.T
    split = np.stack([np.stack([p, a, b], 1), np.stack([p, b, c], 1), np.stack([p, c, a], 1)], 1).reshape(-1, 3)
    return (np.concatenate([vertices, centroids]), np.concatenate([normals, centroid_normals]),
            split.astype(np.int32))


def samples(vertices, triangles):
    """(sample_triangles, barycentric, weights) of the V vertex samples then the T centroid samples
    (centroid_split's points), weighted by the rule of the module's doc."""
    vertices = np.asarray(vertices, np.float64)
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    areas = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    corner = np.zeros(len(vertices))
    np.add.at(corner, triangles.ravel(), np.repeat(CORNER_WEIGHT * areas, 3))
    # a vertex of no face of positive area (loose, or of degenerate faces only) keeps its own value
    positive = corner[corner > 0.0]
    corner = np.maximum(corner, ANCHOR * (positive.mean() if len(positive) else 1.0))
    own = np.repeat(np.arange(len(vertices))[:, None], 3, axis=1)
    sample_triangles = np.concatenate([own, triangles]).astype(np.int32)
    barycentric = np.concatenate([np.tile([1.0, 0.0, 0.0], (len(vertices), 1)),
                                  np.full((len(triangles), 3), 1.0 / 3.0)])
    return sample_triangles, barycentric, np.concatenate([corner, CENTROID_WEIGHT * areas])


def gradient_jumps(vertices, triangles):
    """The regulariser's rows (vertices (R, 4) int32, coefficients (R, 4)): for each edge (a, b)
    that exactly two triangles (a, b, c) and (b, a, d) share, the derivative of the interpolant
    across the edge into each triangle, (x_c - (1 - t) x_a - t x_b) / h with t and h the foot
    and height of the opposite vertex over the edge, summed over the two sides (zero when the
    interpolant is one linear function across the edge), times the smaller height (so that the
    square is of the values' scale, and a sliver's steep gradient weighs no more than its
    neighbours'), and divided by its largest coefficient where that exceeds 1 (an obtuse sliver,
    whose opposite vertex lies far beyond the edge: t >> 1)."""
    vertices = np.asarray(vertices, np.float64)
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    sides = np.concatenate([triangles[:, [0, 1, 2]], triangles[:, [1, 2, 0]], triangles[:, [2, 0, 1]]])
    edges, side_edge = refine.edges_of(triangles)   # side k of a triangle is sides' row k·T + t
    inverse = side_edge.T.ravel()
    counts = np.bincount(inverse, minlength=len(edges))
    shared = counts[inverse] == 2
    order = np.argsort(inverse[shared], kind="stable")
    pairs = sides[shared][order].reshape(-1, 2, 3)       # the two sides of each shared edge
    a, b = pairs[:, 0, 0], pairs[:, 0, 1]
    opposite = pairs[:, :, 2]                             # c, d
    edge = vertices[b] - vertices[a]
    length2 = np.einsum("ij,ij->i", edge, edge)
    coefficients, heights = np.zeros((len(pairs), 4)), np.zeros((len(pairs), 2))
    usable = length2 > 0.0
    for side in range(2):
        offset = vertices[opposite[:, side]] - vertices[a]
        t = np.einsum("ij,ij->i", offset, edge) / np.where(usable, length2, 1.0)
        height = np.linalg.norm(offset - t[:, None] * edge, axis=1)
        usable &= height > 1e-9 * np.sqrt(length2)
        heights[:, side] = height
        inverse_height = 1.0 / np.where(height > 0.0, height, 1.0)
        coefficients[:, 0] -= (1.0 - t) * inverse_height
        coefficients[:, 1] -= t * inverse_height
        coefficients[:, 2 + side] = inverse_height
    rows = np.stack([a, b, opposite[:, 0], opposite[:, 1]], axis=1)[usable]
    coefficients *= heights.min(axis=1)[:, None]
    coefficients /= np.maximum(1.0, np.abs(coefficients).max(axis=1))[:, None]
    return rows.astype(np.int32), coefficients[usable]


def _fitted_keys(result):
    """The arrays fit() solves for, and the one whose first channel is AO (None: AO is solved for).
    AO = V~_00 = M_00,00 (y_00 = 1): where one of those is fitted, AO is its first channel rather
    than a channel of its own (PRT (8)'s M alone is then fitted, without a copy)."""
    keys = [key for key in FITTED if key in result]
    holder = next((key for key in ("visibility", "product_matrices") if key in keys), None)
    if holder is not None:
        keys.remove("ambient_occlusion")
    return keys, holder


def channels(result):
    """How many channels fit() solves for a bake_transfer result of these arrays."""
    return sum(int(np.asarray(result[key])[0].size) for key in _fitted_keys(result)[0])


def predicted_seconds(sd, vertex_count, channel_count):
    """The fit's time for a mesh of vertex_count vertices and channel_count channels: the fit of a
    flat grid of TIMED_GRID_SIDE² vertices timed here (the faster of two, about 20 ms each), scaled
    by TIME_EXPONENT (a surface mesh's sparse factorization fills in a little faster than its
    vertices grow)."""
    n = TIMED_GRID_SIDE
    x, y = np.meshgrid(np.arange(n, dtype=np.float64), np.arange(n, dtype=np.float64))
    points = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)
    corner = (np.arange(n - 1)[None, :] + n * np.arange(n - 1)[:, None]).ravel()
    triangles = np.concatenate([np.stack([corner, corner + 1, corner + n + 1], axis=1),
                                np.stack([corner, corner + n + 1, corner + n], axis=1)])
    values = np.random.default_rng(0).random((len(points) + len(triangles), max(int(channel_count), 1)))
    seconds = []
    for _ in range(2):
        start = time.perf_counter()
        sd.fit_vertex_values(len(points), *samples(points, triangles), values, *gradient_jumps(points, triangles),
                             smoothness=SMOOTHNESS)
        seconds.append(time.perf_counter() - start)
    return min(seconds) * (vertex_count / len(points)) ** TIME_EXPONENT


def fit(sd, result, vertices, triangles, smoothness=SMOOTHNESS, progress=None):
    """The bake of centroid_split's mesh (bake_transfer's dict) as a bake of the V vertices: the
    FITTED arrays least-squares fitted (as the channels of one system: one factorization), the
    per-point normals, ray origins and fallback normals cut to the vertices. Should the system be
    singular after all (sdnative's RuntimeError), the vertices keep their baked values and
    "least_squares_skipped" says why. progress: fit_vertex_values' (a cancel raises BakeCancelled)."""
    n = len(vertices)
    sample_triangles, barycentric, weights = samples(vertices, triangles)
    penalties = gradient_jumps(vertices, triangles)
    out = dict(result)
    keys, holder = _fitted_keys(result)
    arrays = [np.asarray(result[key], np.float64) for key in keys]
    columns = np.cumsum([0] + [a[0].size for a in arrays])
    flat = [a.reshape(len(a), -1) for a in arrays]
    try:
        fitted = sd.fit_vertex_values(n, sample_triangles, barycentric, weights,
                                      flat[0] if len(flat) == 1 else np.concatenate(flat, axis=1),
                                      *penalties, smoothness=smoothness, progress=progress)
        parts = [fitted[:, start:end].reshape((n,) + a.shape[1:])
                 for a, start, end in zip(arrays, columns[:-1], columns[1:])]
    except RuntimeError as exc:
        if isinstance(exc, getattr(sd, "BakeCancelled", ())):   # a RuntimeError too
            raise
        parts = [a[:n] for a in arrays]
        out["least_squares_skipped"] = str(exc)
    out.update(zip(keys, parts))
    if holder is not None:
        out["ambient_occlusion"] = out[holder].reshape(n, -1)[:, 0].copy()
    out["ambient_occlusion"] = np.clip(out["ambient_occlusion"], 0.0, 1.0)
    for key in ("normals", "ray_origins"):
        out[key] = np.asarray(result[key])[:n]
    fallbacks = np.asarray(result["fallback_normals"])
    out["fallback_normals"] = fallbacks[fallbacks < n]
    return out
