"""The ringing window's pure logic (scene/ringing.py): windowing coefficients per band, the
choice made off the main thread and cached, and the panel's lines about it."""

import threading

import numpy as np
import pytest

from sd_lighting.scene import ringing
from sd_lighting.background import Background, Failed


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


class _HeldEnvironment:
    """An sdnative Environment whose ringing_window waits until `release` is set; counts calls."""

    def __init__(self, environment):
        self._env = environment
        self.release = threading.Event()
        self.calls = 0

    def ringing_window(self, lobe, exponent, s, window):
        self.calls += 1
        assert self.release.wait(30)
        return self._env.ringing_window(lobe, exponent, s, window)


@pytest.fixture(scope="module")
def sun(sdnative):
    """A small map with a sun: truncated at s = 8 a sigma = 61 lobe rings (a window is chosen)."""
    pixels = np.full((32, 64, 3), 0.2, dtype=np.float32)
    pixels[6:8, 20:22] = 2000.0
    return sdnative.environment_from_pixels(pixels)


def test_choice_is_pending_then_made_once(sun):
    choices = Background("test")
    held = _HeldEnvironment(sun)
    assert ringing.choice(choices, "sun", held, "phong", 61.0, 8, "automatic") is None
    assert ringing.status(choices) == ["Choosing the ringing window of Phong sigma 61, s = 8 (none meanwhile)"]
    held.release.set()
    chosen = ringing.choice(choices, "sun", held, "phong", 61.0, 8, "automatic", wait=True)
    expected = sun.ringing_window("phong", 61.0, 8, "automatic")
    assert chosen["window"] == expected["window"] != "none"
    np.testing.assert_array_equal(chosen["factors"], expected["factors"])   # deterministic
    assert ringing.choice(choices, "sun", held, "phong", 61, 8, "automatic") is chosen and held.calls == 1
    assert ringing.status(choices) == []
    # another key (the setting, the order, the environment) is another choice
    assert ringing.choice(choices, "sun", held, "phong", 61.0, 8, "hanning", wait=True)["window"] == "hanning"
    assert ringing.choice(choices, "other", held, "phong", 61.0, 8, "automatic") is None
    assert choices.wait(30) and held.calls == 3


def test_a_failed_choice_is_reported_not_raised(sun):
    choices = Background("test")
    assert ringing.choice(choices, "sun", sun, "phong", -1.0, 8, "automatic") is None   # sdnative refuses it
    assert choices.wait(30)
    assert ringing.choice(choices, "sun", sun, "phong", -1.0, 8, "automatic") is None   # not retried
    lines = ringing.status(choices)
    assert len(lines) == 1 and lines[0].startswith("Ringing window of Phong sigma -1, s = 8 failed (none used): ")
    with pytest.raises(Failed):
        ringing.choice(choices, "sun", sun, "phong", -1.0, 8, "automatic", wait=True)
    # the worker goes on with what is asked next
    assert ringing.choice(choices, "sun", sun, "lambert", 1.0, 4, "sloan", wait=True)["window"] == "sloan"
    assert ringing.status(choices) == lines
