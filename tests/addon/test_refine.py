"""bake/refine.py: the conforming split, the rotation-averaged criterion, and refine() on signals
with a known answer (a synthetic bake) and on a real one (sdnative's, a box on a floor)."""

import numpy as np
import pytest

from sd_lighting.bake import refine


def _grid(n, size=1.0):
    """A flat n x n grid of squares, two triangles each, in z = 0 facing +z, as a Surface."""
    xs = np.linspace(-size / 2, size / 2, n + 1)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    vertices = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    index = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int32)
    normals = np.tile([0.0, 0.0, 1.0], (len(vertices), 1))
    return refine.Surface(vertices, normals, vertices.copy(), np.arange(len(vertices)), triangles)


def _signed_areas(vertices, triangles):
    p = vertices[triangles]
    return 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2]


def _boundary_length(vertices, triangles):
    """The length of the edges used by one triangle only: the outline, plus every crack (a side
    that meets a split neighbour at a T-junction is used once)."""
    sides = np.sort(np.stack([triangles, np.roll(triangles, -1, axis=1)], 2).reshape(-1, 2), axis=1)
    edges, counts = np.unique(sides, axis=0, return_counts=True)
    once = edges[counts == 1]
    return float(np.linalg.norm(vertices[once[:, 0]] - vertices[once[:, 1]], axis=1).sum())


# --------------------------------------------------------------------------------------------
# The split

@pytest.mark.parametrize("marked_sides, pieces", [((), 1), ((0,), 2), ((1,), 2), ((2,), 2),
                                                  ((0, 1), 3), ((1, 2), 3), ((2, 0), 3),
                                                  ((0, 1, 2), 4)])
def test_a_triangle_splits_into_pieces_of_the_same_area_and_winding(marked_sides, pieces):
    vertices = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 1.5, 0.0]])
    triangles = np.array([[0, 1, 2]])
    edges, side_edge = refine.edges_of(triangles)
    marked = np.zeros(len(edges), dtype=bool)
    marked[side_edge[0, list(marked_sides)]] = True
    midpoints = 0.5 * (vertices[edges[:, 0]] + vertices[edges[:, 1]])
    out = refine.split(triangles, side_edge, marked, len(vertices) + np.arange(len(edges)))
    all_vertices = np.concatenate([vertices, midpoints])
    areas = _signed_areas(all_vertices, out)
    assert len(out) == pieces
    assert np.all(areas > 0.0)
    assert areas.sum() == pytest.approx(_signed_areas(vertices, triangles)[0], rel=1e-12)
    used_midpoints = set(out.ravel()) - {0, 1, 2}
    assert used_midpoints == {len(vertices) + e for e in side_edge[0, list(marked_sides)]}


def test_closing_the_marks_leaves_no_triangle_with_two_marked_sides():
    surface = _grid(4)
    edges, side_edge = refine.edges_of(surface.triangles)
    marked = np.zeros(len(edges), dtype=bool)
    marked[side_edge[5, :2]] = True
    closed = refine.close_marks(side_edge, np.arange(len(edges)), marked)
    assert closed[side_edge[5]].all()
    assert set(closed[side_edge].sum(axis=1)) <= {0, 1, 3}
    assert (closed >= marked).all()


# --------------------------------------------------------------------------------------------
# The criterion

def test_band_weights_give_the_rotation_average_of_the_squared_difference(sdnative):
    """E_g[(ΔT · L_g)²] = Σ_lm ΔT_lm² |L_l|²/(2l+1) for uniformly random rotations g (Monte
    Carlo over 4000 rotations: a 5 % tolerance holds its spread several times over)."""
    rng = np.random.default_rng(7)
    order = 3
    light = rng.normal(size=((order + 1) ** 2, 3))
    delta = rng.normal(size=(order + 1) ** 2)
    predicted = float(delta ** 2 @ refine.band_weights(light))
    samples = []
    for _ in range(4000):
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        q = q @ np.diag(np.sign(np.diag(r)))
        if np.linalg.det(q) < 0:
            q[:, 0] = -q[:, 0]
        turned = sdnative.rotate_sh(light, q)
        samples.append(np.sum((delta @ turned) ** 2))
    assert np.mean(samples) == pytest.approx(predicted, rel=0.05)


