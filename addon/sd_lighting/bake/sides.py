"""Faces seen from behind (issue 32, item 2): the baked copy's faces turned or doubled so that
every side a viewer can see has vertices baked for it.

Cycles lights and shadows both sides of a face, shading a face seen from behind with its normal
turned towards the viewer; a bake shades the side its normals point to. sdnative.face_sides says
per triangle what each face needs (native/include/sdlighting/face_sides.h): a face of a closed
solid wound inward (a flipped face, a mesh turned inside out) is turned round - its corners
reversed and their normals negated - and a face whose back can be seen (a ground plane, a wall, a
leaf) gets a reverse copy after the mesh's own faces, with its own corners, normals negated. The
two copies of a face are a sheet to the bake (one surface, an origin on each side), and the live
shading draws each copy only from its own side: their vertices are marked (`loop_sides`, stored
per vertex), and the draw culls the back faces of those triangles alone. A
face turned round is drawn from both sides, as before.

A polygon is treated as a whole (its triangles share its answer: the largest code among them).
This module is bpy-free: it works on the loop arrays bake/geometry.py reads.
"""

import dataclasses

import numpy as np

FRONT, FLIPPED, BOTH, SHEET = 0, 1, 2, 3   # sdnative.FACE_FRONT ... FACE_SHEET
# A loop's side: drawn from both sides; the front of a face drawn from its own side only; a back
# copy (drawn from its own side only). The corner split keeps the three apart.
SINGLE, FRONT_SIDE, BACK_SIDE = 0, 1, 2


@dataclasses.dataclass
class SidedLoops:
    """A mesh's loop arrays with its polygons turned or doubled: the polygons in their order,
    then the reverse copies. `loop_order`: each new loop's old loop; `negated`: whether its
    normal is negated; `triangle_loops` [T', 3] in the new loops, wound as the bake winds them;
    `loop_sides`: SINGLE, FRONT_SIDE or BACK_SIDE per new loop; `flipped`, `doubled`: the polygons turned
    round and copied."""
    loop_order: np.ndarray
    negated: np.ndarray
    loop_starts: np.ndarray
    loop_totals: np.ndarray
    triangle_loops: np.ndarray
    loop_sides: np.ndarray
    flipped: int
    doubled: int

    def gather(self, loop_values):
        """A per-loop array [L, ...] of the mesh as one row per new loop (None stays None)."""
        return None if loop_values is None else np.asarray(loop_values)[self.loop_order]

    def normals(self, corner_normals):
        """The corner normals [L, 3] per new loop, negated on the turned and copied corners."""
        normals = np.asarray(corner_normals)[self.loop_order]
        return np.where(self.negated[:, None], -normals, normals)


def polygon_codes(triangle_codes, triangle_loops, loop_starts, loop_totals):
    """Each polygon's code (sdnative.face_sides' per triangle, the largest among its triangles)."""
    polygon_of_loop = np.repeat(np.arange(len(loop_starts)), loop_totals)
    codes = np.zeros(len(loop_starts), dtype=np.int64)
    if len(triangle_loops):
        np.maximum.at(codes, polygon_of_loop[np.asarray(triangle_loops)[:, 0]], np.asarray(triangle_codes, np.int64))
    return codes


def _reversed_offsets(starts, totals):
    """For every loop of the polygons (starts, totals), in order: the loop that takes its place
    when the polygon is wound the other way (its first corner kept, the rest reversed)."""
    offset = np.arange(int(np.sum(totals))) - np.repeat(np.cumsum(totals) - totals, totals)
    each = np.repeat(totals, totals)
    return np.repeat(starts, totals) + (each - offset) % each


def apply(codes, loop_starts, loop_totals, triangle_loops):
    """The SidedLoops of a mesh whose polygons have `codes` (polygon_codes); triangle_loops [T, 3]:
    each triangle's loops as the bake winds them."""
    codes = np.asarray(codes)
    loop_starts = np.asarray(loop_starts, np.int64)
    loop_totals = np.asarray(loop_totals, np.int64)
    loops = int(loop_totals.sum())
    triangle_loops = np.asarray(triangle_loops, np.int64).reshape(-1, 3)
    polygon_of_loop = np.repeat(np.arange(len(loop_starts)), loop_totals)

    # the polygons in place, those FLIPPED wound the other way (a reversal is its own inverse)
    reverse_all = _reversed_offsets(loop_starts, loop_totals)
    turned = codes[polygon_of_loop] == FLIPPED
    in_place = np.where(turned, reverse_all, np.arange(loops))
    # the reverse copies of those BOTH, after every loop of the mesh
    copied = np.flatnonzero(codes == BOTH)
    copy_totals = loop_totals[copied]
    copy_starts = loops + np.cumsum(copy_totals) - copy_totals
    copy_loops = _reversed_offsets(loop_starts[copied], copy_totals)
    copy_of_loop = np.full(loops, -1, np.int64)   # an old loop's place in its polygon's copy
    copy_of_loop[copy_loops] = loops + np.arange(len(copy_loops))

    two_sided = np.isin(codes, (BOTH, SHEET))
    triangle_polygon = polygon_of_loop[triangle_loops[:, 0]] if len(triangle_loops) else np.zeros(0, np.int64)
    front_triangles = in_place[triangle_loops]
    front_triangles = np.where((codes[triangle_polygon] == FLIPPED)[:, None], front_triangles[:, ::-1],
                               front_triangles)
    copies = triangle_loops[codes[triangle_polygon] == BOTH]
    return SidedLoops(
        loop_order=np.concatenate([in_place, copy_loops]).astype(np.int64),
        negated=np.concatenate([turned, np.ones(len(copy_loops), bool)]),
        loop_starts=np.concatenate([loop_starts, copy_starts]).astype(np.int32),
        loop_totals=np.concatenate([loop_totals, copy_totals]).astype(np.int32),
        triangle_loops=np.concatenate([front_triangles, copy_of_loop[copies][:, ::-1]]).astype(np.int64),
        loop_sides=np.concatenate([np.where(two_sided[polygon_of_loop], FRONT_SIDE, SINGLE),
                                   np.full(len(copy_loops), BACK_SIDE)]).astype(np.int8),
        flipped=int(np.count_nonzero(codes == FLIPPED)), doubled=len(copied))
