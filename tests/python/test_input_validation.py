"""Bad input raises ValueError (messages checked loosely)."""
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

NAN = float("nan")
INF = float("inf")
GOOD_DIRS = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
GOOD_WEIGHTS = np.array([1.0, 0.5, 0.25])


@pytest.mark.parametrize("lmax,dirs,match", [
    (-1, [0.0, 0.0, 1.0], "lmax"),
    (65, [0.0, 0.0, 1.0], "lmax"),
    (2, [0.0, 1.0], "shape"),
    (2, np.zeros((4, 2)), "shape"),
    (2, np.ones((2, 3, 3)), "shape"),
    (2, np.ones((3, 4)), "shape"),
    (2, 1.0, "shape"),
    (2, [0.0, 0.0, 0.0], "zero"),
    (2, [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]], "zero"),
    (2, [NAN, 0.0, 1.0], "NaN"),
    (2, [[0.0, INF, 1.0]], "NaN|inf"),
])
def test_sh_basis(sd, lmax, dirs, match):
    with pytest.raises(ValueError, match=match):
        sd.sh_basis(lmax, dirs)


def rotation_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.mark.parametrize("coeffs,rotation,match", [
    (np.ones(5), np.eye(3), "square"),
    (np.ones(8), np.eye(3), "square"),
    (np.ones((10, 3)), np.eye(3), "square"),
    (np.ones(0), np.eye(3), "square"),
    (np.ones(66 * 66), np.eye(3), "lmax"),
    (np.ones((4, 2, 2)), np.eye(3), "shape"),
    (np.ones(()), np.eye(3), "shape"),
    (np.array([1.0, NAN, 0.0, 0.0]), np.eye(3), "NaN"),
    (np.ones(4), np.eye(2), "shape"),
    (np.ones(4), np.eye(4), "shape"),
    (np.ones(4), np.eye(3).ravel(), "shape"),
    (np.ones(4), 2.0 * np.eye(3), "orthogonal"),
    (np.ones(4), np.ones((3, 3)), "orthogonal"),
    (np.ones(4), rotation_z(0.3) + 1e-4, "orthogonal"),
    (np.ones(4), np.diag([1.0, 1.0, -1.0]), "a reflection .*not a rotation"),
    (np.ones(4), -np.eye(3), "a reflection .*not a rotation"),
    (np.ones(4), np.where(np.eye(3) > 0, NAN, 0.0), "NaN|non-finite"),
])
def test_rotate_sh(sd, coeffs, rotation, match):
    with pytest.raises(ValueError, match=match):
        sd.rotate_sh(coeffs, rotation)


@pytest.mark.parametrize("lobe,exponent,lmax,match", [
    ("blinn", 8.0, 4, "lobe"),
    ("Lambert", 0.0, 4, "lobe"),
    ("phong", -1.0, 4, "exponent"),
    ("phong", NAN, 4, "exponent"),
    ("phong", 2e4, 4, "exponent"),
    ("phong", 8.0, -1, "lmax"),
])
def test_zonal_coefficients(sd, lobe, exponent, lmax, match):
    with pytest.raises(ValueError, match=match):
        sd.zonal_coefficients(lobe, exponent, lmax)


@pytest.mark.parametrize("lmax,t,match", [
    (-1, [0.5], "lmax"),
    (3, [0.5, NAN], "NaN"),
    (3, [[0.5]], "1-D"),
    (3, [0.5, 1.5], r"\[-1, 1\].*t\[1\] = 1\.5"),
    (3000, -1.0000001, r"\[-1, 1\]"),
])
def test_legendre(sd, lmax, t, match):
    with pytest.raises(ValueError, match=match):
        sd.legendre(lmax, t)


@pytest.mark.parametrize("args,match", [
    (("phong", 8.0, -1), "degree"),
    (("phong", 8.0, 31), "degree"),
    (("lambert", 0.0, 100), "degree"),
    (("ggx", 8.0, 4), "lobe"),
    (("phong", -2.0, 4), "exponent"),
    (("phong", NAN, 4), "exponent"),
    (("phong", 8.0, 4, "newton"), "method"),
    (("phong", 8.0, 4, ""), "method"),
])
@pytest.mark.parametrize("function", ["zonal_design", "zonal_design_report"])
def test_zonal_design(sd, function, args, match):
    with pytest.raises(ValueError, match=match):
        getattr(sd, function)(*args)