# --------------------------------------------------------------------------------------------
# refine() with a synthetic bake: T_00 a function of the position, the other coefficients 0

def _synthetic_bake(signal, calls=None):
    def bake(vertices, normals, triangles, rest_vertices, rest_triangles):
        if calls is not None:
            calls.append(len(vertices))
        out = np.zeros((len(vertices), 4))
        out[:, 0] = signal(vertices)
        return out
    return bake


WEIGHTS = refine.band_weights(np.eye(4, 3))   # order 1, L_00 = (1, 0, 0)


def test_patches_are_connected_even_in_a_triangle_soup():
    grid = _grid(16)
    corners = grid.triangles.ravel()
    soup = refine.Surface(grid.vertices[corners], grid.normals[corners], grid.positions[corners], corners,
                          np.arange(len(corners)).reshape(-1, 3).astype(np.int32))
    rows = soup.patches(100, 40, seed=3)
    assert len(rows) == len(set(rows.tolist())) == 100
    for patch in (rows[:40], rows[40:80]):   # each grown from its seed through shared (welded) corners
        reached, welds = {int(patch[0])}, set(soup.weld[soup.triangles[patch[0]]].tolist())
        for _ in patch:
            for row in patch:
                if row not in reached and welds & set(soup.weld[soup.triangles[row]].tolist()):
                    reached.add(int(row))
                    welds |= set(soup.weld[soup.triangles[row]].tolist())
        assert reached == set(patch.tolist())
    assert np.array_equal(soup.patches(10_000, 40), np.arange(len(soup.triangles)))   # all of a small mesh


def test_small_errors_here_and_there_split_nothing():
    """Edges off by a little more than the target, on a small share of the area: the object's
    interpolation error is within its share of the target, so nothing is split."""
    surface = _grid(8)
    bump = lambda p: 1.0 + 0.1 * np.exp(-np.sum((p[:, :2] - 0.31) ** 2, axis=1) / 0.0005)  # noqa: E731
    result = refine.refine(surface, _synthetic_bake(bump), WEIGHTS, 0.02, 10 ** 6)
    assert result.worst_left > 0.02                                  # an edge is off by more ...
    assert result.estimated_left <= refine.INTERPOLATION_SHARE * 0.02   # ... but the object is not
    assert result.levels == 0


def test_a_linear_signal_splits_nothing():
    surface = _grid(3)
    result = refine.refine(surface, _synthetic_bake(lambda p: 1.0 + 0.7 * p[:, 0] - 0.2 * p[:, 1]),
                           WEIGHTS, 0.01, 10 ** 6)
    assert result.levels == 0 and result.split_edges == 0
    assert result.worst_left < 1e-12
    assert np.array_equal(result.surface.triangles, surface.triangles)


def test_a_shadow_edge_is_refined_towards_it_and_nowhere_else():
    surface = _grid(8)
    triangle = 1.0 / 128
    step = 0.13

    def shadowed(p):
        return np.where(p[:, 0] < step, 0.2, 1.0)

    calls = []
    result = refine.refine(surface, _synthetic_bake(shadowed, calls), WEIGHTS, 0.02, 10 ** 6)
    out = result.surface
    # Split until the estimated interpolation error is within its share of the target, or the
    # levels run out; the worst edges first.
    assert result.estimated_left <= refine.INTERPOLATION_SHARE * 0.02 or result.levels == refine.MAX_LEVELS
    assert result.levels >= 3
    # Only triangles next to the step were split: far from it the grid's triangles are whole.
    p = out.vertices[out.triangles]
    areas = np.abs(_signed_areas(out.vertices, out.triangles))
    far = (p[:, :, 0].max(axis=1) < step - 0.26) | (p[:, :, 0].min(axis=1) > step + 0.26)
    assert far.any() and np.allclose(areas[far], triangle)
    near = (p[:, :, 0].min(axis=1) <= step) & (p[:, :, 0].max(axis=1) >= step)
    assert areas[near].max() <= triangle / 4 ** (result.levels - 1)
    # Conforming: the area and the outline are those of the square; no crack opened.
    assert areas.sum() == pytest.approx(1.0, rel=1e-12)
    assert _boundary_length(out.vertices, out.triangles) == pytest.approx(4.0, rel=1e-12)
    assert np.all(_signed_areas(out.vertices, out.triangles) > 0.0)
    # Each level after the first bakes only around what the last one made.
    assert calls[1] < calls[0] and len(calls) == refine.MAX_LEVELS
    # Midpoints carry their ends' mean position and unit normals.
    assert np.allclose(out.positions, out.vertices)
    assert np.allclose(out.normals, [0.0, 0.0, 1.0])


