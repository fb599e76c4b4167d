"""Lobe factors, zonal and weighted designs, and Gaunt coefficients."""
import concurrent.futures

import numpy as np
import pytest

from sd_test_utils import (
    EXACT,
    QUADRATURE,
    RandomPolynomial,
    gauss_legendre,
    lobe_integral,
    lobe_weight,
    random_directions,
    sh_count,
    sphere_product_rule,
)


def legendre_table(lmax, t):
    return np.stack([np.polynomial.legendre.legval(t, np.eye(lmax + 1)[l]) for l in range(lmax + 1)], axis=1)


# ---- zonal_coefficients ----

def test_lambert_coefficients(sd):
    c = sd.zonal_coefficients("lambert", 0.0, 8)
    assert c.shape == (9,)
    expected = [1.0, 2.0 / 3.0, 1.0 / 4.0, 0.0, -1.0 / 24.0, 0.0, 1.0 / 64.0, 0.0, -1.0 / 128.0]
    np.testing.assert_allclose(c, expected, rtol=0, atol=EXACT)
    # The exponent is ignored for Lambert, which is Phong with sigma = 1.
    np.testing.assert_allclose(sd.zonal_coefficients("lambert", 123.0, 8), c, atol=0)
    np.testing.assert_allclose(sd.zonal_coefficients("phong", 1.0, 8), c, rtol=0, atol=EXACT)


@pytest.mark.parametrize("lobe,sigma", [("lambert", 1.0), ("phong", 0.0), ("phong", 8.0), ("phong", 32.0),
                                        ("phong", 2.5), ("phong", 7.25)])
def test_zonal_coefficients_match_integration(sd, lobe, sigma):
    lmax = 20
    c = sd.zonal_coefficients(lobe, sigma, lmax)
    assert c[0] == pytest.approx(1.0, abs=EXACT)
    if lobe == "phong":
        assert c[1] == pytest.approx((sigma + 1) / (sigma + 2), abs=EXACT)
    # w_l = 1/2 integral_0^1 w(t) P_l(t) dt; Gauss-Legendre in u = t^(1/2) smooths t^sigma's root.
    u, wu = gauss_legendre(400, 0.0, 1.0)
    t, wt = u * u, wu * 2.0 * u
    integral = 0.5 * (wt * lobe_weight(lobe, sigma)(t)) @ legendre_table(lmax, t)
    np.testing.assert_allclose(c, integral, rtol=0, atol=QUADRATURE)


def test_phong_coefficients_stable_for_narrow_lobes(sd):
    sigma, lmax = 1e4, 60
    c = sd.zonal_coefficients("phong", sigma, lmax)
    assert np.all(np.isfinite(c)) and np.all(np.abs(c) <= 1.0)
    # Composite Gauss-Legendre in s = 1 - t where (1 - s)^sigma lives (width ~1e-4).
    nodes, weights = [], []
    edges = np.linspace(0.0, 0.01, 51)
    for a, b in zip(edges[:-1], edges[1:]):
        x, w = gauss_legendre(20, a, b)
        nodes.append(x)
        weights.append(w)
    s, ws = np.concatenate(nodes), np.concatenate(weights)
    lobe = (2 * sigma + 2) * np.exp(sigma * np.log1p(-s))
    integral = 0.5 * (ws * lobe) @ legendre_table(lmax, 1.0 - s)
    np.testing.assert_allclose(c, integral, rtol=0, atol=QUADRATURE)


# ---- zonal designs ----

def check_design(nodes, weights, degree, mass=1.0):
    assert nodes.ndim == 2 and nodes.shape[1] == 3 and nodes.dtype == np.float64
    assert weights.shape == (len(nodes),) and weights.dtype == np.float64
    assert len(nodes) >= 1
    assert np.all(weights > 0.0)
    np.testing.assert_allclose(weights.sum(), mass, rtol=EXACT)
    np.testing.assert_allclose(np.linalg.norm(nodes, axis=1), 1.0, rtol=0, atol=EXACT)


LOBES = [("lambert", 0.0), ("phong", 0.0), ("phong", 8.0), ("phong", 32.0), ("phong", 2.5)]


@pytest.mark.parametrize("method", ["auto", "gauss", "gradient"])
@pytest.mark.parametrize("lobe,sigma", LOBES)
def test_zonal_design_integrates_polynomials(sd, rng, lobe, sigma, method):
    for degree in (0, 1, 2, 3, 4, 5, 6, 8):
        nodes, weights = sd.zonal_design(lobe, sigma, degree, method)
        check_design(nodes, weights, degree)
        if method == "gauss":
            # Product-rule nodes live where the lobe does (t >= 0). Gradient projection only keeps
            # nodes on the sphere, and may move some slightly below the horizon (still exact).
            assert np.all(nodes[:, 2] >= -EXACT)
        for _ in range(3):
            f = RandomPolynomial(rng, degree)
            exact = lobe_integral(f, lobe, sigma)
            assert weights @ f(nodes) == pytest.approx(exact, abs=QUADRATURE), (degree, method)


