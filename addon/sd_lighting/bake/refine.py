"""Refinement of the baked copy where its vertices are too sparse for the signal (issue 8, item 3).

The live shading interpolates per-vertex data linearly over each triangle, so a shadow that
crosses a large flat face between its vertices is lost: on a CAD-like model that, not the bake,
is most of the error against Cycles. Refinement splits the baked copy's triangles where the
signal between the vertices is not linear, before the bake; the user's mesh is never touched.

The test: an edge is split where the value at its midpoint differs from the mean of the values at
its ends by more than the target error. The value is what a white Lambert surface shows under the
scene's environment, shadowed: B = T · L with T the PRT (2) transfer vector of order
CRITERION_ORDER. The user turns the environment, so the difference is averaged over every
rotation g of it: band l of L turns by a uniformly random orthogonal matrix, hence
    E_g[(ΔT · L_g)²] = Σ_l |ΔT_l|² |L_l|² / (2l + 1)          (|x_l|²: the band's sum of squares)
and the error of an edge is the square root of that over the same mean of B² over the vertices
(the object's RMS radiance): the relative RMS error that the target error states. The ends and the
midpoints are baked in one pass in which every point traces the same ray directions
(bake_transfer's common_rotation), so their difference is the signal's, not ray noise.

Which edges: those whose midpoint is off by more than the target error, the ones that add most to
the object's RMS interpolation error first - estimated from the tested midpoints as
    E² = (8/45) Σ_e a_e δ_e² / A       (δ_e an edge's error, a_e the area of the triangles beside
                                        it, A the object's)
since the interpolation error of a quadratic signal is a bump 4 λ_i λ_j δ_e along each edge, whose
mean square over a triangle of area T is 16 ∫ λ_i² λ_j² / T = 16 · 2 · 2! 2! / 6! = 8/45 of δ_e²
(the bumps' cross terms need signs the rotation average does not keep) - until E is within
INTERPOLATION_SHARE of the target: the bake's own errors (truncation, rays) take the rest, adding
in quadrature - or, where the automatic mode predicts those to be larger than the target, until E
is within BALANCE of them (aim). So a smooth, dense mesh whose edges are off here and there by a
little more than the target is left as it is, while a shadow across a large face is split down to
its edge.

The split is conforming, so no crack opens: an edge is marked as a place (the vertices at one
point - copies split at a hard edge or seam, the corners of a triangle soup - share a `weld` id
and mark their edges together); a triangle with two marked sides gets its third marked too, so
each triangle is kept, halved (one side marked) or cut into four (all sides). Each level tests
only the edges the last one made; refinement stops when E is within its share, no edge is over
the target, after MAX_LEVELS levels, or at the vertex budget. Shading follows the mesh: a midpoint gets the normalised mean of
its ends' normals (Blender and Cycles interpolate smooth normals across the face), their mean
UV, and their material slot and side (a corner copy carries one of each).

This module is bpy-free: `Surface` holds the arrays, `refine` takes the bake as a callback.
"""

from collections import deque
from dataclasses import dataclass, replace

import numpy as np

CRITERION_ORDER = 6    # the order of T the test shades with: a shadow's edge, not just its mean
CRITERION_RAYS = 256   # rays per point of the test (at most the bake's)
MAX_LEVELS = 4         # each level halves the edges it splits
INTERPOLATION_SHARE = 0.5   # of the target error, what the interpolation may take (the module's doc)
# Of the bake's own predicted error (truncation and rays), what the interpolation may keep: errors
# add in quadrature, so refining below half of it lowers the total by under 12 % (README, Use,
# items 5 and 6).
BALANCE = 0.5
BUMP_MEAN_SQUARE = 8.0 / 45.0   # an edge's bump over a triangle beside it (the module's doc)
DEFAULT_MAX_VERTICES = 250_000   # the default vertex budget (test_cycles_parity, benchmark_refine)