def test_the_vertex_budget_holds_and_says_it_stopped_refinement():
    surface = _grid(4)
    budget = len(surface.vertices) + 12
    result = refine.refine(surface, _synthetic_bake(lambda p: np.where(p[:, 0] < 0.13, 0.2, 1.0)),
                           WEIGHTS, 0.02, budget)
    assert result.budget_reached
    assert len(surface.vertices) < len(result.surface.vertices) <= budget
    assert _boundary_length(result.surface.vertices, result.surface.triangles) == pytest.approx(4.0)


def test_a_surface_at_the_budget_is_not_tested_at_all():
    calls = []
    surface = _grid(4)
    result = refine.refine(surface, _synthetic_bake(lambda p: np.where(p[:, 0] < 0.13, 0.2, 1.0), calls),
                           WEIGHTS, 0.02, len(surface.vertices))
    assert result.budget_reached and result.levels == 0 and not calls
    assert result.surface is surface


def test_copies_of_a_vertex_split_their_edges_together():
    """Two triangles meeting at a hard edge, each with its own copies of the edge's vertices (the
    corner split): a signal that changes along one copy only splits both, so no crack opens."""
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
                         [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
    normals = np.array([[0.0, 0.0, 1.0]] * 3 + [[0.0, 0.6, 0.8]] * 3)
    surface = refine.Surface(vertices, normals, vertices.copy(), np.array([0, 1, 2, 1, 2, 3]),
                             np.array([[0, 1, 2], [3, 5, 4]], dtype=np.int32),
                             slots=np.array([0, 0, 0, 1, 1, 1]), uvs=vertices[:, :2].copy())

    def bump_on_first_copy(p):   # a peak at the middle of the shared edge, seen from face 0 only
        return 1.0 + 0.5 * np.exp(-np.sum((p - [0.5, 0.5, 0.0]) ** 2, axis=1) / 0.01)

    def bake(verts, norms, triangles, rest_vertices, rest_triangles):
        out = np.zeros((len(verts), 4))
        out[:, 0] = np.where(norms[:, 2] > 0.9, bump_on_first_copy(verts), 1.0)
        return out

    result = refine.refine(surface, bake, WEIGHTS, 0.02, 10 ** 6, max_levels=1)
    out = result.surface
    assert result.levels == 1
    middles = np.flatnonzero(np.all(np.isclose(out.vertices, [0.5, 0.5, 0.0]), axis=1))
    assert len(middles) == 2                                  # one per copy
    assert len(set(out.weld[middles])) == 1                   # at one place
    assert sorted(out.slots[middles]) == [0, 1]               # each keeps its face's slot
    assert np.allclose(out.normals[middles], normals[[0, 3]]) or np.allclose(out.normals[middles], normals[[3, 0]])
    assert np.allclose(out.uvs[middles], [0.5, 0.5])
    # Welded, the halves of the hard edge are shared: the outline is the unit square's, no crack.
    place_of = {w: i for i, w in enumerate(out.weld)}
    welded = np.vectorize(place_of.get)(out.weld[out.triangles])
    assert _boundary_length(out.vertices, welded) == pytest.approx(4.0)


# --------------------------------------------------------------------------------------------
# refine() on sdnative's bake: a box standing on a floor

def _box(centre, half):
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    triangles = [[f[0], f[1], f[2]] for f in faces] + [[f[0], f[2], f[3]] for f in faces]
    return np.asarray(centre) + half * corners, np.array(triangles, dtype=np.int32)


def _native_bake(sdnative, occluders):
    def bake(vertices, normals, triangles, rest_vertices, rest_triangles):
        verts, tris = [rest_vertices], [rest_triangles]
        if occluders is not None:
            verts.append(occluders[0])
            tris.append(occluders[1] + len(rest_vertices))
        return sdnative.bake_transfer(
            vertices, normals, triangles, rays=refine.CRITERION_RAYS, transfer_order=2,
            occluder_vertices=np.concatenate(verts), occluder_triangles=np.concatenate(tris).astype(np.int32),
            common_rotation=True)["transfer"]
    return bake


def test_a_floor_is_refined_around_a_box_standing_on_it_and_not_alone(sdnative):
    light = np.zeros((9, 3))
    light[0] = 1.0
    light[2] = 0.8          # brighter from above: y_10 ~ z
    weights = refine.band_weights(light)
    floor = _grid(6, size=6.0)
    alone = refine.refine(floor, _native_bake(sdnative, None), weights, 0.02, 10 ** 5)
    assert alone.levels == 0, alone.worst_left
    box = _box([0.0, 0.0, 0.5], 0.5)
    shadowed = refine.refine(floor, _native_bake(sdnative, box), weights, 0.02, 10 ** 5)
    out = shadowed.surface
    assert shadowed.levels >= 2
    new = out.vertices[len(floor.vertices):]
    distance = np.abs(new[:, :2]).max(axis=1)     # from the box's footprint's centre, in the L∞ norm
    assert np.median(distance) < 2.0              # refined around the box, not at the far border
    assert _boundary_length(out.vertices, out.triangles) == pytest.approx(24.0)


def test_common_rotation_makes_points_that_see_alike_bake_alike(sdnative):
    """On an open floor every point sees the same sky: with common rays their transfer vectors are
    equal; with each vertex's own rotation they differ by ray noise."""
    floor = _grid(3, size=2.0)
    kwargs = dict(rays=128, transfer_order=2)
    common = sdnative.bake_transfer(floor.vertices, floor.normals, floor.triangles, common_rotation=True,
                                    **kwargs)["transfer"]
    own = sdnative.bake_transfer(floor.vertices, floor.normals, floor.triangles, **kwargs)["transfer"]
    assert np.abs(common - common[0]).max() < 1e-12
    assert np.abs(own - own[0]).max() > 1e-3


def test_a_larger_predicted_error_elsewhere_stops_the_refinement_sooner():
    """refine.aim: under a bake whose own predicted error is twice the target, the interpolation
    is refined only to BALANCE of that, with fewer vertices and an estimate within it."""
    assert refine.aim(0.02) == refine.INTERPOLATION_SHARE * 0.02
    assert refine.aim(0.02, 0.005) == refine.INTERPOLATION_SHARE * 0.02
    assert refine.aim(0.02, 0.08) == refine.BALANCE * 0.08
    shadowed = _synthetic_bake(lambda p: np.where(p[:, 0] < 0.13, 0.2, 1.0))
    to_target = refine.refine(_grid(8), shadowed, WEIGHTS, 0.02, 10 ** 6)
    balanced = refine.refine(_grid(8), shadowed, WEIGHTS, 0.02, 10 ** 6, aimed=refine.aim(0.02, 0.08))
    assert len(balanced.surface.vertices) < len(to_target.surface.vertices)
    assert balanced.estimated_left <= refine.BALANCE * 0.08


def test_a_shadow_of_the_sources_drawn_per_pixel_is_left_to_them():
    """whole_weights: where the live shading draws the bright sources' shadows per pixel, the
    edges are measured on the rest of the map's light (here 2 % of the energy, weights scaled by
    0.02^2), relative to the whole map's B: a shadow edge the sources make is not refined, while the
    same edge in the whole light is."""
    shadowed = _synthetic_bake(lambda p: np.where(p[:, 0] < 0.13, 0.2, 1.0))
    whole = refine.refine(_grid(8), shadowed, WEIGHTS, 0.02, 10 ** 6)
    rest = refine.refine(_grid(8), shadowed, 0.02 ** 2 * WEIGHTS, 0.02, 10 ** 6, whole_weights=WEIGHTS)
    assert whole.levels >= 3 and rest.levels == 0
    assert 0.0 < rest.worst_left < 0.02    # the edge, seen on 2 % of the light: under the target
    # relative to the part's own B it would be the whole edge again
    assert refine.refine(_grid(8), shadowed, 0.02 ** 2 * WEIGHTS, 0.02, 10 ** 6).levels == whole.levels
