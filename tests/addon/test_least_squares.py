"""Least-squares vertex values (bake/least_squares.py): the centroid split, the samples' rule,
the regulariser's rows, and a fit of real bakes against the signal between the vertices."""

import numpy as np
import pytest

from sd_lighting import methods
from sd_lighting.bake import least_squares


def grid(n=5, size=1.0, height=None):
    """An n x n grid of vertices over [0, size]^2 (z from `height`, a function of x and y, or 0),
    two triangles per cell, counter-clockwise seen from +z."""
    xs = np.linspace(0.0, size, n)
    x, y = np.meshgrid(xs, xs)
    z = np.zeros_like(x) if height is None else height(x, y)
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    triangles = []
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            triangles += [(a, a + 1, a + n + 1), (a, a + n + 1, a + n)]
    return points, np.asarray(triangles, np.int32)


def areas(points, triangles):
    a, b, c = (points[triangles[:, k]] for k in range(3))
    return 0.5 * np.cross(b - a, c - a)


def test_the_split_is_the_same_surface():
    points, triangles = grid(height=lambda x, y: 0.3 * x * y)
    normals = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    split_points, split_normals, split = least_squares.centroid_split(points, normals, triangles)
    assert len(split_points) == len(points) + len(triangles) and len(split) == 3 * len(triangles)
    assert np.allclose(split_points[:len(points)], points)
    assert np.allclose(split_points[len(points):], points[triangles].mean(axis=1))
    # each triangle's three parts add up to it, oriented alike
    assert np.allclose(areas(split_points, split).reshape(-1, 3, 3).sum(axis=1), areas(points, triangles))
    assert np.allclose(np.linalg.norm(split_normals, axis=1), 1.0)


def test_the_samples_integrate_quadratics_exactly():
    rng = np.random.default_rng(3)
    points, triangles = grid(n=4, height=lambda x, y: 0.2 * np.sin(x + 2 * y))
    sample_triangles, barycentric, weights = least_squares.samples(points, triangles)
    where = np.einsum("sk,skd->sd", barycentric, points[sample_triangles])
    for _ in range(5):
        q = rng.normal(size=10)

        def quadratic(p):
            x, y, z = p.T
            return q[0] + q[1] * x + q[2] * y + q[3] * z + q[4] * x * x + q[5] * y * y + q[6] * z * z \
                + q[7] * x * y + q[8] * y * z + q[9] * z * x
        # exact over a triangle: its area times the mean of q at its edges' midpoints
        a, b, c = (points[triangles[:, k]] for k in range(3))
        exact = np.sum(np.linalg.norm(areas(points, triangles), axis=1) *
                       (quadratic((a + b) / 2) + quadratic((b + c) / 2) + quadratic((c + a) / 2)) / 3.0)
        assert np.dot(weights, quadratic(where)) == pytest.approx(exact, rel=1e-12)


def test_a_loose_vertex_keeps_a_little_weight():
    points, triangles = grid(n=3)
    points = np.concatenate([points, [[5.0, 5.0, 5.0]]])
    weights = least_squares.samples(points, triangles)[2]
    assert 0.0 < weights[len(points) - 1] < 0.01 * weights[:len(points) - 1].mean()


def test_gradient_jumps_vanish_for_a_linear_signal_and_not_across_a_fold():
    points, triangles = grid(n=4)
    rows, coefficients = least_squares.gradient_jumps(points, triangles)
    assert len(rows) == 33 - 12      # a 3 x 3-cell grid has 33 edges, 12 of them on its border
    linear = 2.0 * points[:, 0] - 0.7 * points[:, 1] + 0.1
    assert np.abs(np.sum(coefficients * linear[rows], axis=1)).max() < 1e-12
    kink = np.abs(points[:, 0] - 0.5)
    assert np.abs(np.sum(coefficients * kink[rows], axis=1)).max() > 0.3
    # a hard edge along x = 1/3: the triangles left of it have copies of its 4 vertices, so the
    # 3 edges along it are no longer shared and get no row
    line = np.flatnonzero(np.isclose(points[:, 0], 1.0 / 3.0))
    copies = dict(zip(line, len(points) + np.arange(len(line))))
    parted = triangles.copy()
    for t in np.flatnonzero(points[triangles].mean(axis=1)[:, 0] < 1.0 / 3.0):
        parted[t] = [copies.get(v, v) for v in parted[t]]
    parted_rows, _ = least_squares.gradient_jumps(np.concatenate([points, points[line]]), parted)
    assert len(parted_rows) == len(rows) - 3


def test_an_obtuse_sliver_weighs_no_more_than_a_good_triangle():
    # Edge (0, 1) shared by a right triangle and an obtuse sliver whose apex projects 100 edge
    # lengths beyond it: the row's coefficients stay of order one.
    points = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [100.0, -0.01, 0.0]])
    rows, coefficients = least_squares.gradient_jumps(points, np.array([[0, 1, 2], [1, 0, 3]]))
    assert len(rows) == 1 and np.abs(coefficients).max() == 1.0
    linear = 0.4 * points[:, 0] + 2.0 * points[:, 1]
    assert abs(np.sum(coefficients * linear[rows])) < 1e-12


def test_only_the_linear_arrays_are_fitted():
    assert least_squares.applies(methods.get("prt_diffuse"))
    assert least_squares.applies(methods.get("prt_matrix"))
    assert not least_squares.applies(methods.get("msd_visibility"))
    assert not least_squares.applies(methods.get("unshadowed"))