@pytest.mark.parametrize("lobe,sigma", [("lambert", 0.0), ("phong", 8.0)])
def test_zonal_design_sizes(sd, lobe, sigma):
    # The seed's node counts: 10 (degree 4) and 18 (degree 6) by gradient projection; 11 and 22
    # by the Gauss product rule with the pole as a node. No positive rule beats (k/2+1)^2.
    for degree, at_most in ((4, 10), (6, 18)):
        nodes, _ = sd.zonal_design(lobe, sigma, degree)
        assert (degree // 2 + 1) ** 2 <= len(nodes) <= at_most
        nodes, _ = sd.zonal_design(lobe, sigma, degree, method="gradient")
        assert len(nodes) <= at_most
    for degree in (2, 4, 6, 8, 10):
        nodes, _ = sd.zonal_design(lobe, sigma, degree, method="gauss")
        assert len(nodes) == 1 + (degree // 2) * (degree + 1), degree


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


def test_module_constants(sd):
    assert sd.MAX_DESIGN_DEGREE == 30
    assert sd.DESIGN_TOLERANCE == 1e-10
    assert "Condon" in sd.__doc__ and "l^2 + l + m" in sd.__doc__
    for name in ("sh_basis", "rotate_sh", "zonal_coefficients", "zonal_design", "zonal_design_tabulated",
                 "weighted_design", "zonal_design_report", "weighted_design_report", "gaunt_coefficients",
                 "legendre"):
        assert getattr(sd, name).__doc__


def test_zonal_design_threads(sd):
    # The builders release the GIL; concurrent calls give the sequential results.
    jobs = [("phong", s, k) for s in (4.0, 8.0, 16.0) for k in (4, 6, 8)]
    sequential = [sd.zonal_design(*job) for job in jobs]
    with concurrent.futures.ThreadPoolExecutor(max_workers=3) as pool:
        threaded = list(pool.map(lambda job: sd.zonal_design(*job), jobs))
    for (n1, w1), (n2, w2) in zip(sequential, threaded):
        np.testing.assert_allclose(n1, n2, atol=0)
        np.testing.assert_allclose(w1, w2, atol=0)


# ---- tabulated zonal weights ----

def tabulated_integral(f, t_samples, w_samples, n_phi=64):
    """integral f(x) w(x . e3) dmu for a piecewise-linear w: Gauss-Legendre on each segment."""
    total = 0.0
    for i in range(len(t_samples) - 1):
        a, b = t_samples[i], t_samples[i + 1]
        dirs, weights = sphere_product_rule(24, n_phi, (a, b))
        w = np.interp(dirs[:, 2], t_samples, w_samples)
        total += np.sum(weights * w * f(dirs))
    return total


@pytest.mark.parametrize("t,w", [
    ([-1.0, 1.0], [0.0, 2.0]),                 # 1 + t on the whole sphere, mass 1/2
    ([0.0, 1.0], [0.0, 4.0]),                  # Lambert, mass 1
    ([-0.5, 0.0, 0.3, 0.9], [0.0, 2.0, 0.5, 3.0]),  # a ragged band
])
def test_zonal_design_tabulated(sd, rng, t, w):
    t, w = np.array(t), np.array(w)
    mass = tabulated_integral(lambda d: np.ones(len(d)), t, w)
    for degree in (0, 2, 4, 6):
        for method in ("auto", "gauss"):
            nodes, weights = sd.zonal_design_tabulated(t, w, degree, method)
            check_design(nodes, weights, degree, mass=mass)
            for _ in range(3):
                f = RandomPolynomial(rng, degree)
                assert weights @ f(nodes) == pytest.approx(tabulated_integral(f, t, w), abs=QUADRATURE)


def test_tabulated_lambert_matches_lobe(sd, rng):
    nodes, weights = sd.zonal_design_tabulated([0.0, 1.0], [0.0, 4.0], 6)
    f = RandomPolynomial(rng, 6)
    assert weights @ f(nodes) == pytest.approx(lobe_integral(f, "lambert", 0.0), abs=QUADRATURE)


# ---- weighted designs ----

def check_moments(sd, nodes, weights, dirs, mass_weights, degree):
    target = sd.sh_basis(degree, dirs).T @ mass_weights
    got = sd.sh_basis(degree, nodes).T @ weights
    mass = mass_weights.sum()
    assert np.max(np.abs(got - target)) <= QUADRATURE * mass


@pytest.mark.parametrize("degree", [0, 1, 2, 4, 6, 8])
def test_weighted_design_random_measure(sd, rng, degree):
    dirs = 3.0 * random_directions(rng, 2000)
    w = rng.uniform(0.05, 1.0, len(dirs))
    nodes, weights = sd.weighted_design(dirs, w, degree)
    check_design(nodes, weights, degree, mass=w.sum())
    assert len(nodes) <= sh_count(degree)
    check_moments(sd, nodes, weights, dirs / 3.0, w, degree)
    f = RandomPolynomial(rng, degree)
    assert weights @ f(nodes) == pytest.approx(w @ f(dirs / 3.0), abs=QUADRATURE * w.sum())


def test_weighted_design_hemisphere_visibility(sd, rng):
    # A visibility-like measure: only directions above a tilted horizon, with zero weights mixed in.
    dirs = random_directions(rng, 3000)
    w = (dirs @ np.array([0.3, 0.2, 0.9]) > 0.1).astype(float)
    for degree in (4, 6):
        report = sd.weighted_design_report(dirs, w, degree)
        assert set(report) == {"nodes", "weights", "degree", "residual", "method"}
        assert report["degree"] == degree and report["residual"] <= sd.DESIGN_TOLERANCE
        assert report["method"] in ("tchakaloff", "gradient")
        check_design(report["nodes"], report["weights"], degree, mass=w.sum())
        assert len(report["nodes"]) <= sh_count(degree)
        check_moments(sd, report["nodes"], report["weights"], dirs, w, degree)
        nodes, weights = sd.weighted_design(dirs, w, degree)
        np.testing.assert_allclose(nodes, report["nodes"], atol=0)
        np.testing.assert_allclose(weights, report["weights"], atol=0)


def test_weighted_design_degenerate_measures(sd):
    # All the mass on one direction (given twice, unnormalised): one node carries it.
    dirs = np.array([[0.0, 0.0, 2.0], [0.0, 0.0, 5.0], [1.0, 0.0, 0.0]])
    nodes, weights = sd.weighted_design(dirs, [1.5, 0.5, 0.0], 6)
    assert len(nodes) == 1
    np.testing.assert_allclose(nodes[0], [0.0, 0.0, 1.0], atol=EXACT)
    np.testing.assert_allclose(weights, [2.0], rtol=EXACT)
    # Fewer samples than moments: the design reproduces the samples' moments with <= M nodes.
    rng = np.random.default_rng(5)
    dirs = random_directions(rng, 7)
    w = rng.uniform(0.5, 1.0, 7)
    nodes, weights = sd.weighted_design(dirs, w, 8)
    assert len(nodes) <= 7
    check_moments(sd, nodes, weights, dirs, w, 8)


# ---- Gaunt coefficients ----

def test_gaunt_product_identity(sd, rng):
    oa, ob = 4, 3
    indices, values = sd.gaunt_coefficients(oa, ob, oa + ob)
    assert indices.dtype == np.int32 and indices.shape == (len(values), 3) and values.dtype == np.float64
    keys = indices.astype(np.int64) @ np.array([10**6, 10**3, 1])
    assert np.all(np.diff(keys) > 0)  # sorted by (a, b, c), no duplicates
    x = random_directions(rng, 25)
    Y = sd.sh_basis(oa + ob, x)
    for a in range(sh_count(oa)):
        for b in range(sh_count(ob)):
            rows = (indices[:, 0] == a) & (indices[:, 1] == b)
            expansion = Y[:, indices[rows, 2]] @ values[rows]
            np.testing.assert_allclose(expansion, Y[:, a] * Y[:, b], rtol=0, atol=EXACT * 10)


def test_gaunt_against_quadrature(sd):
    oa, ob, oc = 3, 3, 4
    indices, values = sd.gaunt_coefficients(oa, ob, oc)
    assert np.all(indices[:, 2] < sh_count(oc))
    dirs, weights = sphere_product_rule(8, 16)  # exact for degree 10 = 3 + 3 + 4
    Y = sd.sh_basis(4, dirs)
    dense = np.einsum("q,qa,qb,qc->abc", weights, Y[:, :16], Y[:, :16], Y)
    sparse = np.zeros_like(dense)
    sparse[indices[:, 0], indices[:, 1], indices[:, 2]] = values
    np.testing.assert_allclose(sparse, dense, rtol=0, atol=EXACT)
    # y_00 y_b = y_b.
    rows = indices[:, 0] == 0
    np.testing.assert_array_equal(indices[rows, 1], indices[rows, 2])
    np.testing.assert_allclose(values[rows], 1.0, atol=EXACT)
