"""Corner data (issue 8, item 4): the baked copy gets one vertex per group of face corners that
shade alike, so that per-vertex data can follow what Blender and Cycles shade with.

A mesh vertex is split where its corners (loops) differ in
- the corner normal (flat faces, sharp edges, custom normals: what Cycles interpolates), by more
  than NORMAL_TOLERANCE_DEGREES;
- the material slot (its colour is looked up per vertex: materials.py);
- the UV coordinate of the albedo texture (a UV seam), when the bake keeps one;
- the side it is drawn from (bake/sides.py: a face seen from both sides and its reverse copy
  never share a vertex with a face drawn from both sides by one copy).
On a smooth mesh with one material and no seam nothing is split, and the vertex order is kept:
new vertices are sorted by their original vertex, then by their first loop.
"""

import numpy as np

# Two corners of a vertex share a copy when their unit normals are within this angle (Blender's
# corner normals on a smooth face equal the vertex normal exactly; flat faces and sharp edges
# differ by far more), their slots are equal and their UVs agree to float32 rounding. Read at each
# split: blender_tests/benchmark_refine.py measures the bake without corner data at 180 degrees
# (copies by slot and UV only, each with its corners' mean normal, as on a welded mesh).
NORMAL_TOLERANCE_DEGREES = 0.6
_UV_TOLERANCE = 1e-6


class CornerSplit:
    """How the loops of a mesh map to the split vertices.

    loop_vertex[l]: the split vertex of loop l; origin[v]: the mesh vertex split vertex v came
    from; normal_sums[v]: the sum of its corners' normals (float64; normalise it, with a fallback
    where it is zero)."""

    def __init__(self, loop_vertex, origin, normal_sums):
        self.loop_vertex = loop_vertex
        self.origin = origin
        self.normal_sums = normal_sums

    @property
    def count(self):
        return len(self.origin)


def split(loop_vertices, corner_normals, loop_materials=None, loop_uvs=None, loop_sides=None):
    """Groups the loops of each vertex that shade alike (see the module's doc).

    loop_vertices: int [L] each loop's vertex; corner_normals: [L, 3] (unit or zero);
    loop_materials: int [L] each loop's material slot, or None (one material);
    loop_uvs: [L, 2] or None (no texture); loop_sides: int [L] (sides.SINGLE, FRONT_SIDE or BACK_SIDE) or
    None (all single). Returns a CornerSplit.

    Each vertex's loops are taken in loop order: the first one not yet grouped leads a new copy,
    which takes every loop that agrees with it. So the copies and their order depend only on the
    topology and on which corners agree - not on the space the normals are in, nor on rounding
    (a mirrored object and the same mesh with Apply Scale split alike)."""
    loop_vertices = np.asarray(loop_vertices, dtype=np.int64)
    normals = np.asarray(corner_normals, dtype=np.float64).reshape(-1, 3)
    if len(normals) != len(loop_vertices):
        raise ValueError("%d corner normals for %d loops" % (len(normals), len(loop_vertices)))
    cos_tolerance = np.cos(np.radians(NORMAL_TOLERANCE_DEGREES)) - 1e-12   # 180: opposite normals too
    lengths = np.linalg.norm(normals, axis=1)
    units = normals / np.where(lengths > 0.0, lengths, 1.0)[:, None]
    slots = None if loop_materials is None else np.asarray(loop_materials, dtype=np.int64)
    uvs = None if loop_uvs is None else np.asarray(loop_uvs, dtype=np.float64).reshape(-1, 2)
    sides = None if loop_sides is None else np.asarray(loop_sides, dtype=np.int64)
    copy = np.zeros(len(loop_vertices), dtype=np.int64)     # each loop's copy, per vertex: 0, 1, ...
    remaining = np.argsort(loop_vertices, kind="stable")    # by vertex, then loop order
    rank = 0
    while remaining.size:
        vertex = loop_vertices[remaining]
        starts = np.flatnonzero(np.r_[True, vertex[1:] != vertex[:-1]])
        leader = np.repeat(remaining[starts], np.diff(np.r_[starts, len(remaining)]))
        same = np.einsum("ij,ij->i", units[remaining], units[leader]) >= cos_tolerance
        same |= (lengths[remaining] == 0.0) & (lengths[leader] == 0.0)   # no normal: one copy
        if slots is not None:
            same &= slots[remaining] == slots[leader]
        if sides is not None:
            same &= sides[remaining] == sides[leader]
        if uvs is not None:
            same &= np.all(np.abs(uvs[remaining] - uvs[leader]) <= _UV_TOLERANCE, axis=1)
        same |= remaining == leader
        copy[remaining[same]] = rank
        remaining = remaining[~same]
        rank += 1
    keys = loop_vertices * max(rank, 1) + copy
    unique, loop_vertex = np.unique(keys, return_inverse=True)
    summed = np.zeros((len(unique), 3))
    np.add.at(summed, loop_vertex, normals)
    return CornerSplit(loop_vertex.reshape(-1).astype(np.int32), unique // max(rank, 1), summed)


def vertex_values(split_, loop_values):
    """A per-loop array [L, ...] as one value per split vertex (any of its loops: they agree)."""
    out = np.empty((split_.count,) + np.shape(loop_values)[1:], dtype=np.asarray(loop_values).dtype)
    out[split_.loop_vertex] = loop_values
    return out
