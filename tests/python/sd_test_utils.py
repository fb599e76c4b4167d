"""Plain-numpy references for the tests: quadrature rules, random rotations and polynomials.

Nothing here calls sdnative, so the references are independent of the code under test.
"""
import itertools
import math

import numpy as np

EXACT = 1e-12  # results the library computes exactly, up to rounding
QUADRATURE = 1e-10  # results checked against a numerical quadrature


def sh_count(order):
    return (order + 1) ** 2


def sh_index(l, m):
    return l * l + l + m


def gauss_legendre(n, a=-1.0, b=1.0):
    """n-point Gauss-Legendre rule on [a, b]: exact for polynomials of degree 2n - 1."""
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


def sphere_product_rule(n_t, n_phi, t_range=(-1.0, 1.0), phi_offset=0.25):
    """Product rule for dmu = dx / 4pi restricted to t = z in t_range: Gauss-Legendre in t times
    n_phi equally spaced azimuths. Over the whole sphere it integrates every polynomial of degree
    <= min(2 n_t - 1, n_phi - 1) exactly; the weights sum to the measure of the band."""
    t, wt = gauss_legendre(n_t, *t_range)
    phi = 2.0 * np.pi * (np.arange(n_phi) + phi_offset) / n_phi
    r = np.sqrt(np.maximum(0.0, 1.0 - t * t))
    dirs = np.stack(
        [np.outer(r, np.cos(phi)), np.outer(r, np.sin(phi)), np.outer(t, np.ones(n_phi))], axis=-1
    ).reshape(-1, 3)
    weights = np.outer(wt / 2.0, np.full(n_phi, 1.0 / n_phi)).ravel()
    return dirs, weights


def random_directions(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def random_rotation(rng):
    """Uniform on SO(3) (QR of a Gaussian matrix with the sign fix)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0.0:
        q[:, 0] = -q[:, 0]
    return q


def rotation_about_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class RandomPolynomial:
    """f(x, y, z) = sum c_abc x^a y^b z^c over a + b + c <= degree, with sum |c_abc| = 1, so that
    |f| <= 1 on the sphere."""

    def __init__(self, rng, degree):
        self.exponents = np.array(
            [e for e in itertools.product(range(degree + 1), repeat=3) if sum(e) <= degree], dtype=int
        )
        c = rng.normal(size=len(self.exponents))
        self.coefficients = c / np.abs(c).sum()

    def __call__(self, dirs):
        dirs = np.asarray(dirs, dtype=float)
        powers = np.prod(dirs[:, None, :] ** self.exponents[None, :, :], axis=2)
        return powers @ self.coefficients


def lobe_weight(lobe, exponent):
    """The normalised lobe w(t) of msd-notes as a numpy function."""
    sigma = 1.0 if lobe == "lambert" else float(exponent)
    return lambda t: (2.0 * sigma + 2.0) * np.where(t > 0.0, np.maximum(t, 0.0) ** sigma, 0.0)


def lobe_integral(f, lobe, exponent, n_t=96, n_phi=64):
    """integral f(x) w(x . e3) dmu(x) for a lobe supported on t >= 0, by a product rule on the
    upper hemisphere in u = sqrt(t): for integer and half-integer exponents sigma the integrand is
    a polynomial in u, so the rule is exact while 2 sigma + 2 deg f + 1 < 2 n_t and deg f < n_phi."""
    u, wu = gauss_legendre(n_t, 0.0, 1.0)
    t, wt = u * u, 2.0 * u * wu
    phi = 2.0 * np.pi * (np.arange(n_phi) + 0.25) / n_phi
    r = np.sqrt(np.maximum(0.0, 1.0 - t * t))
    dirs = np.stack(
        [np.outer(r, np.cos(phi)), np.outer(r, np.sin(phi)), np.outer(t, np.ones(n_phi))], axis=-1
    ).reshape(-1, 3)
    weights = np.outer(wt / 2.0 * lobe_weight(lobe, exponent)(t), np.full(n_phi, 1.0 / n_phi)).ravel()
    return float(np.sum(weights * f(dirs)))
