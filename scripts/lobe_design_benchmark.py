"""Lobe designs (Theorem 2.1, eq. 12): the search from scratch (sdnative.zonal_design) against the
add-on's builds (live/lobe_designs.py: continued from the nearest exponent already cached), node
counts and seconds per degree and Phong exponent.

    PYTHONPATH=build/native /usr/bin/python3 scripts/lobe_design_benchmark.py [--degrees 10,12,14]

For each degree, the add-on's cache starts empty: its first exponent is searched from scratch,
each next one continued from the nearest cached (the exponents are visited in the order given).
"""

import argparse
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "addon"))

from sd_lighting import native  # noqa: E402
from sd_lighting.live import lobe_designs  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--degrees", default="6,8,10,12,14")
    parser.add_argument("--sigmas", default="8,10,16,32,64,128,1000",
                        help="Phong exponents, in the order the add-on's cache meets them")
    parser.add_argument("--no-search", action="store_true",
                        help="only the add-on's builds (the search takes minutes from degree 16)")
    args = parser.parse_args()
    sd = native.get()
    sigmas = [float(x) for x in args.sigmas.split(",")]
    print("%6s %8s %13s %10s %13s %10s %8s" % ("degree", "sigma", "search nodes", "search s",
                                               "add-on nodes", "add-on s", "speedup"))
    for degree in (int(x) for x in args.degrees.split(",")):
        with tempfile.TemporaryDirectory() as directory:
            designs = lobe_designs.LobeDesigns(sd, directory)
            for sigma in sigmas:
                key = lobe_designs.design_key("phong", sigma, degree)
                start = time.perf_counter()
                design = designs.build(key)
                built = time.perf_counter() - start
                designs.files.save(key, design)
                search_nodes, search = "-", float("nan")
                if not args.no_search:
                    start = time.perf_counter()
                    search_nodes = len(sd.zonal_design("phong", sigma, degree)[1])
                    search = time.perf_counter() - start
                print("%6d %8g %13s %10.3f %13d %10.3f %8.1f" % (
                    degree, sigma, search_nodes, search, len(design.weights), built, search / built),
                    flush=True)


if __name__ == "__main__":
    main()
