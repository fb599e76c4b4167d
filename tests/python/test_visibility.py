"""The binding contract of the visibility / transfer bake (sdnative.bake_transfer, bake_visibility,
vertex_ray_directions, BakeCancelled): the arrays it returns, progress on the calling thread,
cancellation, the GIL and bad input, with one real computation each. The bake's math (closed forms on
a plane, a box, a convex sphere; determinism; designs) is tested in tests/cpp/bake.

Exact checks (EXACT) recompute the outputs from the recorded ray bits (return_rays=True) and
vertex_ray_directions with plain numpy.
"""
import math
import threading

import numpy as np
import pytest

from sd_test_utils import EXACT, sh_count

# ---- meshes ----

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


# ---- what the bake returns ----

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


def test_offset_origins_false_starts_rays_along_the_normal(sd):
    # A cube standing on a floor: a bottom corner's averaged normal points into the floor, so
    # without the offset into its faces (the benchmarks' baseline) its rays start below the floor
    # and see the lower half-space (1/2) instead of the upper one less the cube's octant (3/8).
    v, t = cube(1.0)
    v[:, 2] += 1.0
    t = t[:, ::-1]   # wound outwards (cube's faces face in)
    n = v - v.mean(axis=0)
    floor_v = np.array([[-50.0, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]])
    floor_t = np.array([[0, 1, 2], [0, 2, 3]])
    bottom = v[:, 2] == 0.0
    for offset, expected in ((True, 0.375), (False, 0.5)):
        out = sd.bake_transfer(v, n, t, 4096, occluder_vertices=floor_v, occluder_triangles=floor_t,
                               offset_origins=offset)
        np.testing.assert_allclose(out["ambient_occlusion"][bottom], expected, atol=1e-2)
        along_normal = np.cross(out["ray_origins"] - v, n)[bottom]
        assert np.all(np.abs(along_normal) < 1e-9) == (not offset)


def test_outputs_equal_direct_sums_over_the_rays(sd):
    v, n, t = bumpy_sphere(1)
    rays = 300
    out = sd.bake_transfer(v, n, t, rays, seed=6, visibility_order=2, product_orders=(3, 2), transfer_order=3,
                           return_rays=True)
    assert set(out) == {"ambient_occlusion", "visibility", "product_matrices", "transfer", "ray_visibility", "rays",
                        "seed", "ray_origins", "seconds", "setup_seconds", "fallback_normals", "normals"}
    assert out["visibility"].shape == (len(v), 9) and out["transfer"].shape == (len(v), 16)
    assert out["product_matrices"].shape == (len(v), 16, 9) and out["product_matrices"].dtype == np.float64
    assert out["ray_visibility"].dtype == np.bool_ and out["ray_visibility"].shape == (len(v), rays)
    assert (out["rays"], out["seed"]) == (rays, 6) and out["seconds"] > 0.0
    assert out["ray_origins"].shape == (len(v), 3) and out["ray_origins"].dtype == np.float64
    offsets = np.einsum("ij,ij->i", out["ray_origins"] - v, n / np.linalg.norm(n, axis=1)[:, None])
    assert np.all(offsets > 0.0)  # each vertex's rays start outside the surface
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
    # s' above s: the rows' and the columns' turns of different orders
    wide = sd.bake_transfer(v, n, t, rays, seed=6, product_orders=(2, 4), return_rays=True)
    for i in range(len(v)):
        y = sd.sh_basis(4, sd.vertex_ray_directions(rays, 6, i)[wide["ray_visibility"][i]])
        np.testing.assert_allclose(wide["product_matrices"][i], y[:, :9].T @ y / rays, rtol=0, atol=EXACT)


def test_threads_change_nothing(sd):
    v, n, t = bumpy_sphere(2)
    kwargs = dict(seed=99, visibility_order=2, product_orders=(2, 1), transfer_order=2, design_orders=(2, 1),
                  return_rays=True)
    runs = [sd.bake_transfer(v, n, t, 200, threads=k, **kwargs) for k in (1, 2)]
    for other in runs[1:]:
        for key, value in runs[0].items():
            if key not in ("seconds", "setup_seconds"):
                np.testing.assert_array_equal(other[key], value, err_msg=key)


def test_bake_visibility_is_the_transfer_bakes_visibility(sd):
    v, n, t = bumpy_sphere(1)
    gv = np.array([[-5, -5, -1.2], [5, -5, -1.2], [5, 5, -1.2], [-5, 5, -1.2]])
    gt = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    vis = sd.bake_visibility(v, n, t, 2, 128, seed=5, occluder_vertices=gv, occluder_triangles=gt)
    out = sd.bake_transfer(v, n, t, 128, seed=5, visibility_order=2, occluder_vertices=gv, occluder_triangles=gt)
    assert vis.shape == (len(v), 9) and vis.dtype == np.float64
    np.testing.assert_array_equal(vis, out["visibility"])


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
    # (0, 0) while the scene is built, then (done, len(v)) from before the first vertex
    rays = next(i for i, report in enumerate(reports) if report[1] > 0)
    assert reports[0] == (0, 0) and set(reports[:rays]) == {(0, 0)} and reports[rays] == (0, len(v))
    assert reports[-1] == (len(v), len(v)) and all(total == len(v) for _, total in reports[rays:])
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


def test_zero_and_non_finite_normals_get_a_fallback(sd):
    # They used to fail the whole bake; now they get their faces' normal and are listed.
    normals = with_value(with_value(N, 2, 0.0), (4, 2), -np.inf)
    repaired = sd.bake_transfer(V, normals, T, 64, transfer_order=1)
    assert repaired["fallback_normals"].tolist() == [2, 4]
    assert repaired["fallback_normals"].dtype == np.int64
    reference = sd.bake_transfer(V, N, T, 64, transfer_order=1)
    assert reference["fallback_normals"].tolist() == []
    np.testing.assert_allclose(reference["normals"], N / np.linalg.norm(N, axis=1)[:, None], atol=1e-15)
    np.testing.assert_array_equal(repaired["normals"][[0, 1, 3]], reference["normals"][[0, 1, 3]])
    assert np.all(np.sum(repaired["normals"][[2, 4]] * reference["normals"][[2, 4]], axis=1) > 0.9)
    np.testing.assert_allclose(repaired["transfer"], reference["transfer"], atol=0.1)


def test_degenerate_triangles_and_probes_are_fine(sd):
    t = np.vstack([T, [[0, 0, 1], [2, 2, 2]]])
    assert sd.bake_transfer(V, N, t, 32)["ambient_occlusion"].shape == (12,)
    probes = sd.bake_transfer(V, N, np.zeros((0, 3), dtype=np.int32), 32)
    np.testing.assert_array_equal(probes["ambient_occlusion"], 1.0)
