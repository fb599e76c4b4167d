"""The binding contract of the live shading's ray BVH (sdnative.ray_bvh, ray_bvh_occluded): the
arrays it returns, its walk against every triangle tested with numpy (float64: rays that graze an
edge may differ from float32, so those are left out) and bad input. The layout's invariants are
tested in tests/cpp/shading/test_ray_bvh.cpp; the shader's walk of it against Cycles in
blender_tests/test_source_shadows.py (step 8)."""
import numpy as np
import pytest


def soup(count, seed):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0.0, 1.0, (count, 1, 3))
    vertices = (centres + rng.uniform(-0.08, 0.08, (count, 3, 3))).reshape(-1, 3)
    return vertices, np.arange(3 * count).reshape(-1, 3)


def brute_force(vertices, triangles, origins, directions):
    """(hit, margin) per ray with every triangle's test in float64; margin: how far the nearest
    barycentric test or t is from deciding otherwise."""
    p0, p1, p2 = (vertices[triangles[:, k]] for k in range(3))
    e1, e2 = p1 - p0, p2 - p0
    hits, margins = [], []
    for o, d in zip(origins, directions):
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        s = o - p0
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.einsum("ij,ij->i", s, p) / det
            q = np.cross(s, e1)
            v = (q @ d) / det
            t = np.einsum("ij,ij->i", e2, q) / det
        inside = np.minimum.reduce([u, v, 1.0 - u - v, t])
        hits.append(bool(np.any(inside > 0.0)))
        margins.append(float(np.nanmin(np.abs(inside))))
    return np.array(hits), np.array(margins)


def test_walk_answers_as_every_triangle(sd):
    vertices, triangles = soup(1500, 1)
    bvh = sd.ray_bvh(vertices, triangles)
    assert bvh["nodes"].dtype == np.float32 and bvh["nodes"].shape[1] == 8
    assert bvh["triangles"].shape == (1500, 12)
    assert sorted(bvh["order"]) == list(range(1500))
    # each row holds its triangle's corners
    rows = bvh["triangles"].reshape(-1, 3, 4)[:, :, :3].astype(np.float64)
    corners = vertices[triangles[bvh["order"]]]
    np.testing.assert_allclose(rows[:, 0], corners[:, 0], atol=1e-6)
    np.testing.assert_allclose(rows[:, 1], corners[:, 1] - corners[:, 0], atol=1e-6)
    rng = np.random.default_rng(2)
    origins = rng.uniform(0.0, 1.0, (3000, 3))
    directions = rng.normal(size=(3000, 3))
    walked = sd.ray_bvh_occluded(bvh["nodes"], bvh["triangles"], origins, directions)
    expected, margin = brute_force(vertices, triangles, origins, directions)
    clear = margin > 1e-5
    assert clear.sum() > 2900
    np.testing.assert_array_equal(walked[clear], expected[clear])
    assert 300 < walked.sum() < 2700


def test_empty_and_degenerate(sd):
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    none = sd.ray_bvh(square, np.zeros((0, 3), int))
    assert none["nodes"].shape == (0, 8) and none["triangles"].shape == (0, 12)
    flat = sd.ray_bvh(square, np.array([[0, 1, 2], [0, 0, 1]]))
    assert list(flat["order"]) == [0]   # the zero-area triangle is left out
    hit = sd.ray_bvh_occluded(flat["nodes"], flat["triangles"], np.array([[0.8, 0.2, 1.0], [0.2, 0.8, 1.0]]),
                              np.array([[0, 0, -1.0], [0, 0, -1.0]]))
    assert list(hit) == [True, False]


@pytest.mark.parametrize("call, match", [
    (lambda sd: sd.ray_bvh(np.zeros((3, 3)), np.array([[0, 1, 3]])), "triangles"),
    (lambda sd: sd.ray_bvh(np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]]), np.array([[0, 1, 2]])), "vertices"),
    (lambda sd: sd.ray_bvh(np.zeros((3, 2)), np.array([[0, 1, 2]])), "vertices"),
    (lambda sd: sd.ray_bvh_occluded(np.zeros((1, 7), np.float32), np.zeros((0, 12), np.float32),
                                    np.zeros((1, 3)), np.ones((1, 3))), "nodes"),
    (lambda sd: sd.ray_bvh_occluded(np.array([[0, 0, 0, 5, 1, 1, 1, 6]], np.float32), np.zeros((0, 12), np.float32),
                                    np.zeros((1, 3)), np.ones((1, 3))), "not a node"),
    (lambda sd: sd.ray_bvh_occluded(np.zeros((0, 8), np.float32), np.zeros((0, 12), np.float32),
                                    np.zeros((2, 3)), np.ones((1, 3))), "same length"),
])
def test_bad_input(sd, call, match):
    with pytest.raises(ValueError, match=match):
        call(sd)
