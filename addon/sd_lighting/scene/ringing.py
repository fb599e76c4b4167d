"""Windows against SH ringing of the environment L~ (environment.h, "RingingWindow"): the window
setting, applying a window's factors, and the panel's line about the choice.

A window multiplies band l of L_lm by sigma_l. That commutes with rotations (they mix only
coefficients within a band), so it is applied once to the unrotated L, and every method, the SH
sums and the band-limited texture alike, shades with the same windowed L. Which window:
sdnative's Environment.ringing_window, per lobe, order s and environment; 'automatic' (the
default) picks the one with the smallest error of the displayed radiance, none unless a window
lowers it.

The choice (0.1 - 0.4 s, and the environment's order-64 projection the first time) is made in a
worker thread (`choice`, background.py) and kept in memory per (environment, lobe, exponent,
s, setting): the draw shades with no window until it is there, a preview or reference waits.
"""

from collections import namedtuple

import numpy as np

from . import lobes

WINDOWS = ("automatic", "none", "hanning", "lanczos", "sloan")
LABELS = {"automatic": "Automatic", "none": "None", "hanning": "Hanning", "lanczos": "Lanczos",
          "sloan": "Sloan"}


def windowed(coefficients, factors):
    """SH coefficients [(s+1)^2, C] with band l times factors[l] (s + 1 factors)."""
    coefficients = np.asarray(coefficients, dtype=np.float64)
    factors = np.asarray(factors, dtype=np.float64)
    order = len(factors) - 1
    if coefficients.shape[0] != (order + 1) ** 2:
        raise ValueError("%d coefficients for %d window factors (order %d needs %d)" % (
            coefficients.shape[0], len(factors), order, (order + 1) ** 2))
    per_coefficient = np.repeat(factors, 2 * np.arange(order + 1) + 1)
    return coefficients * per_coefficient.reshape((-1,) + (1,) * (coefficients.ndim - 1))


def unwindowed(order):
    """The choice for an environment nothing rings in (a uniform colour): no window, no error."""
    return {"window": "none", "sloan_lambda": 0.0, "factors": np.ones(order + 1), "error": 0.0,
            "unwindowed_error": 0.0, "l2_error": 0.0, "unwindowed_l2_error": 0.0,
            "min_over_max": 0.0, "unwindowed_min_over_max": 0.0}


def describe(choice, setting):
    """One line for the panel: the window used and why (its displayed error against none's, and
    the most negative B over the largest B, before -> after)."""
    before, after = 100.0 * choice["unwindowed_error"], 100.0 * choice["error"]
    low_before = 100.0 * min(choice["unwindowed_min_over_max"], 0.0)
    low_after = 100.0 * min(choice["min_over_max"], 0.0)
    if choice["window"] == "none":
        if setting == "automatic":
            return "None: no window lowers the %.1f %% displayed error" % before
        return "None: %.1f %% displayed error, min/max B %+.1f %%" % (before, low_before)
    return "%s: %.1f %% -> %.1f %% displayed error, min/max B %+.1f %% -> %+.1f %%" % (
        LABELS[choice["window"]], before, after, low_before, low_after)


ChoiceKey = namedtuple("ChoiceKey", "environment lobe exponent order setting")


def choice(choices, environment_key, environment, lobe, exponent, order, setting, wait=False):
    """The window of `setting` for the lobe and order s on an sdnative Environment (its
    ringing_window dict), computed once per key in the worker thread of `choices` (a
    background.Background; environment_key names the environment). wait=False (the draw): None
    until it is there, or when it failed (choices.failures(), the panel's `status`); wait=True:
    waits for it, raises background.Failed when it failed."""
    key = ChoiceKey(environment_key, lobe, float(exponent), int(order), setting)

    def compute():
        return environment.ringing_window(key.lobe, key.exponent, key.order, key.setting)

    return choices.result(key, compute) if wait else choices.get(key, compute)


def status(choices):
    """Lines for the panel: the choices being made (no window meanwhile) and those that failed."""
    def what(key):
        return "%s, s = %d%s" % (lobes.label(key.lobe, key.exponent), key.order,
                                 "" if key.setting == "automatic" else ", " + LABELS[key.setting])
    lines = ["Choosing the ringing window of %s (none meanwhile)" % what(key) for key in choices.pending()]
    lines += ["Ringing window of %s failed (none used): %s" % (what(key), why)
              for key, why in choices.failures().items()]
    return lines