@dataclass
class Surface:
    """A triangle mesh as the bake and the baked copy see it; per vertex: `vertices` (bake space),
    `normals` (unit or zero), `positions` (the object's local space), `weld` (vertices at the same
    place share it), `slots`, `uvs` and `sides` (bake/sides.py; or None); `triangles` [T, 3] in
    the bake's winding."""
    vertices: np.ndarray
    normals: np.ndarray
    positions: np.ndarray
    weld: np.ndarray
    triangles: np.ndarray
    slots: object = None
    uvs: object = None
    sides: object = None

    def subset(self, rows):
        """The surface of the triangles `rows` alone, with their vertices (re-indexed, welds kept)."""
        triangles = np.asarray(self.triangles)[rows]
        used, local = np.unique(triangles, return_inverse=True)

        def pick(values):
            return None if values is None else np.asarray(values)[used]

        return Surface(self.vertices[used], self.normals[used], self.positions[used], self.weld[used],
                       local.reshape(-1, 3).astype(triangles.dtype), pick(self.slots), pick(self.uvs),
                       pick(self.sides))

    def patches(self, count, size, seed=0):
        """The rows of `count` triangles (all of them, in order, when that is all) in patches of
        up to `size` connected ones - sharing a welded vertex, so a triangle soup's too - each
        grown breadth-first from a seed triangle drawn at random (seeded) among those not taken.
        A refinement of a sample predicts the copy's only when the sample's triangles have their
        neighbours: the split spreads to them (conforming, closing), and runs of a triangle soup's
        rows are not neighbours (README, Use: the predicted bake time)."""
        triangles = np.asarray(self.triangles)
        if count >= len(triangles):
            return np.arange(len(triangles))
        welds = np.asarray(self.weld)[triangles]
        corners = np.argsort(welds.ravel(), kind="stable")   # the triangles at each weld id
        starts = np.searchsorted(welds.ravel()[corners], np.arange(int(welds.max()) + 2))
        taken = np.zeros(len(triangles), dtype=bool)
        rows = []
        for start in np.random.default_rng(seed).permutation(len(triangles)):
            if len(rows) >= count:
                break
            if taken[start]:
                continue
            taken[start] = True
            queue, grown = deque([int(start)]), 0
            while queue and grown < size and len(rows) < count:
                row = queue.popleft()
                rows.append(row)
                grown += 1
                for weld in welds[row]:
                    for neighbour in corners[starts[weld]:starts[weld + 1]] // 3:
                        if not taken[neighbour]:
                            taken[neighbour] = True
                            queue.append(int(neighbour))
        return np.array(rows, dtype=np.int64)

    def with_midpoints(self, edges, welded_edges):
        """This surface with one vertex appended at the middle of each edge [E, 2]; midpoints of
        copies of one place (welded_edges [E]: its index) share a new weld id."""
        a, b = edges[:, 0], edges[:, 1]
        normals = self.normals[a] + self.normals[b]
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0.0)

        def mean(values):
            return None if values is None else np.concatenate([values, 0.5 * (values[a] + values[b])])

        def first(values):
            return None if values is None else np.concatenate([values, values[a]])

        return replace(self, vertices=mean(self.vertices), positions=mean(self.positions),
                       normals=np.concatenate([self.normals, normals]),
                       weld=np.concatenate([self.weld, self.weld.max(initial=-1) + 1 + welded_edges]),
                       slots=first(self.slots), uvs=mean(self.uvs), sides=first(self.sides))


def criterion_rays(rays):
    """The rays per point of the test for a bake of `rays` rays."""
    return min(int(rays), CRITERION_RAYS)


def edges_of(triangles):
    """(edges [E, 2] with a < b, side_edge [T, 3]): side k of triangle t runs from t[k] to
    t[(k + 1) % 3] and is edge side_edge[t, k]."""
    sides = np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=2).reshape(-1, 2)
    # np.unique of the rows themselves (axis=0) sorts them as structured values, far slower
    keys, inverse = np.unique(_pair_keys(sides), return_inverse=True)
    edges = np.stack([keys >> 32, keys & 0xFFFFFFFF], axis=1).astype(triangles.dtype)
    return edges, inverse.reshape(-1, 3)


def _pair_keys(pairs):
    """One int64 per unordered pair of ids [N, 2], ordered as the sorted pairs are: ids stay below
    2³¹ (Embree indexes vertices with 32 bits, and a weld id is a vertex's)."""
    ends = np.sort(pairs, axis=1).astype(np.int64)
    return (ends[:, 0] << 32) | ends[:, 1]


def _places(weld, edges):
    """(the index of each edge's place among the distinct places, an int64 key of each place):
    a place is the unordered pair of its ends' weld ids."""
    keys = _pair_keys(weld[edges])     # the same key at every level
    return np.unique(keys, return_inverse=True)[1].reshape(-1), keys