def test_a_fit_follows_the_shadow_between_the_vertices(sdnative):
    """A coarse floor partly under a slab: the ambient occlusion inside its triangles (baked there
    directly) is matched better by the interpolated fit than by the values at the vertices."""
    points, triangles = grid(n=4, size=3.0)
    normals = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    slab, slab_triangles = grid(n=2, size=1.4)
    slab = slab + [0.8, 0.6, 0.35]
    occluders = {"occluder_vertices": slab, "occluder_triangles": slab_triangles}
    kwargs = dict(rays=1024, seed=1, transfer_order=2, **occluders)
    plain = sdnative.bake_transfer(points, normals, triangles, **kwargs)
    split = least_squares.centroid_split(points, normals, triangles)
    fitted = least_squares.fit(sdnative, dict(sdnative.bake_transfer(*split, **kwargs)), points, triangles)
    assert fitted["ambient_occlusion"].shape == (len(points),)
    assert fitted["transfer"].shape == plain["transfer"].shape and len(fitted["normals"]) == len(points)
    assert fitted["ambient_occlusion"].min() >= 0.0 and fitted["ambient_occlusion"].max() <= 1.0
    # the truth inside: AO at a dense set of points of every triangle
    rng = np.random.default_rng(0)
    barycentric = rng.dirichlet(np.ones(3), size=(len(triangles), 12))
    inside = np.einsum("tsk,tkd->tsd", barycentric, points[triangles]).reshape(-1, 3)
    truth = sdnative.bake_transfer(inside, np.tile([0.0, 0.0, 1.0], (len(inside), 1)),
                                   np.zeros((0, 3), np.int32), rays=1024, seed=2,
                                   occluder_vertices=np.concatenate([points, slab]),
                                   occluder_triangles=np.concatenate([triangles, slab_triangles + len(points)]
                                                                     ).astype(np.int32))["ambient_occlusion"]

    def error(values):
        interpolated = np.einsum("tsk,tk->ts", barycentric, values[triangles]).ravel()
        return np.sqrt(np.mean((interpolated - truth) ** 2))
    assert error(fitted["ambient_occlusion"]) < 0.8 * error(np.asarray(plain["ambient_occlusion"]))


@pytest.mark.parametrize("key,channels", [("transfer", 1 + 6), ("product_matrices", 6)])
def test_every_array_is_fitted_in_one_system_and_keeps_its_shape(sdnative, key, channels):
    # Linear signals come back exactly, each in its own shape, from one factorization; with M,
    # AO is M_00,00 (its first channel), not a channel of its own.
    points, triangles = grid(n=4)
    split_points = least_squares.centroid_split(points, np.tile([0.0, 0.0, 1.0], (len(points), 1)),
                                                triangles)[0]
    linear = 0.3 * split_points[:, 0] - 0.2 * split_points[:, 1] + 0.5   # within [0, 1], as AO
    baked = {"ambient_occlusion": linear, key: np.einsum("s,ij->sij", linear, [[1.0, 2.0]] * 3),
             "normals": split_points, "ray_origins": split_points, "fallback_normals": np.zeros(0, int)}
    calls = []

    class Counted:
        @staticmethod
        def fit_vertex_values(*args, **kwargs):
            calls.append(args[4].shape)
            return sdnative.fit_vertex_values(*args, **kwargs)
    out = least_squares.fit(Counted, baked, points, triangles)
    assert calls == [(len(split_points), channels)]
    at_vertices = linear[:len(points)]
    np.testing.assert_allclose(out["ambient_occlusion"], at_vertices, atol=1e-9)
    assert out[key].shape == (len(points), 3, 2)
    np.testing.assert_allclose(out[key][:, 2, 1], 2.0 * at_vertices, atol=1e-9)


def test_the_predicted_fit_time_counts_the_channels_fit_solves(sdnative):
    s = 5
    assert least_squares.channels({"ambient_occlusion": np.zeros(s), "transfer": np.zeros((s, 25))}) == 26
    assert least_squares.channels({"ambient_occlusion": np.zeros(s), "product_matrices": np.zeros((s, 25, 9))}) == 225
    assert least_squares.channels({"ambient_occlusion": np.zeros(s)}) == 1
    small = least_squares.predicted_seconds(sdnative, 10000, 26)
    assert 0.0 < small < least_squares.predicted_seconds(sdnative, 1000000, 26)


def test_a_cancel_during_the_fit_is_not_taken_for_a_singular_system(sdnative):
    points, triangles = grid(n=3)
    split = least_squares.centroid_split(points, np.tile([0.0, 0.0, 1.0], (len(points), 1)), triangles)
    baked = dict(sdnative.bake_transfer(*split, rays=16))
    with pytest.raises(sdnative.BakeCancelled):
        least_squares.fit(sdnative, baked, points, triangles, progress=lambda done, total: False)


def test_a_singular_fit_keeps_the_baked_values():
    class Singular:
        @staticmethod
        def fit_vertex_values(*args, **kwargs):
            raise RuntimeError("singular")
    points, triangles = grid(n=3)
    baked = {"ambient_occlusion": np.linspace(0.0, 1.0, len(points) + len(triangles)),
             "normals": np.zeros((len(points) + len(triangles), 3)),
             "ray_origins": np.zeros((len(points) + len(triangles), 3)),
             "fallback_normals": np.array([1, len(points) + 2])}
    out = least_squares.fit(Singular, baked, points, triangles)
    assert np.array_equal(out["ambient_occlusion"], baked["ambient_occlusion"][:len(points)])
    assert out["least_squares_skipped"] == "singular" and out["fallback_normals"].tolist() == [1]
    assert len(out["normals"]) == len(points)