def test_zonal_design_continued(sd):
    nodes, weights = sd.zonal_design("phong", 8.0, 4)
    for args, match in [
        (("phong", 9.0, 31, 8.0, nodes, weights), "degree"),
        (("ggx", 9.0, 4, 8.0, nodes, weights), "lobe"),
        (("phong", 9.0, 4, -1.0, nodes, weights), "exponent"),
        (("phong", 9.0, 4, 8.0, nodes[:, :2], weights), "start_nodes"),
        (("phong", 9.0, 4, 8.0, nodes[:0], weights[:0]), "start_nodes"),
        (("phong", 9.0, 4, 8.0, nodes, weights[:-1]), "start_weights"),
        (("phong", 9.0, 4, 8.0, nodes, -weights), "positive"),
        (("phong", 9.0, 4, 8.0, nodes, weights * NAN), "start_weights"),
    ]:
        with pytest.raises(ValueError, match=match):
            sd.zonal_design_continued(*args)


@pytest.mark.parametrize("t,w,degree,method,match", [
    ([0.0, 1.0], [1.0, 1.0], -1, "auto", "degree"),
    ([0.0, 1.0], [1.0, 1.0], 31, "auto", "degree"),
    ([0.0, 1.0], [1.0, 1.0], 4, "fast", "method"),
    ([0.0, 1.0], [1.0, 1.0, 1.0], 4, "auto", "length"),
    ([0.5], [1.0], 4, "auto", "at least"),
    ([[0.0, 1.0]], [[1.0, 1.0]], 4, "auto", "1-D"),
    ([0.0, NAN], [1.0, 1.0], 4, "auto", "NaN"),
    ([0.0, 1.0], [1.0, INF], 4, "auto", "NaN|inf"),
    ([0.0, 1.0], [1.0, -0.5], 4, "auto", "negative"),
    ([0.5, 0.0], [1.0, 1.0], 4, "auto", "increasing"),
    ([0.0, 0.0, 1.0], [1.0, 1.0, 1.0], 4, "auto", "increasing"),
    ([-1.5, 1.0], [1.0, 1.0], 4, "auto", r"\[-1, 1\]"),
    ([0.0, 1.0], [0.0, 0.0], 4, "auto", "zero"),
])
def test_zonal_design_tabulated(sd, t, w, degree, method, match):
    with pytest.raises(ValueError, match=match):
        sd.zonal_design_tabulated(t, w, degree, method)


@pytest.mark.parametrize("dirs,weights,degree,match", [
    (GOOD_DIRS, GOOD_WEIGHTS, -1, "degree"),
    (GOOD_DIRS, GOOD_WEIGHTS, 31, "degree"),
    (GOOD_DIRS[:, :2], GOOD_WEIGHTS, 4, "shape"),
    (GOOD_DIRS[0], GOOD_WEIGHTS[:1], 4, "shape"),
    (GOOD_DIRS.reshape(1, 3, 3), GOOD_WEIGHTS, 4, "shape"),
    (np.zeros((0, 3)), np.zeros(0), 4, "empty"),
    (GOOD_DIRS, GOOD_WEIGHTS[:2], 4, "weights"),
    (GOOD_DIRS, GOOD_WEIGHTS.reshape(3, 1), 4, "weights"),
    (np.where(np.eye(3) > 0, NAN, 0.0), GOOD_WEIGHTS, 4, "NaN"),
    (np.array([[0.0, 0.0, 1.0], [INF, 0.0, 0.0], [0.0, 1.0, 0.0]]), GOOD_WEIGHTS, 4, "NaN|inf"),
    (GOOD_DIRS, [1.0, NAN, 1.0], 4, "NaN"),
    (GOOD_DIRS, [1.0, -0.1, 1.0], 4, "negative"),
    (GOOD_DIRS, [1.0, -INF, 1.0], 4, "NaN|inf|negative"),
    (GOOD_DIRS, [0.0, 0.0, 0.0], 4, "zero"),
    (np.vstack([GOOD_DIRS[:2], [0.0, 0.0, 0.0]]), GOOD_WEIGHTS, 4, "zero"),
])
@pytest.mark.parametrize("function", ["weighted_design", "weighted_design_report"])
def test_weighted_design(sd, function, dirs, weights, degree, match):
    with pytest.raises(ValueError, match=match):
        getattr(sd, function)(dirs, weights, degree)