def split(triangles, side_edge, marked, midpoint):
    """The triangles with their marked sides split, windings kept: a triangle with no marked side
    is kept, one with one is halved towards the opposite corner, one with two is cut into three
    (the corner between them, and the rest by the diagonal from the unsplit side's first corner),
    one with three into four. marked: bool [E]; midpoint: int [E], the vertex at the middle of
    each marked edge. Returns the triangles."""
    t = triangles
    m = np.where(marked[side_edge], midpoint[side_edge], -1)   # [T, 3]: side k's midpoint or -1
    count = (m >= 0).sum(axis=1)
    out = [t[count == 0]]

    four = count == 3
    if four.any():
        a, b, c = t[four].T
        ab, bc, ca = m[four].T
        out += [np.stack(x, axis=1) for x in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]

    for marked_sides in (1, 2):
        rows = np.flatnonzero(count == marked_sides)
        if rows.size == 0:
            continue
        # Turn each triangle so that its first marked side (for two: the one whose next side is
        # marked too) is side 0: (a, b) split at ab; c is the opposite corner.
        has = m[rows] >= 0
        if marked_sides == 1:
            k = np.argmax(has, axis=1)
        else:
            k = np.argmax(has & np.roll(has, -1, axis=1), axis=1)
        turn = (k[:, None] + np.arange(3)[None, :]) % 3
        a, b, c = np.take_along_axis(t[rows], turn, axis=1).T
        ab, bc, _ = np.take_along_axis(m[rows], turn, axis=1).T
        if marked_sides == 1:
            out += [np.stack((a, ab, c), axis=1), np.stack((ab, b, c), axis=1)]
        else:
            out += [np.stack((ab, b, bc), axis=1), np.stack((a, ab, bc), axis=1),
                    np.stack((a, bc, c), axis=1)]
    return np.concatenate(out).astype(triangles.dtype)


def close_marks(side_edge, welded_edges, marked_welded):
    """The marks of places (bool over welded edges) with every triangle that has two marked sides
    given its third: afterwards each triangle has none, one or three."""
    marked_welded = marked_welded.copy()
    side_place = welded_edges[side_edge]
    while True:
        sides = marked_welded[side_place]
        two = sides.sum(axis=1) == 2
        if not two.any():
            return marked_welded
        marked_welded[side_place[two][~sides[two]]] = True


def band_weights(light):
    """Per SH coefficient l² + l + m of `light` ([(s+1)², channels]): |L_l|² / (2l + 1), the weight
    of ΔT_lm² in the rotation-averaged squared difference of B (the module's doc)."""
    light = np.asarray(light, dtype=np.float64).reshape(len(light), -1)
    order = int(round(np.sqrt(len(light)))) - 1
    band = np.repeat(np.arange(order + 1), 2 * np.arange(order + 1) + 1)
    energy = np.bincount(band, weights=(light ** 2).sum(axis=1), minlength=order + 1)
    return (energy / (2 * np.arange(order + 1) + 1))[band]


@dataclass
class Refinement:
    """What refine() did: the refined surface, the levels run, the edges split, the largest error
    of an edge left unsplit and the object's RMS interpolation error left as its tested edges
    estimate it (both relative; an edge split in the last level counts as resolved)."""
    surface: Surface
    levels: int
    split_edges: int
    worst_left: float
    estimated_left: float
    budget_reached: bool


def aim(target, predicted_error=None):
    """The RMS interpolation error refinement aims at: its share of the target, or, where the bake's
    own predicted error is larger, its BALANCE of that."""
    share = INTERPOLATION_SHARE * target
    return share if predicted_error is None else max(share, BALANCE * predicted_error)


