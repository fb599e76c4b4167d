"""The binding contract of the lobe factors, the designs and the Gaunt coefficients, with one real
computation each; their math is tested in tests/cpp (sh/, quadrature/)."""
import concurrent.futures

import numpy as np
import pytest

from sd_test_utils import (
    EXACT,
    QUADRATURE,
    RandomPolynomial,
    lobe_integral,
    random_directions,
    sh_count,
    sphere_product_rule,
)


def test_zonal_coefficients(sd):
    c = sd.zonal_coefficients("lambert", 0.0, 8)
    assert c.shape == (9,) and c.dtype == np.float64
    expected = [1.0, 2.0 / 3.0, 1.0 / 4.0, 0.0, -1.0 / 24.0, 0.0, 1.0 / 64.0, 0.0, -1.0 / 128.0]
    np.testing.assert_allclose(c, expected, rtol=0, atol=EXACT)
    # The exponent is ignored for Lambert.
    np.testing.assert_allclose(sd.zonal_coefficients("lambert", 123.0, 8), c, atol=0)


def check_design(nodes, weights, mass=1.0):
    assert nodes.ndim == 2 and nodes.shape[1] == 3 and nodes.dtype == np.float64
    assert weights.shape == (len(nodes),) and weights.dtype == np.float64
    assert len(nodes) >= 1 and np.all(weights > 0.0)
    np.testing.assert_allclose(weights.sum(), mass, rtol=EXACT)
    np.testing.assert_allclose(np.linalg.norm(nodes, axis=1), 1.0, rtol=0, atol=EXACT)


@pytest.mark.parametrize("method", ["auto", "gauss", "gradient"])
def test_zonal_design_integrates_polynomials(sd, rng, method):
    nodes, weights = sd.zonal_design("phong", 8.0, 6, method)
    check_design(nodes, weights)
    f = RandomPolynomial(rng, 6)
    assert weights @ f(nodes) == pytest.approx(lobe_integral(f, "phong", 8.0), abs=QUADRATURE)


def test_zonal_design_report(sd):
    for method in ("auto", "gauss", "gradient"):
        report = sd.zonal_design_report("phong", 8.0, 6, method)
        assert set(report) == {"nodes", "weights", "degree", "residual", "method"}
        assert isinstance(report["degree"], int) and report["degree"] == 6
        assert isinstance(report["residual"], float) and 0.0 <= report["residual"] <= sd.DESIGN_TOLERANCE
        assert report["method"] in ("gauss", "gauss-radau", "gradient")
        if method == "gauss":
            assert report["method"].startswith("gauss")
        nodes, weights = sd.zonal_design("phong", 8.0, 6, method)
        np.testing.assert_allclose(report["nodes"], nodes, atol=0)
        np.testing.assert_allclose(report["weights"], weights, atol=0)
    assert sd.zonal_design_report("lambert", 0.0, 4, method="gauss")["method"] == "gauss-radau"


def test_zonal_design_continued(sd, rng):
    start = sd.zonal_design("phong", 8.0, 6)
    nodes, weights = sd.zonal_design_continued("phong", 10.0, 6, 8.0, *start)
    check_design(nodes, weights)
    assert len(weights) <= len(start[1])
    f = RandomPolynomial(rng, 6)
    assert weights @ f(nodes) == pytest.approx(lobe_integral(f, "phong", 10.0), abs=QUADRATURE)
    # from Lambert (Phong at sigma 1): its design moves to sigma 1.2
    lambert = sd.zonal_design("lambert", 0.0, 6)
    check_design(*sd.zonal_design_continued("phong", 1.2, 6, 1.0, *lambert))


def test_module_constants(sd):
    assert sd.DESIGN_TOLERANCE == 1e-10
    assert "Condon" in sd.__doc__ and "l^2 + l + m" in sd.__doc__


