"""The binding contract of sh_basis, legendre, rotate_sh and sh_recurrence_constants, with one real
computation each; the math of the basis and the rotation is tested in tests/cpp/sh."""
import math

import numpy as np
import pytest

from sd_test_utils import (
    EXACT,
    random_directions,
    random_rotation,
    rotation_about_z,
    sh_count,
    sh_index,
)


def test_closed_forms(sd, rng):
    d = random_directions(rng, 50)
    x, y, z = d.T
    Y = sd.sh_basis(2, d)
    assert Y.shape == (50, 9) and Y.dtype == np.float64
    expected = {
        (0, 0): np.ones_like(x),
        (1, -1): math.sqrt(3) * y,
        (1, 0): math.sqrt(3) * z,
        (1, 1): math.sqrt(3) * x,
        (2, -2): math.sqrt(15) * x * y,
        (2, -1): math.sqrt(15) * y * z,
        (2, 0): math.sqrt(5) / 2 * (3 * z * z - 1),
        (2, 1): math.sqrt(15) * x * z,
        (2, 2): math.sqrt(15) / 2 * (x * x - y * y),
    }
    for (l, m), values in expected.items():
        np.testing.assert_allclose(Y[:, sh_index(l, m)], values, rtol=0, atol=EXACT, err_msg=f"y_{l},{m}")


def test_single_direction_and_normalisation(sd, rng):
    d = random_directions(rng, 7)
    batch = sd.sh_basis(6, d)
    for i in range(len(d)):
        single = sd.sh_basis(6, d[i])
        assert single.shape == (sh_count(6),)
        np.testing.assert_allclose(single, batch[i], rtol=0, atol=EXACT)
    # Directions are normalised: any positive scale gives the same values, lists and ints work.
    np.testing.assert_allclose(sd.sh_basis(6, 1e-3 * d), batch, rtol=0, atol=EXACT)
    np.testing.assert_allclose(sd.sh_basis(6, 1e250 * d), batch, rtol=0, atol=EXACT)
    np.testing.assert_allclose(sd.sh_basis(3, [0, 0, 7]), sd.sh_basis(3, np.array([0.0, 0.0, 1.0])), atol=0)
    assert sd.sh_basis(4, np.zeros((0, 3))).shape == (0, 25)
    # A non-contiguous float32 view is converted.
    wide = np.asfortranarray(np.hstack([d, d]).astype(np.float32))[:, ::2]
    np.testing.assert_allclose(sd.sh_basis(2, wide), sd.sh_basis(2, wide.astype(np.float64)), atol=0)


def test_legendre(sd, rng):
    t = np.concatenate([rng.uniform(-1, 1, 30), [-1.0, 0.0, 1.0]])
    P = sd.legendre(20, t)
    assert P.shape == (len(t), 21)
    reference = np.stack([np.polynomial.legendre.legval(t, np.eye(21)[l]) for l in range(21)], axis=1)
    np.testing.assert_allclose(P, reference, rtol=0, atol=EXACT)
    np.testing.assert_allclose(sd.legendre(20, 0.3), sd.legendre(20, [0.3])[0], atol=0)
    assert sd.legendre(0, [0.5]).tolist() == [[1.0]]


def test_rotate_y11_about_z_by_90_degrees(sd, rng):
    # R turns x into y, so f = y_11 = sqrt(3) x becomes f(R^T x) = sqrt(3) (R^T x)_x = sqrt(3) y = y_1,-1.
    R = rotation_about_z(math.pi / 2)
    c = np.zeros(4)
    c[sh_index(1, 1)] = 1.0
    rotated = sd.rotate_sh(c, R)
    expected = np.zeros(4)
    expected[sh_index(1, -1)] = 1.0
    np.testing.assert_allclose(rotated, expected, rtol=0, atol=EXACT)
    # The same through the basis: sum_i rotated_i y_i(x) = f(R^T x).
    x = random_directions(rng, 10)
    np.testing.assert_allclose(sd.sh_basis(1, x) @ rotated, sd.sh_basis(1, x @ R) @ c, rtol=0, atol=EXACT)
    np.testing.assert_allclose(sd.sh_basis(1, x) @ rotated, math.sqrt(3) * x[:, 1], rtol=0, atol=EXACT)