def refine(surface, bake, weights, target, max_vertices, max_levels=MAX_LEVELS, aimed=None, whole_weights=None):
    """Refines `surface` (the module's doc). bake(vertices, normals, triangles, rest_vertices,
    rest_triangles) -> T [V, (s+1)²]: the transfer vectors of the object made of those vertices
    and triangles, with rest_triangles (indices into rest_vertices: the surface's other triangles)
    and the scene as occluders, every vertex tracing the same ray directions; weights: band_weights
    of the light; target: the relative error an edge may keep; aimed: the RMS interpolation error
    refinement aims at (default aim(target)); max_vertices: the budget; whole_weights: band_weights of
    the light whose B the errors are relative to, where `weights` are of a part of it (the map
    without the bright sources the live shading shades on their own: their shadows are drawn per
    pixel, so only the rest's need vertices; default `weights`). Raises what bake raises (a cancel).
    Returns a Refinement."""
    triangles = np.asarray(surface.triangles)
    if len(surface.vertices) >= max_vertices:
        return Refinement(surface, 0, 0, 0.0, 0.0, True)
    known_keys = np.zeros(0, dtype=np.int64)   # the places tested so far (sorted keys) ...
    known_errors = np.zeros(0)                 # ... and the error found at each
    scale = None
    levels = split_count = 0
    worst_left = estimated_left = 0.0
    budget_reached = False
    for _ in range(max_levels):
        edges, side_edge = edges_of(triangles)
        welded_edges, keys = _places(surface.weld, edges)
        position = np.minimum(np.searchsorted(known_keys, keys), max(len(known_keys) - 1, 0))
        seen = known_keys[position] == keys if len(known_keys) else np.zeros(len(keys), dtype=bool)
        error = np.where(seen, known_errors[position] if len(known_keys) else 0.0, 0.0)
        candidate = ~seen          # the edges the last split made (all of them at first)
        if not candidate.any():
            break

        # Bake the triangles with a candidate side, those sides split, with the rest as occluders.
        probe = surface.with_midpoints(edges, welded_edges)
        midpoint = len(surface.vertices) + np.arange(len(edges))
        around = candidate[side_edge].any(axis=1)
        probed = split(triangles[around], side_edge[around], candidate, midpoint)
        used, local = np.unique(probed, return_inverse=True)
        transfer = np.zeros((len(probe.vertices), len(weights)))
        transfer[used] = bake(probe.vertices[used], probe.normals[used], local.reshape(-1, 3),
                              surface.vertices, triangles[~around])
        if scale is None:
            scale = float(np.mean(transfer[used] ** 2 @ (weights if whole_weights is None else whole_weights)))
        a, b = edges[candidate, 0], edges[candidate, 1]
        delta = transfer[midpoint[candidate]] - 0.5 * (transfer[a] + transfer[b])
        error[candidate] = np.sqrt(delta ** 2 @ weights / scale) if scale > 0.0 else 0.0
        order = np.argsort(np.r_[known_keys, keys[candidate]], kind="stable")
        known_keys = np.r_[known_keys, keys[candidate]][order]
        known_errors = np.r_[known_errors, error[candidate]][order]

        # Per place: its worst copy's error and its share of E² (the module's doc).
        place_error = np.zeros(welded_edges.max() + 1)
        np.maximum.at(place_error, welded_edges, error)
        corners = surface.vertices[triangles]
        area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
        edge_area = np.bincount(side_edge.ravel(), weights=np.repeat(area, 3), minlength=len(edges))
        place_area = np.bincount(welded_edges, weights=edge_area, minlength=len(place_error))
        contribution = BUMP_MEAN_SQUARE * place_area * place_error ** 2
        total_area = max(float(area.sum()), 1e-300)
        total, goal = contribution.sum(), (aim(target) if aimed is None else aimed) ** 2 * total_area

        # The places over the target that add most to the object's error first, until what is
        # left is within its share of the target; as many as the budget holds once closed.
        worst = np.flatnonzero(place_error > target)
        worst = worst[np.argsort(-contribution[worst], kind="stable")]
        left = total - np.cumsum(contribution[worst])
        keep = min(int(np.searchsorted(-left, -goal)) + 1, len(worst)) if total > goal else 0
        room = max_vertices - len(surface.vertices)
        copies = np.bincount(welded_edges, minlength=len(place_error))
        marked = np.zeros(len(place_error), dtype=bool)
        while keep > 0:
            marked[:] = False
            marked[worst[:keep]] = True
            marked = close_marks(side_edge, welded_edges, marked)
            if copies[marked].sum() <= room:
                break
            budget_reached = True
            keep //= 2
        worst_left = float(place_error[~marked].max(initial=0.0))
        estimated_left = float(np.sqrt(contribution[~marked].sum() / total_area))
        if keep == 0:
            break
        split_marked = marked[welded_edges]
        order = np.cumsum(split_marked) - 1
        kept = surface.with_midpoints(edges[split_marked], welded_edges[split_marked])
        triangles = split(triangles, side_edge, split_marked,
                          len(surface.vertices) + np.where(split_marked, order, 0))
        surface = replace(kept, triangles=triangles)
        levels += 1
        split_count += int(split_marked.sum())
        if budget_reached:
            break
    return Refinement(replace(surface, triangles=triangles), levels, split_count, worst_left,
                      estimated_left, budget_reached)