def test_zonal_design_threads(sd):
    # The builders release the GIL; concurrent calls give the sequential results.
    jobs = [("phong", s, k) for s in (4.0, 8.0, 16.0) for k in (4, 6, 8)]
    sequential = [sd.zonal_design(*job) for job in jobs]
    with concurrent.futures.ThreadPoolExecutor(max_workers=3) as pool:
        threaded = list(pool.map(lambda job: sd.zonal_design(*job), jobs))
    for (n1, w1), (n2, w2) in zip(sequential, threaded):
        np.testing.assert_allclose(n1, n2, atol=0)
        np.testing.assert_allclose(w1, w2, atol=0)


def tabulated_integral(f, t_samples, w_samples, n_phi=64):
    """integral f(x) w(x . e3) dmu for a piecewise-linear w: Gauss-Legendre on each segment."""
    total = 0.0
    for i in range(len(t_samples) - 1):
        a, b = t_samples[i], t_samples[i + 1]
        dirs, weights = sphere_product_rule(24, n_phi, (a, b))
        w = np.interp(dirs[:, 2], t_samples, w_samples)
        total += np.sum(weights * w * f(dirs))
    return total


def test_zonal_design_tabulated(sd, rng):
    t, w = np.array([-0.5, 0.0, 0.3, 0.9]), np.array([0.0, 2.0, 0.5, 3.0])  # a ragged band
    nodes, weights = sd.zonal_design_tabulated(list(t), w, 4)
    check_design(nodes, weights, mass=tabulated_integral(lambda d: np.ones(len(d)), t, w))
    f = RandomPolynomial(rng, 4)
    assert weights @ f(nodes) == pytest.approx(tabulated_integral(f, t, w), abs=QUADRATURE)


def check_moments(sd, nodes, weights, dirs, mass_weights, degree):
    target = sd.sh_basis(degree, dirs).T @ mass_weights
    got = sd.sh_basis(degree, nodes).T @ weights
    assert np.max(np.abs(got - target)) <= QUADRATURE * mass_weights.sum()


def test_weighted_design(sd, rng):
    # Unnormalised directions of a visibility-like measure: above a tilted horizon, zero weights mixed in.
    dirs = random_directions(rng, 3000)
    w = (dirs @ np.array([0.3, 0.2, 0.9]) > 0.1) * rng.uniform(0.05, 1.0, len(dirs))
    report = sd.weighted_design_report(3.0 * dirs, w, 6)
    assert set(report) == {"nodes", "weights", "degree", "residual", "method"}
    assert report["degree"] == 6 and report["residual"] <= sd.DESIGN_TOLERANCE
    assert report["method"] in ("tchakaloff", "gradient")
    check_design(report["nodes"], report["weights"], mass=w.sum())
    assert len(report["nodes"]) <= sh_count(6)
    check_moments(sd, report["nodes"], report["weights"], dirs, w, 6)
    nodes, weights = sd.weighted_design(3.0 * dirs, w, 6)
    np.testing.assert_allclose(nodes, report["nodes"], atol=0)
    np.testing.assert_allclose(weights, report["weights"], atol=0)


def test_gaunt_coefficients(sd, rng):
    oa, ob = 4, 3
    indices, values = sd.gaunt_coefficients(oa, ob, oa + ob)
    assert indices.dtype == np.int32 and indices.shape == (len(values), 3) and values.dtype == np.float64
    keys = indices.astype(np.int64) @ np.array([10**6, 10**3, 1])
    assert np.all(np.diff(keys) > 0)  # sorted by (a, b, c), no duplicates
    # y_a y_b = sum_c G_abc y_c at random points.
    x = random_directions(rng, 25)
    Y = sd.sh_basis(oa + ob, x)
    for a in range(sh_count(oa)):
        for b in range(sh_count(ob)):
            rows = (indices[:, 0] == a) & (indices[:, 1] == b)
            expansion = Y[:, indices[rows, 2]] @ values[rows]
            np.testing.assert_allclose(expansion, Y[:, a] * Y[:, b], rtol=0, atol=EXACT * 10)
