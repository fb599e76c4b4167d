"""Tests of the visibility / transfer bake: sdnative.bake_transfer, bake_visibility, BakeCancelled.

Exact checks (EXACT) recompute the outputs from the recorded ray bits (return_rays=True) and
vertex_ray_directions with plain numpy; Monte-Carlo ones compare with closed forms within the error
of the randomly rotated spherical Fibonacci rule at the ray count used.
"""
import math
import threading

import numpy as np
import pytest

from sd_test_utils import EXACT, sh_count, sh_index

# The error of a randomly rotated 4096-point Fibonacci rule on the hemisphere indicator (measured over
# 3000 rotations: <= 5.2e-3 per SH coefficient up to l = 8, <= 2.5e-3 for the escaping fraction).
FIBONACCI_4096 = 8e-3
FRACTION_4096 = 4e-3


# ---- meshes ----

def plane_grid(half=10.0, cells=20):
    """A flat square grid in z = 0 with normals +z."""
    s = np.linspace(-half, half, cells + 1)
    x, y = np.meshgrid(s, s)
    vertices = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    normals = np.tile([0.0, 0.0, 1.0], (len(vertices), 1))
    at = lambda i, j: j * (cells + 1) + i  # noqa: E731
    triangles = []
    for j in range(cells):
        for i in range(cells):
            triangles += [(at(i, j), at(i + 1, j), at(i + 1, j + 1)), (at(i, j), at(i + 1, j + 1), at(i, j + 1))]
    return vertices, normals, np.array(triangles, dtype=np.int64)


