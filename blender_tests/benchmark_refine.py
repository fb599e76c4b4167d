"""What refinement and least squares cost and give: for each asset and HDRI of
test_cycles_parity.py, the preview against Cycles (relative RMS over 4 x 4 blocks) with Refine off
and at each vertex budget, each with Least Squares off and on, beside the bake's time, vertices
and memory - measured in one run, printed as a table with ratios to the plain bake (neither).
With --without, also the last budget with Least Squares on (the defaults) without each of:
- `origins`: the ray origins off the walls (sdnative.bake_transfer's offset_origins=False for
  every bake: each vertex's rays start along its normal, as before the fix);
- `corners`: corner data (corners.NORMAL_TOLERANCE_DEGREES at 180: the corners of a mesh vertex
  split only by material slot and albedo UV, each copy with its corners' mean normal, as on a
  welded mesh; a file whose vertices are already split at hard edges, as glTF's are, keeps its
  split).
With --texture-space, also a bake with texture-space data at each lightmap size (Refine and
Least Squares then do not apply); its memory counts the stored texels' data beside the vertices'.

    blender -b --factory-startup --python blender_tests/benchmark_refine.py -- --zip Z --out DIR
        [--assets engine,house,wuson] [--hdris forest.exr,sunrise.exr] [--budgets 100000,250000]
        [--least-squares off,on] [--without origins,corners] [--texture-space 1024,2048]
"""

import argparse
import contextlib
import functools
import os
import sys
from unittest import mock

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import accuracy_scenes  # noqa: E402
import test_cycles_parity as parity  # noqa: E402


def options():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--assets", default=",".join(parity.ASSETS))
    parser.add_argument("--hdris", default=",".join(parity.HDRIS))
    parser.add_argument("--budgets", default="100000,250000,500000")
    parser.add_argument("--least-squares", default="off,on")
    parser.add_argument("--without", default="")
    parser.add_argument("--texture-space", default="")
    return parser.parse_known_args(argv)[0]


def without(package, fix):
    """A context in which the add-on's bakes run without `fix` (the module's doc)."""
    if fix == "origins":
        sdnative = package.native.get()
        return mock.patch.object(sdnative, "bake_transfer",
                                 functools.partial(sdnative.bake_transfer, offset_origins=False))
    if fix == "corners":
        return mock.patch.object(package.bake.corners, "NORMAL_TOLERANCE_DEGREES", 180.0)
    raise ValueError("--without takes origins and corners, not %r" % fix)


def main():
    args, opts = sdtest.arguments(), options()
    package = sdtest.install_addon(args.zip)
    budgets = [int(b) for b in opts.budgets.split(",") if b]
    fits = [{"off": False, "on": True}[x] for x in opts.least_squares.split(",")]
    runs = [(budget, fit, "", 0) for budget in [None] + budgets for fit in fits]
    runs += [(budgets[-1] if budgets else None, True, fix, 0) for fix in opts.without.split(",") if fix]
    runs += [(None, False, "", int(size)) for size in opts.texture_space.split(",") if size]
    rows = []
    for name in opts.assets.split(","):
        scene, obj, texture = parity.build(name)
        for hdri in opts.hdris.split(","):
            accuracy_scenes.set_hdri(texture, sdtest.hdri(hdri))
            stem = os.path.join(args.out, "%s_%s" % (name, hdri[:-4]))
            theirs, noise, _ = parity.cycles(scene, stem)
            for budget, fit, fix, size in runs:
                if budget is not None:
                    scene.sd_lighting.refine_max_vertices = budget
                with without(package, fix) if fix else contextlib.nullcontext():
                    image, info = parity.preview(scene, obj, budget is not None, stem + "_bench.exr", fit, size)
                rms = parity.compare(image, theirs)[0]
                seconds = info["seconds"]   # refinement, least squares and the texels included
                rows.append((name, hdri[:-4], budget, fit, fix, size, rms, info, seconds))
                print("%s %s budget %s, least squares %s%s%s: %.1f %% (Cycles noise %.2f %%), %d vertices, "
                      "%.2f s, %s" % (name, hdri, budget, fit, ", without " + fix if fix else "",
                                      ", texture space %d (%d texels)" % (size, info.get("lightmap_texels", 0))
                                      if size else "", 100 * rms, 100 * noise, info["vertices"], seconds,
                                      info["method"]), flush=True)
    print("\n| asset | HDRI | refine | least squares | without | texture space | error vs Cycles | vertices "
          "| bake | bake / plain | memory |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, hdri, budget, fit, fix, size, rms, info, seconds in rows:
        base = next(r[8] for r in rows if r[:4] == (name, hdri, None, fits[0]) and not r[4] and not r[5])
        print("| %s | %s | %s | %s | %s | %s | %.1f %% | %d | %.1f s | %.1fx | %.1f MB |" % (
            name, hdri, "off" if budget is None else "max %d vertices" % budget, "on" if fit else "off",
            fix or "-", "%d x %d" % (size, size) if size else "-", 100 * rms, info["vertices"], seconds,
            seconds / max(base, 1e-9),
            (info["vertices"] + info.get("lightmap_stored", 0)) * info["bytes_per_vertex"] / 1e6))
    return 0


sdtest.run(main)