@pytest.mark.parametrize("orders", [(-1, 2, 2), (2, -1, 2), (2, 2, -1), (65, 0, 0)])
def test_gaunt_coefficients(sd, orders):
    with pytest.raises(ValueError, match="order"):
        sd.gaunt_coefficients(*orders)


def test_valid_edge_cases_do_not_raise(sd):
    # The limits themselves are accepted.
    assert sd.sh_basis(64, [0.0, 0.0, 1.0]).shape == (65 * 65,)
    assert sd.rotate_sh(np.ones(1), np.eye(3)).tolist() == [1.0]
    nodes, weights = sd.zonal_design("lambert", float("nan"), 0)  # exponent ignored for Lambert
    assert len(nodes) >= 1 and weights.sum() == pytest.approx(1.0)
    assert sd.zonal_coefficients("phong", 1e4, 2).shape == (3,)
    assert sd.zonal_coefficients("phong", 0.0, 0).tolist() == [1.0]
    # A rotation with rounding noise below the 1e-5 tolerance is accepted, float32 ones included.
    assert sd.rotate_sh(np.ones(4), rotation_z(0.7) + 1e-13).shape == (4,)
    assert sd.rotate_sh(np.ones(4), rotation_z(0.7).astype(np.float32)).shape == (4,)


def test_limits_are_exported_and_enforced(sd):
    # Each limit is a module attribute, and one past it is refused with the limit in the message.
    light = lambda order: np.ones(((order + 1) ** 2, 3))
    normals = np.array([[0.0, 0.0, 1.0]])
    calls = {
        "MAX_SH_ORDER": lambda n: sd.sh_basis(n, [0.0, 0.0, 1.0]),
        "MAX_LEGENDRE_ORDER": lambda n: sd.legendre(n, 0.5),
        "MAX_DESIGN_DEGREE": lambda n: sd.zonal_design("lambert", 1.0, n),
        "MAX_SHADING_ORDER": lambda n: sd.shade("unshadowed", light(n), normals),
        "MAX_VISIBILITY_ORDER": lambda n: sd.bake_visibility(normals, normals, np.zeros((0, 3), int), n, 8),
        "MAX_TRANSFER_ORDER": lambda n: sd.bake_transfer(normals, normals, np.zeros((0, 3), int), 8,
                                                         transfer_order=n),
        "MAX_RAYS_PER_VERTEX": lambda n: sd.vertex_ray_directions(n, 0, 0),
        "MAX_ENERGY_ORDER": lambda n: sd.band_limited_texture(light(n), 4, 2),
        "MAX_TEXTURE_SIDE": lambda n: sd.band_limited_texture(light(0), n, 2),
    }
    for name, call in calls.items():
        limit = getattr(sd, name)
        assert isinstance(limit, int) and limit > 0, name
        with pytest.raises(ValueError, match=str(limit)):
            call(limit + 1)
    assert sd.MAX_SHADING_ORDER == 16
    assert sd.MAX_PROJECTION_ORDER <= sd.MAX_ENERGY_ORDER <= sd.MAX_SH_ORDER
    assert sd.MAX_PHONG_EXPONENT == 1e4
    with pytest.raises(ValueError, match="Phong exponent"):
        sd.zonal_coefficients("phong", sd.MAX_PHONG_EXPONENT * 1.5, 2)


def test_module_refuses_numpy_2_when_its_pybind11_cannot_read_it(sd, tmp_path):
    # pybind11 < 2.12 returns NumPy 2 arrays with zero strides (every element the first): the
    # module must refuse to load there instead. A stand-in numpy that only says it is 2.0.0 is
    # enough: the check runs before any array is made.
    header = os.path.join("/usr/include/pybind11/detail/common.h")
    version = dict(re.findall(r"#define PYBIND11_VERSION_(MAJOR|MINOR) (\d+)", open(header).read()))
    if (int(version["MAJOR"]), int(version["MINOR"])) >= (2, 12):
        pytest.skip("built with pybind11 >= 2.12, which reads NumPy 2")
    (tmp_path / "numpy").mkdir()
    (tmp_path / "numpy" / "__init__.py").write_text("__version__ = '2.0.0'\n")
    module_dir = os.path.dirname(sd.__file__)
    done = subprocess.run([sys.executable, "-c", "import sdnative"], capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), module_dir])))
    assert done.returncode != 0
    assert "ImportError" in done.stderr and "NumPy 2.0.0" in done.stderr and "pybind11 >= 2.12" in done.stderr