def icosphere(levels):
    """Unit icosphere; normals are the radial directions."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    vertices = [np.array(p, float) / np.linalg.norm(p) for p in v]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
             (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        cache = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = vertices[a] + vertices[b]
                vertices.append(p / np.linalg.norm(p))
                cache[key] = len(vertices) - 1
            return cache[key]

        finer = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            finer += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = finer
    vertices = np.array(vertices)
    return vertices, vertices.copy(), np.array(faces, dtype=np.int64)


def bumpy_sphere(levels):
    """An icosphere with bumps (real self-occlusion); area-weighted face normals."""
    v, _, f = icosphere(levels)
    v = v * (1.0 + 0.25 * np.sin(5 * v[:, 0]) * np.sin(4 * v[:, 1] + 1) * np.sin(3 * v[:, 2]))[:, None]
    n = np.zeros_like(v)
    face_n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    for k in range(3):
        np.add.at(n, f[:, k], face_n)
    return v, n / np.linalg.norm(n, axis=1, keepdims=True), f


def cube(h):
    v = np.array([[h if i & 1 else -h, h if i & 2 else -h, h if i & 4 else -h] for i in range(8)], dtype=float)
    t = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, t


def hemisphere_coefficients(order):
    """SH coefficients of the upper-hemisphere indicator: 1/2 sqrt(2l+1) int_0^1 P_l, m = 0 only."""
    out = np.zeros(sh_count(order))
    p0 = [np.polynomial.legendre.legval(0.0, [0] * n + [1]) for n in range(order + 2)]
    out[0] = 0.5
    for l in range(1, order + 1):
        out[sh_index(l, 0)] = 0.5 * math.sqrt(2 * l + 1) * (p0[l - 1] - p0[l + 1]) / (2 * l + 1)
    return out


# ---- the open plane ----

@pytest.fixture(scope="module")
def plane():
    v, n, t = plane_grid()
    interior = np.flatnonzero((np.abs(v[:, 0]) <= 2) & (np.abs(v[:, 1]) <= 2))
    return v, n, t, interior


def test_open_plane_visibility_is_the_hemisphere_indicator(sd, plane):
    v, n, t, interior = plane
    out = sd.bake_transfer(v, n, t, 4096, seed=2, visibility_order=8)
    assert set(out) == {"visibility", "ambient_occlusion", "rays", "seed", "ray_origins", "seconds"}
    assert out["visibility"].shape == (len(v), 81)
    vis = out["visibility"][interior]
    np.testing.assert_allclose(out["ambient_occlusion"][interior], 0.5, atol=FRACTION_4096)
    np.testing.assert_array_equal(vis[:, 0], out["ambient_occlusion"][interior])
    np.testing.assert_allclose(vis, np.tile(hemisphere_coefficients(8), (len(interior), 1)), atol=FIBONACCI_4096)
    assert abs(hemisphere_coefficients(1)[2] - math.sqrt(3) / 4) < 1e-15
    assert out["ray_origins"].shape == (len(v), 3) and out["ray_origins"].dtype == np.float64
    assert np.all(out["ray_origins"][:, 2] > 0.0)  # above the plane the vertices lie in


def test_open_plane_rays_above_escape_and_rays_below_are_blocked(sd, plane):
    v, n, t, interior = plane
    out = sd.bake_transfer(v, n, t, 1024, seed=4, return_rays=True)
    bits = out["ray_visibility"]
    assert bits.dtype == np.bool_ and bits.shape == (len(v), 1024)
    np.testing.assert_array_equal(bits.mean(axis=1), out["ambient_occlusion"])
    for i in interior:
        dirs = sd.vertex_ray_directions(1024, 4, int(i))
        assert np.all(bits[i][dirs[:, 2] > 0])
        assert not np.any(bits[i][dirs[:, 2] < -1e-3])  # well below the horizon: they meet the grid


def test_open_plane_transfer(sd, plane):
    v, n, t, interior = plane
    rays = 4096
    out = sd.bake_transfer(v, n, t, rays, seed=8, transfer_order=4, return_rays=True)
    tr = out["transfer"]
    assert tr.shape == (len(v), 25)
    w_hat = sd.zonal_coefficients("lambert", 1.0, 4)
    expected = np.zeros(25)
    for l in range(5):
        expected[sh_index(l, 0)] = w_hat[l] * math.sqrt(2 * l + 1)
    for i in interior:
        dirs = sd.vertex_ray_directions(rays, 8, int(i))
        hit = out["ray_visibility"][i]
        direct = (4 * np.maximum(0, dirs[hit, 2]))[:, None] * sd.sh_basis(4, dirs[hit])
        np.testing.assert_allclose(tr[i], direct.sum(axis=0) / rays, rtol=0, atol=EXACT)
        assert tr[i, 0] == pytest.approx(1.0, abs=1e-3)
        np.testing.assert_allclose(tr[i], expected, atol=1e-3)


# ---- closed box and convex object ----

def test_points_inside_a_closed_box_see_nothing(sd):
    v = np.array([[-0.1, -0.1, 0.0], [0.1, -0.1, 0.05], [0.0, 0.1, -0.05]])
    n = np.array([[0, 0, 1.0], [0, 1, 1], [1, 0, 1]])
    t = np.array([[0, 1, 2]])
    cv, ct = cube(1.0)
    out = sd.bake_transfer(v, n, t, 512, visibility_order=3, product_orders=(2, 2), transfer_order=2,
                           design_orders=(2, 1), occluder_vertices=cv, occluder_triangles=ct)
    for key in ("visibility", "ambient_occlusion", "product_matrices", "transfer"):
        assert not np.any(out[key]), key
    np.testing.assert_array_equal(out["design_offsets"], [0, 0, 0, 0])
    assert out["design_offsets"].dtype == np.int64
    assert out["design_nodes"].shape == (0, 3) and out["design_weights"].shape == (0,)
    assert out["design_degree"] == 3
    free = sd.bake_transfer(v, n, t, 512)
    assert np.all(free["ambient_occlusion"] > 0.3)


def test_convex_icosphere_has_nothing_above_the_tangent_plane(sd):
    v, n, t = icosphere(4)
    out = sd.bake_transfer(v, n, t, 512, seed=3, return_rays=True)
    for i in range(0, len(v), 17):
        dirs = sd.vertex_ray_directions(512, 3, i)
        above = dirs @ n[i] > 0
        assert np.all(out["ray_visibility"][i][above])
        assert out["ambient_occlusion"][i] >= above.mean()
    # Rays slightly below the horizon pass the neighbouring facets (about 0.02 more at this level).
    assert np.all(np.abs(out["ambient_occlusion"] - 0.515) < 0.035)


# ---- exactness, consistency, determinism ----

def test_outputs_equal_direct_sums_over_the_rays(sd):
    v, n, t = bumpy_sphere(1)
    rays = 300
    out = sd.bake_transfer(v, n, t, rays, seed=6, visibility_order=2, product_orders=(3, 2), transfer_order=3,
                           return_rays=True)
    assert out["product_matrices"].shape == (len(v), 16, 9)
    assert out["ambient_occlusion"].min() < 0.45
    for i in range(len(v)):
        dirs = sd.vertex_ray_directions(rays, 6, i)
        hit = out["ray_visibility"][i]
        y = sd.sh_basis(3, dirs[hit])
        np.testing.assert_allclose(out["visibility"][i], y[:, :9].sum(0) / rays, rtol=0, atol=EXACT)
        np.testing.assert_allclose(out["product_matrices"][i], y.T @ y[:, :9] / rays, rtol=0, atol=EXACT)
        cosine = 4 * np.maximum(0, dirs[hit] @ n[i])
        np.testing.assert_allclose(out["transfer"][i], cosine @ y / rays, rtol=0, atol=EXACT)
        assert out["ambient_occlusion"][i] == pytest.approx(hit.sum() / rays, abs=EXACT)


def test_product_matrix_column_zero_is_the_visibility(sd):
    v, n, t = bumpy_sphere(1)
    out = sd.bake_transfer(v, n, t, 256, visibility_order=3, product_orders=(2, 3))
    m, vis = out["product_matrices"], out["visibility"]
    np.testing.assert_allclose(m[:, :, 0], vis[:, :9], rtol=0, atol=EXACT)
    np.testing.assert_allclose(m[:, :, :9], np.transpose(m[:, :, :9], (0, 2, 1)), rtol=0, atol=EXACT)


def test_same_seed_same_result_for_any_thread_count(sd):
    v, n, t = bumpy_sphere(2)
    kwargs = dict(seed=99, visibility_order=2, product_orders=(2, 1), transfer_order=2, design_orders=(2, 1),
                  return_rays=True)
    runs = [sd.bake_transfer(v, n, t, 200, threads=k, **kwargs) for k in (1, 2, 3, 0)]
    for other in runs[1:]:
        for key, value in runs[0].items():
            if key != "seconds":
                np.testing.assert_array_equal(other[key], value, err_msg=key)
    different = sd.bake_transfer(v, n, t, 200, **dict(kwargs, seed=100))
    assert not np.array_equal(different["ray_visibility"], runs[0]["ray_visibility"])


def test_bake_visibility_is_the_transfer_bakes_visibility(sd):
    v, n, t = bumpy_sphere(1)
    gv = np.array([[-5, -5, -1.2], [5, -5, -1.2], [5, 5, -1.2], [-5, 5, -1.2]])
    gt = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    vis = sd.bake_visibility(v, n, t, 2, 128, seed=5, occluder_vertices=gv, occluder_triangles=gt)
    out = sd.bake_transfer(v, n, t, 128, seed=5, visibility_order=2, occluder_vertices=gv, occluder_triangles=gt)
    np.testing.assert_array_equal(vis, out["visibility"])
    free = sd.bake_visibility(v, n, t, 2, 128, seed=5)
    assert vis[:, 0].sum() < free[:, 0].sum() - 1.0  # the ground occludes


# ---- designs ----

def test_designs_reproduce_the_ray_measure(sd):
    v, n, t = bumpy_sphere(1)
    rays, degree = 400, 6
    out = sd.bake_transfer(v, n, t, rays, seed=1, design_orders=(4, 2), return_rays=True)
    assert out["design_degree"] == degree
    off, nodes, weights = out["design_offsets"], out["design_nodes"], out["design_weights"]
    assert off.shape == (len(v) + 1,) and off[0] == 0 and off[-1] == len(nodes) == len(weights)
    assert np.all(out["design_residuals"] <= sd.DESIGN_TOLERANCE)
    assert np.all(weights > 0)
    for i in range(len(v)):
        a, b = off[i], off[i + 1]
        assert 0 < b - a <= sh_count(degree)
        assert weights[a:b].sum() == pytest.approx(out["ambient_occlusion"][i], abs=EXACT)
        dirs = sd.vertex_ray_directions(rays, 1, i)
        target = sd.sh_basis(degree, dirs[out["ray_visibility"][i]]).sum(0) / rays
        moments = weights[a:b] @ sd.sh_basis(degree, nodes[a:b])
        np.testing.assert_allclose(moments, target, rtol=0, atol=2 * sd.DESIGN_TOLERANCE)


# ---- progress, cancellation, the GIL ----

def test_progress_reports_from_the_calling_thread(sd):
    v, n, t = bumpy_sphere(3)
    reports, idents = [], set()

    def progress(done, total):
        reports.append((done, total))
        idents.add(threading.get_ident())

    sd.bake_transfer(v, n, t, 256, design_orders=(2, 2), progress=progress)
    assert reports[0] == (0, len(v)) and reports[-1] == (len(v), len(v))
    assert all(b[0] >= a[0] for a, b in zip(reports, reports[1:]))
    assert idents == {threading.get_ident()}


def test_progress_returning_false_raises_bake_cancelled(sd):
    v, n, t = bumpy_sphere(1)
    assert issubclass(sd.BakeCancelled, RuntimeError)
    with pytest.raises(sd.BakeCancelled, match="cancelled"):
        sd.bake_transfer(v, n, t, 64, visibility_order=1, progress=lambda done, total: False)
    calls = []

    def stop_later(done, total):
        calls.append(done)
        return len(calls) < 2

    with pytest.raises(sd.BakeCancelled):
        sd.bake_visibility(v, n, t, 1, 64, progress=stop_later)
    assert len(calls) == 2


def test_progress_exception_cancels_and_propagates(sd):
    v, n, t = bumpy_sphere(3)

    class Stop(Exception):
        pass

    def progress(done, total):
        if done > 0:
            raise Stop("from the callback")

    with pytest.raises(Stop, match="from the callback"):
        sd.bake_transfer(v, n, t, 256, design_orders=(2, 2), progress=progress)


def test_the_gil_is_released_during_the_bake(sd):
    v, n, t = bumpy_sphere(3)
    result = {}
    worker = threading.Thread(target=lambda: result.update(sd.bake_transfer(v, n, t, 256, design_orders=(2, 2))))
    count = 0
    worker.start()
    while worker.is_alive():
        count += 1
    worker.join()
    assert "design_nodes" in result
    assert count > 100000, "the main thread could not run while the bake worked"


# ---- bad input ----

V, N, T = icosphere(0)


def bad(**changes):
    args = dict(vertices=V, normals=N, triangles=T, rays=16)
    args.update(changes)
    return args


def with_value(array, index, value):
    array = np.array(array, dtype=float if array.dtype.kind == "f" else array.dtype)
    array[index] = value
    return array


@pytest.mark.parametrize("args,match", [
    (bad(vertices=with_value(V, (3, 1), np.nan)), "vertices"),
    (bad(vertices=with_value(V, (0, 0), np.inf)), "vertices"),
    (bad(normals=with_value(N, 2, 0.0)), "zero"),
    (bad(normals=with_value(N, (2, 2), -np.inf)), "normals"),
    (bad(triangles=with_value(T, (4, 1), 12)), "out of range"),
    (bad(triangles=with_value(T, (0, 2), -1)), "out of range"),
    (bad(triangles=T.astype(float)), "integers"),
    (bad(triangles=T[:, :2]), "shape"),
    (bad(vertices=V[:, :2]), "shape"),
    (bad(normals=N[:5]), "normals"),
    (bad(vertices=np.zeros((0, 3)), normals=np.zeros((0, 3)), triangles=np.zeros((0, 3), dtype=int)), "empty"),
    (bad(rays=0), "rays"),
    (bad(rays=-3), "rays"),
    (bad(visibility_order=9), "visibility_order"),
    (bad(visibility_order=-2), "visibility_order"),
    (bad(transfer_order=17), "transfer_order"),
    (bad(product_orders=(17, 2)), "product_orders"),
    (bad(product_orders=(2, 9)), "product_orders"),
    (bad(design_orders=(2, -1)), "design_orders"),
    (bad(design_orders=(2, 9)), "design_orders"),
    (bad(threads=-1), "threads"),
    (bad(progress=3), "progress"),
    (bad(occluder_vertices=cube(1)[0]), "together"),
    (bad(occluder_vertices=cube(1)[0], occluder_triangles=cube(1)[1] + 1), "out of range"),
    (bad(occluder_vertices=with_value(cube(1)[0], (1, 1), np.nan), occluder_triangles=cube(1)[1]), "occluder"),
])
def test_bad_input_raises_value_error(sd, args, match):
    with pytest.raises(ValueError, match=match):
        sd.bake_transfer(**args)


def test_bad_input_to_bake_visibility(sd):
    for order in (-1, 9):
        with pytest.raises(ValueError, match="order"):
            sd.bake_visibility(V, N, T, order, 16)
    with pytest.raises(ValueError, match="rays"):
        sd.bake_visibility(V, N, T, 2, 0)
    with pytest.raises(ValueError, match="rays"):
        sd.vertex_ray_directions(0, 0, 0)


def test_degenerate_triangles_and_probes_are_fine(sd):
    t = np.vstack([T, [[0, 0, 1], [2, 2, 2]]])
    assert sd.bake_transfer(V, N, t, 32)["ambient_occlusion"].shape == (12,)
    probes = sd.bake_transfer(V, N, np.zeros((0, 3), dtype=np.int32), 32)
    np.testing.assert_array_equal(probes["ambient_occlusion"], 1.0)


def test_docstrings(sd):
    for name in ("bake_transfer", "bake_visibility", "vertex_ray_directions", "BakeCancelled"):
        assert getattr(sd, name).__doc__ and len(getattr(sd, name).__doc__) > 40, name
