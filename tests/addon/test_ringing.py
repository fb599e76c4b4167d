"""The ringing window's pure logic (utils/ringing.py): windowing coefficients per band, and the
panel's line about the choice."""

import numpy as np
import pytest

from sd_lighting.utils import ringing


def test_windowed_multiplies_each_band():
    coefficients = np.arange(27, dtype=np.float64).reshape(9, 3) + 1.0
    factors = np.array([1.0, 0.5, 0.25])
    out = ringing.windowed(coefficients, factors)
    np.testing.assert_array_equal(out[0], coefficients[0])
    np.testing.assert_array_equal(out[1:4], 0.5 * coefficients[1:4])
    np.testing.assert_array_equal(out[4:9], 0.25 * coefficients[4:9])
    np.testing.assert_array_equal(ringing.windowed(coefficients[:, 0], factors)[4:], 0.25 * coefficients[4:, 0])
    with pytest.raises(ValueError, match="window factors"):
        ringing.windowed(coefficients, factors[:2])


def test_windowing_commutes_with_rotation(sdnative):
    rng = np.random.default_rng(4)
    light = rng.normal(size=(25, 3))
    factors = np.array([1.0, 0.9, 0.6, 0.3, 0.1])
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    g = q * np.sign(np.linalg.det(q))
    np.testing.assert_allclose(sdnative.rotated_environment_sh(ringing.windowed(light, factors), g),
                               ringing.windowed(sdnative.rotated_environment_sh(light, g), factors),
                               rtol=0, atol=1e-12)


def test_describe():
    choice = dict(ringing.unwindowed(4), window="hanning", error=0.04, unwindowed_error=0.12,
                  min_over_max=-0.02, unwindowed_min_over_max=-0.36)
    assert ringing.describe(choice, "automatic") == (
        "Hanning: 12.0 % -> 4.0 % displayed error, min/max B -36.0 % -> -2.0 %")
    none = dict(ringing.unwindowed(4), unwindowed_error=0.07, error=0.07)
    assert ringing.describe(none, "automatic") == "None: no window lowers the 7.0 % displayed error"
    assert ringing.describe(none, "none") == "None: 7.0 % displayed error, min/max B +0.0 %"
    assert set(ringing.WINDOWS) == set(ringing.LABELS)