def test_calls_refuse_allocations_beyond_the_budget(sd):
    # Each of these allocated until the kernel killed the process (or ran for minutes in ~20 GB);
    # now they are refused before allocating, with the size in the message.
    one = np.array([[0.0, 0.0, 1.0]])
    no_triangles = np.zeros((0, 3), int)
    calls = {
        "gaunt_coefficients": lambda: sd.gaunt_coefficients(64, 64, 64),
        "design from 2**24 rays": lambda: sd.bake_transfer(one, one, no_triangles, sd.MAX_RAYS_PER_VERTEX,
                                                          design_orders=(4, 2)),
        "recorded rays": lambda: sd.bake_transfer(np.zeros((1000, 3)), np.tile(one, (1000, 1)), no_triangles,
                                                  sd.MAX_RAYS_PER_VERTEX, return_rays=True),
        "product matrices": lambda: sd.bake_transfer(np.zeros((10**6, 3)), np.tile(one, (10**6, 1)), no_triangles, 1,
                                                     product_orders=(16, 8)),
        "weighted design": lambda: sd.weighted_design(np.tile(one, (3_000_000, 1)), np.ones(3_000_000), 12),
    }
    budget = f"{sd.MAX_CALL_BYTES / 1e9:.3g} GB"
    for name, call in calls.items():
        with pytest.raises(ValueError, match=f"would need .* GB, more than the {budget}"):
            call()
    assert sd.gaunt_coefficients(8, 8, 16)[0].shape[1] == 3  # orders in use stay well inside


FIT = {"vertex_count": 3, "sample_triangles": [[0, 1, 2]] * 4,
       "sample_barycentric": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.2, 0.3, 0.5]],
       "sample_weights": [1.0] * 4, "values": [[1.0], [2.0], [0.5], [2.0]],
       "penalty_vertices": np.zeros((0, 4), np.int32), "penalty_coefficients": np.zeros((0, 4))}


@pytest.mark.parametrize("change,error,match", [
    ({"vertex_count": -1}, ValueError, "vertex_count"),
    ({"sample_triangles": [[0, 1, 5]] * 4}, ValueError, "index 5"),
    ({"sample_triangles": [[0, 1]] * 4}, ValueError, "sample_triangles"),
    ({"sample_barycentric": [[NAN, 0.0, 0.0]] * 4}, ValueError, "NaN|finite"),
    ({"sample_weights": [1.0]}, ValueError, "sample_weights"),
    ({"sample_weights": [1.0, -2.0, 1.0, 1.0]}, ValueError, "weight"),
    ({"values": [[1.0], [INF], [1.0], [1.0]]}, ValueError, "finite"),
    ({"values": [1.0, 2.0, 3.0]}, ValueError, "values"),
    ({"penalty_vertices": [[0, 1, 0, 0]], "penalty_coefficients": [[1.0, -1.0]]}, ValueError, "penalty_coefficients"),
    ({"penalty_vertices": [[0, 9, 0, 0]], "penalty_coefficients": [[1.0, -1.0, 0.0, 0.0]]}, ValueError, "index 9"),
    ({"vertex_count": 4}, RuntimeError, "no sample"),     # vertex 3 is in no sample
])
def test_fit_vertex_values(sd, change, error, match):
    with pytest.raises(error, match=match):
        sd.fit_vertex_values(**dict(FIT, **change))
    assert sd.fit_vertex_values(**FIT).shape == (3, 1)


def test_fit_vertex_values_progress_and_cancel(sd):
    calls = []
    sd.fit_vertex_values(**FIT, progress=lambda done, total: calls.append((done, total)))
    assert calls[0] == (0, 1) and calls[-1] == (1, 1)
    with pytest.raises(sd.BakeCancelled):
        sd.fit_vertex_values(**FIT, progress=lambda done, total: False)
    # cancelled after the factorization, as the solves start (its second report)
    reports = []
    with pytest.raises(sd.BakeCancelled):
        sd.fit_vertex_values(**FIT, progress=lambda done, total: reports.append(done) or len(reports) < 2)
    assert len(reports) == 2
    with pytest.raises(ValueError, match="progress"):
        sd.fit_vertex_values(**FIT, progress=3)