def test_rotate_sh_channels(sd, rng):
    order = 8
    R = random_rotation(rng)
    for channels in (1, 2, 3, 4, 5):
        c = rng.normal(size=(sh_count(order), channels))
        rotated = sd.rotate_sh(c, R)
        assert rotated.shape == c.shape and rotated.dtype == np.float64
        for k in range(channels):
            np.testing.assert_allclose(rotated[:, k], sd.rotate_sh(c[:, k].copy(), R), rtol=0, atol=EXACT)
    # Non-contiguous inputs (a Fortran-order array, a transposed rotation) are converted.
    c = np.asfortranarray(rng.normal(size=(sh_count(order), 3)))
    np.testing.assert_allclose(sd.rotate_sh(c, R.T.copy().T), sd.rotate_sh(np.ascontiguousarray(c), R), atol=0)
    assert sd.rotate_sh(np.zeros((sh_count(2), 0)), R).shape == (9, 0)


def recurrence_formula(order):
    """The recurrence constants by their closed forms (the formula the add-on evaluated in Python
    before sdnative.sh_recurrence_constants exported them): Q_mm = (2m-1)!! sqrt(2 (2m+1) / (2m)!) for
    m > 0, Q_00 = 1; for m < l, a_lm = sqrt((2l-1)(2l+1) / ((l-m)(l+m))) (sqrt(2m+3) at l = m+1) and
    b_lm = sqrt((2l+1)(l+m-1)(l-m-1) / ((l-m)(l+m)(2l-3))) (0 at l = m+1), at l (l+1) / 2 + m."""
    diagonal = np.array([1.0] + [math.prod(range(1, 2 * m, 2)) * math.sqrt(2.0 * (2 * m + 1) / math.factorial(2 * m))
                                 for m in range(1, order + 1)])
    l, m = np.array([(l, m) for l in range(order + 1) for m in range(l + 1)], dtype=float).T
    below = m < l
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(below, np.sqrt((2 * l - 1) * (2 * l + 1) / ((l - m) * (l + m))), 0.0)
        b = np.where(below & (l > m + 1),
                     np.sqrt((2 * l + 1) * (l + m - 1) * (l - m - 1) / ((l - m) * (l + m) * (2 * l - 3))), 0.0)
    return diagonal, a, b


def test_sh_recurrence_constants_are_the_closed_forms(sd):
    for order in (0, 1, 5, 24):
        constants = sd.sh_recurrence_constants(order)
        assert sorted(constants) == ["a", "b", "diagonal"]
        size = (order + 1) * (order + 2) // 2
        for key, length in (("diagonal", order + 1), ("a", size), ("b", size)):
            assert constants[key].dtype == np.float64 and constants[key].shape == (length,), key
        for key, expected in zip(("diagonal", "a", "b"), recurrence_formula(order)):
            np.testing.assert_allclose(constants[key], expected, rtol=1e-14, atol=0, err_msg=key)
    for order in (-1, 65):
        with pytest.raises(ValueError, match="order"):
            sd.sh_recurrence_constants(order)


def test_sh_recurrence_constants_reproduce_sh_basis(sd, rng):
    order = 20
    constants = sd.sh_recurrence_constants(order)
    a, b, diagonal = constants["a"], constants["b"], constants["diagonal"]
    d = random_directions(rng, 40)
    x, y, z = d.T
    evaluated = np.zeros((len(d), sh_count(order)))
    re, im = np.ones_like(x), np.zeros_like(x)  # (x + i y)^m
    for m in range(order + 1):
        if m > 0:
            re, im = re * x - im * y, re * y + im * x
        q_before, q = np.zeros_like(z), np.full_like(z, diagonal[m])
        for l in range(m, order + 1):
            if l > m:
                k = l * (l + 1) // 2 + m
                q_before, q = q, a[k] * z * q - b[k] * q_before
            evaluated[:, sh_index(l, m)] = q * re
            if m > 0:
                evaluated[:, sh_index(l, -m)] = q * im
    np.testing.assert_allclose(evaluated, sd.sh_basis(order, d), rtol=0, atol=EXACT)
