"""Ringing windows on Blender's eight HDRIs: for Lambert and Phong sigma = 8, 32, 61 at s = 4, 8,
16, the automatic window (sdnative's Environment.ringing_window), the displayed error with none
and with it, the plain relative RMS of the clamped B, and min B / max B before and after.

    PYTHONPATH=build/native /usr/bin/python3 scripts/ringing_table.py [--orders 4,8,16]

The displayed error and min/max are those of ringing.h's displayed_error
(unshadowed B over a 256 x 128 grid of lobe axes, against the order-64 B).
"""

import argparse
import os
import time

import sdnative

WORLDS = "/usr/share/blender/datafiles/studiolights/world"
NAMES = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")
LOBES = (("lambert", 1.0), ("phong", 8.0), ("phong", 32.0), ("phong", 61.0))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--orders", default="4,8,16")
    orders = [int(s) for s in parser.parse_args().orders.split(",")]
    print("%-9s %-12s %3s  %-8s %9s  %-17s %-17s %-17s %6s" % (
        "HDRI", "lobe", "s", "window", "lambda", "displayed error", "clamped RMS", "min B / max B",
        "ms"))
    for name in NAMES:
        env = sdnative.load_environment(os.path.join(WORLDS, name + ".exr"))
        env.band_energies(0)  # the order-64 projection, once per map (not timed below)
        for lobe, sigma in LOBES:
            for s in orders:
                start = time.perf_counter()
                c = env.ringing_window(lobe, sigma, s)
                ms = 1e3 * (time.perf_counter() - start)
                label = "Lambert" if lobe == "lambert" else "Phong %g" % sigma
                print("%-9s %-12s %3d  %-8s %9.3g  %6.1f -> %6.1f %%  %6.1f -> %6.1f %%  %+6.1f -> %+6.1f %%  %6.0f" % (
                    name, label, s, c["window"], c["sloan_lambda"],
                    100 * c["unwindowed_error"], 100 * c["error"],
                    100 * c["unwindowed_l2_error"], 100 * c["l2_error"],
                    100 * c["unwindowed_min_over_max"], 100 * c["min_over_max"], ms))


if __name__ == "__main__":
    main()
