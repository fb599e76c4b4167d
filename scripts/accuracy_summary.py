#!/usr/bin/env python3
"""The accuracy-cost report's Markdown summary, plots and image strip from its JSON (issue 11).

    /usr/bin/python3 scripts/accuracy_summary.py docs/report [WORK]

reads DIR/accuracy_report.json (blender_tests/accuracy_report.py; stored compressed as
accuracy_report.json.gz, its cost model also as cost_model.json) and WORK/strip.npz (default
build/accuracy_report_work), and DIR/viewport_frames.json where it is there (the MSD / PRT frame
ratios at scale, from blender_tests/benchmark_viewport.py --json, for Table 1), and writes into DIR:
report.md, error_vs_frame_<scene>.png and error_vs_bake_<scene>.png (every Monte Carlo row, mean
over the HDRIs, per material, with the Pareto front), strip.png (Cycles, the add-on's previews, the
reference and each method at the vertices, and error heat maps). Needs matplotlib
(python3-matplotlib).
"""

import gzip
import json
import math
import os
import sys
from collections import defaultdict

import numpy as np

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# The method table (the add-on's methods.py, which needs no Blender) names the methods.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "addon"))
from sd_lighting.methods import METHODS  # noqa: E402

LABELS = {method.id: method.short_label for method in METHODS}
PALETTE = ("#d62728", "#ff7f0e", "#17becf", "#1f77b4", "#2ca02c", "#8c564b", "#999999", "#9467bd", "#e377c2")
COLOURS = {method.id: PALETTE[k % len(PALETTE)] for k, method in enumerate(METHODS)}
MATERIALS = ["lambert", "phong4", "phong16", "phong64", "mix"]


def setting(row):
    parts = ["s = %d" % row["s"]]
    if row.get("s_v") is not None:
        parts.append("s' = %d" % row["s_v"])
    if row.get("rays"):
        parts.append("%d rays" % row["rays"])
    return "%s, %s" % (LABELS[row["method"]], ", ".join(parts))


def mean_over_hdris(rows):
    """{(scene, material, method, s, s', rays): averaged row} over the HDRIs."""
    groups = defaultdict(list)
    for row in rows:
        if row["reference"] == "monte_carlo":
            groups[row["scene"], row["material"], row["method"], row["s"], row.get("s_v"), row.get("rays")].append(row)
    out = {}
    for key, group in groups.items():
        mean = dict(group[0])
        for field in ("rel_rms", "p99", "reference_se", "rel_rms_without_reference_noise"):
            mean[field] = float(np.mean([r[field] for r in group]))
        mean["hdris"] = len(group)
        out[key] = mean
    return out


def pareto(points):
    """Indices of the points (cost, error) no other point beats in both."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def plot(report, averaged, cost, label, name, out):
    scenes = report["config"]["scenes"]
    files = []
    for scene in scenes:
        fig, axes = plt.subplots(1, len(MATERIALS), figsize=(4.2 * len(MATERIALS), 4.0), sharey=True)
        for ax, material in zip(axes, MATERIALS):
            rows = [r for k, r in averaged.items() if k[0] == scene and k[1] == material and r.get(cost)]
            if not rows:
                ax.set_visible(False)
                continue
            points = [(r[cost], r["rel_rms"]) for r in rows]
            for method in LABELS:
                xs = [p for p, r in zip(points, rows) if r["method"] == method]
                if xs:
                    ax.scatter(*zip(*xs), s=10, alpha=0.6, color=COLOURS[method], label=LABELS[method])
            front = pareto(points)
            ax.plot([points[i][0] for i in front], [points[i][1] for i in front], "k-", lw=1.0, label="Pareto front")
            ax.scatter([points[i][0] for i in front], [points[i][1] for i in front], s=26, facecolors="none",
                       edgecolors="k")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title("%s, %s" % (scene, material))
            ax.set_xlabel(label)
            ax.grid(True, which="both", alpha=0.3)
        axes[0].set_ylabel("relative RMS error (mean over %d HDRIs)" % len(report["hdris"]))
        axes[0].legend(fontsize=7, loc="lower left")
        fig.tight_layout()
        path = "%s_%s.png" % (name, scene)
        fig.savefig(os.path.join(out, path), dpi=80)
        plt.close(fig)
        files.append(path)
    return files


def strip(work, out):
    """strip.png from the run's images (WORK/strip.npz); without them (the summary made again from
    the stored JSON) the run's strip.png already in `out`, if any."""
    path = os.path.join(work, "strip.npz")
    if not os.path.isfile(path):
        return "strip.png" if os.path.isfile(os.path.join(out, "strip.png")) else None
    data = np.load(path)
    images = {k[6:]: data[k] for k in data.files if k.startswith("image:")}
    vertex = {k[7:]: data[k] for k in data.files if k.startswith("vertex:")}
    reference = data["vertex_reference"]
    clip = data["vertex_clip"]
    ndc = clip[:, :2] / clip[:, 3:4]
    scale = float(np.percentile(reference.mean(axis=1), 99)) or 1.0
    cycles = images.pop("Cycles", None)
    panels_top = ([("Cycles", cycles)] if cycles is not None else []) + sorted(images.items())
    panels_bottom = [("reference (vertices)", reference)] + sorted(vertex.items())
    columns = max(len(panels_top), len(panels_bottom))
    fig, axes = plt.subplots(4, columns, figsize=(2.2 * columns, 9.0))
    for ax in axes.ravel():
        ax.axis("off")
    rms = math.sqrt(float(np.mean(reference ** 2)))
    for j, (title, image) in enumerate(panels_top):
        axes[0, j].imshow(np.clip(image[..., :3] / scale, 0, 1) ** (1 / 2.2))
        axes[0, j].set_title(title, fontsize=7)
        if cycles is not None and title != "Cycles":
            mask = (image[..., 3] > 0.99) & (cycles[..., 3] > 0.99)
            error = np.where(mask, np.abs(image[..., :3] - cycles[..., :3]).mean(axis=2), np.nan) / scale
            axes[1, j].imshow(error, cmap="magma", vmin=0, vmax=0.3)
            axes[1, j].set_title("|preview - Cycles| / B99", fontsize=7)
    for j, (title, values) in enumerate(panels_bottom):
        colours = np.clip(values / scale, 0, 1) ** (1 / 2.2)
        axes[2, j].scatter(ndc[:, 0], ndc[:, 1], c=colours, s=3)
        axes[2, j].set_title(title, fontsize=7)
        axes[2, j].set_aspect("equal")
        if j:
            error = np.sqrt(np.mean((values - reference) ** 2, axis=1)) / rms
            axes[3, j].scatter(ndc[:, 0], ndc[:, 1], c=error, cmap="magma", vmin=0, vmax=0.5, s=3)
            axes[3, j].set_title("error / RMS B: %.1f %%" % (100 * math.sqrt(float(np.mean((values - reference) ** 2))) / rms),
                                 fontsize=7)
            axes[3, j].set_aspect("equal")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "strip.png"), dpi=80)
    plt.close(fig)
    return "strip.png"


def percent(x):
    return "%.1f %%" % (100 * x) if x is not None else "-"


def best_settings(averaged, scene, material, tolerance=1.1):
    """(the smallest error of the grid, the cheapest setting by CPU frame cost within `tolerance`
    of it)."""
    rows = [r for k, r in averaged.items() if k[0] == scene and k[1] == material and r.get("frame_ns_per_vertex")]
    if not rows:
        return None, None
    best = min(r["rel_rms"] for r in rows)
    good = [r for r in rows if r["rel_rms"] <= tolerance * best]
    return best, min(good, key=lambda r: (r["frame_ns_per_vertex"], r["bake_seconds"]))


def ratio_text(values):
    return "%.2f-%.2fx" % (min(values), max(values)) if values else "-"


def findings(report, averaged, comparison):
    """The findings, in sentences with the measured numbers; comparison: automatic_against_hand_picked's."""
    out = []
    full = report["config"]["full_rays"]
    scenes = report["config"]["scenes"]
    # Settings per material: the cheapest within 10 % of the best, over the scenes.
    for material in MATERIALS:
        picks = [(scene,) + best_settings(averaged, scene, material) for scene in scenes]
        picks = [p for p in picks if p[2] is not None]
        if not picks:
            continue
        out.append("- **%s**: %s." % (material, "; ".join(
            "%s: %s (%s; best anywhere %s)" % (scene, setting(pick), percent(pick["rel_rms"]), percent(best))
            for scene, best, pick in picks)))
    # Orders: how the error of PRT (10) (lobe not truncated) falls with s, per material (mean over scenes).
    for material in ("lambert", "phong16", "phong64"):
        errors = []
        for s in report["config"]["orders"]:
            values = [averaged[k]["rel_rms"] for k in averaged if k[1] == material and k[2] == "prt_gaunt"
                      and k[3] == s and k[4] == max(report["config"]["visibility_orders"]) and k[5] == full]
            if values:
                errors.append("s = %d: %s" % (s, percent(float(np.mean(values)))))
        if errors:
            out.append("- %s, PRT (10) = MSD (12), s' = %d, %d rays, mean over the scenes and HDRIs: %s." % (
                material, max(report["config"]["visibility_orders"]), full, ", ".join(errors)))
    gpu = report["gpu_rows"]
    if gpu:
        def ratios(method, light, base, shading="vertex"):
            values = []
            for row in gpu:
                if row["method"] == method and row["light"] == light and row["shading"] == shading:
                    ref = next((r for r in gpu if r["scene"] == row["scene"] and r["method"] == base
                                and r["shading"] == shading), None)
                    if ref:
                        values.append((row["frame_ms"] / ref["frame_ms"], row["bytes_per_vertex"] / ref["bytes_per_vertex"]))
            return values
        for method, base in (("msd_visibility", "prt_matrix"), ("msd_lobe", "prt_gaunt")):
            for light in ("texture", "sh"):
                values = ratios(method, light, base)
                if values:
                    out.append("- %s (%s) against %s, per vertex, s = 4, s' = 2: GPU frame time %s, memory %s "
                               "(over the scenes)." % (LABELS[method], "band-limited texture" if light == "texture" else "SH sum",
                                                       LABELS[base], ratio_text([v[0] for v in values]),
                                                       ratio_text([v[1] for v in values])))
    for label in report.get("cycles_findings", [report["recommended"]]):
        cycles = [r for r in report["rows"] if r["reference"] == "cycles" and r["setting"] == label
                  and r["material"] == "lambert" and r["light"] == "sh"]
        for scene in scenes:
            rows = [r for r in cycles if r["scene"] == scene]
            if rows:
                out.append("- %s against Cycles at %s: per vertex %s, per pixel %s (over %s); %s, "
                           "bake %.2f s, %d bytes per vertex." % (
                               scene, label,
                               ratio_text_percent([r["rel_rms"] for r in rows if r["shading"] == "vertex"]),
                               ratio_text_percent([r["rel_rms"] for r in rows if r["shading"] == "pixel"]),
                               ", ".join(sorted({r["hdri"] for r in rows})),
                               ", ".join(sorted({"%s s = %d%s%s" % (
                                   LABELS[r["method"]], r["s"], "" if r["s_v"] is None else ", s' = %d" % r["s_v"],
                                   "" if r["rays"] is None else ", %d rays" % r["rays"]) for r in rows})),
                               rows[0]["bake_seconds"], rows[0]["bytes_per_vertex"]))
    ggx = ggx_rows(report, "prefiltered")
    if ggx:
        truncated = ggx_rows(report, "truncated")
        parts = []
        for base in sorted({r["base"] for r in ggx}):
            for roughness in sorted({r["roughness"] for r in ggx if r["base"] == base}):
                case = lambda rows: [r for r in rows if r["base"] == base and r["roughness"] == roughness]  # noqa: E731
                flips = [r["flip"] for r in case(ggx) if r.get("flip") is not None]
                parts.append("%s %.2f %s%s (truncated lobe %s)" % (
                    base, roughness, ratio_text_percent([r["rel_rms"] for r in case(ggx)]),
                    ", FLIP %.3f-%.3f" % (min(flips), max(flips)) if flips else "",
                    ratio_text_percent([r["rel_rms"] for r in case(truncated)])))
        out.append("- Principled BSDFs against Cycles at the panel's defaults, prefiltered glossy light (over %s and %s): "
                   "%s." % (", ".join(sorted({r["scene"] for r in ggx})), ", ".join(sorted({r["hdri"] for r in ggx})),
                            "; ".join(parts)))
    if comparison:
        def over(key, against):
            return ratio_text([c["automatic"][key] / c[against][key] for c in comparison if c[against]])
        better = sum(c["automatic"]["rel_rms"] <= c["fixed"]["rel_rms"] for c in comparison)
        out.append("- Automatic (2 %% target) against the fixed defaults (%s), against Cycles per vertex over %d "
                   "scene x HDRI cases: CPU frame cost %s, bake time %s, memory %s; error %s against %s "
                   "(lower or equal in %d of %d). Against the cheapest hand-picked setting at equal or lower "
                   "error (found in %d cases): frame cost %s, bake time %s, memory %s." % (
                       report["recommended"], len(comparison), over("frame_ns", "fixed"),
                       over("bake_seconds", "fixed"), over("bytes_per_vertex", "fixed"),
                       ratio_text_percent([c["automatic"]["rel_rms"] for c in comparison]),
                       ratio_text_percent([c["fixed"]["rel_rms"] for c in comparison]), better,
                       len(comparison), sum(c["best"] is not None for c in comparison),
                       over("frame_ns", "best"), over("bake_seconds", "best"), over("bytes_per_vertex", "best")))
    graded = [c for c in comparison if c["grid"]]
    if graded:
        out.append("- Over the whole grid (against the Monte Carlo reference, the automatic choice's setting at "
                   "the nearest grid rays at or below its own): the cheapest setting at equal or lower error has "
                   "%s of the automatic choice's CPU frame cost (%d of %d scene x HDRI cases: the same frame cost "
                   "or more)." % (ratio_text([c["grid"]["best"]["frame_ns_per_vertex"] /
                                                c["grid"]["automatic"]["frame_ns_per_vertex"] for c in graded]),
                                  sum(c["grid"]["best"]["frame_ns_per_vertex"] >=
                                      c["grid"]["automatic"]["frame_ns_per_vertex"] for c in graded), len(graded)))
    compared = [p for p in report.get("predictions", []) if not p["noise_limited"] and not p["extrapolated"]]
    if compared:
        ratios = [p["ratio"] for p in compared]
        front = [p["ratio_front_facing"] for p in compared if p["material"] != "lambert" and np.isfinite(p["ratio_front_facing"])]
        extrapolated = [p["ratio"] for p in report["predictions"] if p["extrapolated"] and not p["noise_limited"]]
        out.append("- The panel's predicted error (plan/accuracy.py) against the measured one: ratio %.2f-%.2f "
                   "(median %.2f) over %d settings at the table's own rays; extrapolated to other rays by its "
                   "1/sqrt(rays) noise model %s; glossy against the front-facing error a user sees %s." % (
                       min(ratios), max(ratios), float(np.median(ratios)), len(compared),
                       ratio_text(extrapolated), ratio_text(front)))
    return out


def frame_costs(report):
    """{(scene, method, s, s'): median CPU frame ns per vertex over the Monte Carlo grid's Lambert
    rows} (the frame cost does not depend on the rays or the HDRI)."""
    groups = defaultdict(list)
    for row in report["rows"]:
        if row["reference"] == "monte_carlo" and row["material"] == "lambert" and row.get("frame_ns_per_vertex"):
            groups[row["scene"], row["method"], row["s"], row.get("s_v")].append(row["frame_ns_per_vertex"])
    return {key: float(np.median(values)) for key, values in groups.items()}


def automatic_against_hand_picked(report):
    """Per scene and HDRI (against Cycles, per vertex, SH sum): the automatic mode's choice, the
    fixed defaults (the report's `recommended`) and the cheapest hand-picked Cycles setting at
    equal or lower error, each with its error and costs. The automatic mode's label is the Cycles
    setting whose label begins "Automatic". Returns a list of dicts."""
    costs = frame_costs(report)
    rows = [r for r in report["rows"] if r["reference"] == "cycles" and r["material"] == "lambert"
            and r["light"] == "sh" and r["shading"] == "vertex"]
    out = []
    for scene, hdri in sorted({(r["scene"], r["hdri"]) for r in rows}):
        here = [dict(r, frame_ns=costs.get((scene, r["method"], r["s"], r["s_v"]))) for r in rows
                if r["scene"] == scene and r["hdri"] == hdri]
        automatic = next((r for r in here if r["setting"].startswith("Automatic")), None)
        fixed = next((r for r in here if r["setting"] == report["recommended"]), None)
        if automatic is None or fixed is None or automatic["frame_ns"] is None:
            continue
        picked = [r for r in here if r is not automatic and r["frame_ns"] is not None
                  and r["rel_rms"] <= automatic["rel_rms"]]
        best = min(picked, key=lambda r: (r["frame_ns"], r["bake_seconds"], r["bytes_per_vertex"])) if picked else None
        out.append({"scene": scene, "hdri": hdri, "automatic": automatic, "fixed": fixed, "best": best,
                    "grid": grid_at_equal_error(report, automatic)})
    return out


def grid_at_equal_error(report, automatic):
    """The automatic choice against the whole Monte Carlo grid (Lambert, same scene and HDRI): its
    setting's grid row at the largest grid ray count not above its own (so an error at least its
    own: the comparison favours the hand-picked side), and the cheapest grid setting (frame cost,
    then bake time, memory) with an error no larger. None when the grid lacks the setting."""
    grid = [r for r in report["rows"] if r["reference"] == "monte_carlo" and r["material"] == "lambert"
            and r["scene"] == automatic["scene"] and r["hdri"] == automatic["hdri"] and r.get("frame_ns_per_vertex")]
    rays = automatic["rays"]
    below = [n for n in report["config"]["rays"] if rays is None or n <= rays]
    same = [r for r in grid if (r["method"], r["s"], r.get("s_v")) == (automatic["method"], automatic["s"], automatic["s_v"])
            and (r["rays"] is None or r["rays"] == max(below, default=None))]
    if not same:
        return None
    proxy = same[0]
    best = min((r for r in grid if r["rel_rms"] <= proxy["rel_rms"]),
               key=lambda r: (r["frame_ns_per_vertex"], r["bake_seconds"], r["bytes_per_vertex"]))
    return {"automatic": proxy, "best": best}


def grid_cell(row):
    return "%s: %s, %.0f ns, %.2f s, %d B" % (setting(row), percent(row["rel_rms"]), row["frame_ns_per_vertex"],
                                            row["bake_seconds"], row["bytes_per_vertex"])


def ggx_rows(report, light):
    """The GGX cases' rows of one light ("prefiltered" or "truncated"), in the order they ran."""
    return [r for r in report["rows"] if r["reference"] == "cycles" and r["material"] == "ggx" and r["light"] == light]


def ggx_table(report):
    """The Markdown section of the glossy cases (accuracy_report.ggx_cases): one row per scene,
    material, roughness and HDRI."""
    rows = ggx_rows(report, "prefiltered")
    if not rows:
        return []
    truncated = {(r["scene"], r["hdri"], r["base"], r["roughness"]): r for r in ggx_rows(report, "truncated")}
    flip = lambda row: "%.3f" % row["flip"] if row.get("flip") is not None else "-"  # noqa: E731
    lines = ["", "## Glossy: Principled BSDFs against Cycles (issue 28)", "",
             "Gold (metallic 1) and red plastic (metallic 0) Principled BSDFs on the measured object (Suzanne's "
             "white ground plane is in the frame and in the measure), baked at the "
             "panel's defaults (the automatic mode's choice in the setting column), against Cycles from the same "
             "camera: relative RMS over 4 x 4 blocks, bias (mean over Cycles' mean, per channel) and the mean "
             "HDR-FLIP per pixel (0: identical), with the prefiltered glossy light (the default), and baked instead "
             "with the seed's Phong lobe truncated at s (the add-on before issue 28; MSD (13), s = 8, s' = 4, 256 "
             "rays). Under a sun a near-mirror's highlight is smaller than a pixel, and both renders sample each "
             "pixel at its centre: one pixel then carries most of the relative RMS, which FLIP weighs as the eye "
             "does.", "",
             "| scene | material | roughness | HDRI | setting | error | bias (R, G, B) | FLIP | truncated lobe: error, FLIP "
             "| Cycles noise |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        old = truncated.get((row["scene"], row["hdri"], row["base"], row["roughness"]))
        lines.append("| %s | %s | %.2f | %s | %s | %s | %s | %s | %s | %s |" % (
            row["scene"], row["base"], row["roughness"], row["hdri"], setting(row),
            percent(row["rel_rms"]), ", ".join("%+.1f" % (100 * b) for b in row["bias"]), flip(row),
            "%s, %s" % (percent(old["rel_rms"]), flip(old)) if old else "-", percent(row["reference_se"])))
    return lines


def ratio_text_percent(values):
    return "%s-%s" % (percent(min(values)), percent(max(values))) if values else "-"


def markdown(report, averaged, plots, strip_file, viewport=None):
    comparison = automatic_against_hand_picked(report)
    lines = ["# Accuracy against cost: the measured report (issue 11)", ""]
    lines.append("Generated by `scripts/accuracy_report.sh` (blender_tests/accuracy_report.py, then "
                 "scripts/accuracy_summary.py) in %.0f s on Blender %s, %d CPU threads%s. Every row is in "
                 "[`accuracy_report.json.gz`](accuracy_report.json.gz); the cost model fitted from it is its "
                 "`cost_model`, also in [`cost_model.json`](cost_model.json)." % (report["wall_seconds"], report["blender"], report["cpu_threads"],
                                    ", GPU: " + report["gpu"] if report["gpu"] else ""))
    lines.append("")
    lines.append("Scenes (vertices measured): %s. HDRIs: %s. Materials: Lambert, Phong sigma = 4, 16, 64 and "
                 "the mix %g Lambert + %g Phong 16. Errors are relative RMS over the probe vertices (the "
                 "Monte Carlo reference, eq. 1, at %d probes, %d sample pairs for Lambert, %d for Phong; "
                 "glossy from %d views, front-facing points only) or over 4 x 4-pixel blocks (Cycles); "
                 "p99 is the 99th percentile of the per-point error over the RMS of B." % (
                     ", ".join("%s (%d)" % kv for kv in report["vertices"].items()), ", ".join(report["hdris"]),
                     report["mix"]["weights"][0], report["mix"]["weights"][1], report["config"]["probes"],
                     report["config"]["samples"], report["config"]["phong_samples"], 2))
    lines += ["", "## Findings", ""] + findings(report, averaged, comparison)
    lines += ["", "## Invariants", ""]
    for check in report["invariants"]:
        lines.append("- %s %s (%s)" % ("PASS" if check["ok"] else "FAIL", check["check"], check["detail"]))
    worst = max((e["max_relative_difference"] for e in report["equalities"]), default=float("nan"))
    lines.append("- MSD (13) against PRT (8) and MSD (12) against PRT (10), same orders and rays, measured on "
                 "%d cases: largest max |dB| / max |B| = %.2g." % (len(report["equalities"]), worst))

    lines += ["", "## Which settings to pick", "",
              "Per scene and material, mean over the HDRIs: the smallest error anywhere in the grid, and the "
              "cheapest setting (CPU frame cost) within 10 % of it; then the error of the add-on's defaults "
              "(MSD (13), s = 4, s' = 2) for comparison.", "",
              "| scene | material | best error | cheapest within 10 % | its error | frame ns/vertex | bake s | bytes/vertex | MSD (13) 4, 2 |",
              "|---|---|---|---|---|---|---|---|---|"]
    for scene in report["config"]["scenes"]:
        for material in MATERIALS:
            best, pick = best_settings(averaged, scene, material)
            if pick is None:
                continue
            default = averaged.get((scene, material, "msd_visibility", 4, 2, report["config"]["full_rays"]))
            lines.append("| %s | %s | %s | %s | %s | %.0f | %.2f | %d | %s |" % (
                scene, material, percent(best), setting(pick), percent(pick["rel_rms"]), pick["frame_ns_per_vertex"],
                pick["bake_seconds"], pick["bytes_per_vertex"], percent(default["rel_rms"]) if default else "-"))
    lines += ["", "Per HDRI (every scene averaged), the cheapest setting within 10 % of the best:", "",
              "| HDRI | " + " | ".join(MATERIALS) + " |", "|---|" + "---|" * len(MATERIALS)]
    by_hdri = defaultdict(list)
    for row in report["rows"]:
        if row["reference"] == "monte_carlo":
            by_hdri[row["hdri"], row["material"], row["method"], row["s"], row.get("s_v"), row.get("rays")].append(row)
    for hdri in report["hdris"]:
        cells = []
        for material in MATERIALS:
            rows = [(np.mean([r["rel_rms"] for r in group]), np.mean([r["frame_ns_per_vertex"] for r in group]), group[0])
                    for k, group in by_hdri.items() if k[0] == hdri and k[1] == material
                    and all(r.get("frame_ns_per_vertex") for r in group) and len(group) == len(report["config"]["scenes"])]
            if not rows:
                cells.append("-")
                continue
            best = min(e for e, _, _ in rows)
            error, _, pick = min((r for r in rows if r[0] <= 1.1 * best), key=lambda r: r[1])
            cells.append("%s: %s" % (setting(pick), percent(error)))
        lines.append("| %s | %s |" % (hdri, " | ".join(cells)))

    gpu = report["gpu_rows"]
    if gpu:
        lines += ["", "## MSD against PRT: frame time and memory", "",
                  "GPU frame time (1280 x 720, software rasteriser: %s) at s = 4, s' = 2, Lambert, 256 rays; "
                  "ns/vertex is the frame time over the vertices (at a few thousand vertices the frame's fixed "
                  "cost is most of it); ratios to PRT (8) for MSD (13) and to PRT (10) for MSD (12):" % report["gpu"], "",
                  "| scene | method | shading | L~ | frame ms | ns/vertex | bytes/vertex | design nodes mean/max | / PRT |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for row in gpu:
            base = "prt_matrix" if row["method"] == "msd_visibility" else "prt_gaunt" if row["method"] == "msd_lobe" else None
            ref = next((r for r in gpu if base and r["scene"] == row["scene"] and r["method"] == base
                        and r["shading"] == row["shading"]), None)
            lines.append("| %s | %s | %s | %s | %.1f | %.0f | %d | %s | %s |" % (
                row["scene"], LABELS[row["method"]], row["shading"], row["light"], row["frame_ms"], row["ns_per_vertex"],
                row["bytes_per_vertex"],
                "%.1f / %d" % (row["design_nodes_mean"], row["design_nodes_max"]) if row.get("design_nodes_mean") else "-",
                "%.2f" % (row["frame_ms"] / ref["frame_ms"]) if ref else "-"))

    lines += ["", "## The seed's Table 1 (s = 4, s' = 2) with measured costs", "",
              "The seed counts terms per vertex and floats per vertex; beside them the measured CPU cost "
              "(sdnative.shade, ns per vertex, median over the scenes: the whole call on both cores, the "
              "rotation of L included, over the scene's %d-%d vertices), the GPU frame time per vertex "
              "against PRT (8) for MSD (13) and PRT (10) for MSD (12) (the table above: L~ from the "
              "band-limited texture, and summed; at these sizes the frame's fixed cost is much of it: "
              "blender_tests/benchmark_viewport.py measures 100k vertices), the floats the add-on stores "
              "(without the normal; a design at its own length, three floats a node and its count) and "
              "the design nodes." % (min(report["vertices"].values()), max(report["vertices"].values()))]
    scales, measured = [], []   # benchmark_viewport.py --json: the same ratios where the vertices are many
    synthetic, baked = (viewport.get("synthetic"), viewport.get("baked")) if viewport else (None, None)
    if synthetic:
        scales.append(("synthetic", "%.0fk vertices, synthetic" % (synthetic["vertices"] / 1000.0)))
        baselines = ""
        if "smooth_ms" in synthetic:
            baselines = ("; whole frames, of which Blender's uniform-colour shader takes %.0f ms and its "
                         "smooth-colour one, which interpolates a colour per vertex as every method does, %.0f ms, "
                         "against PRT (8)'s %.0f ms" % (synthetic["uniform_ms"], synthetic["smooth_ms"],
                                                        synthetic["frame_ms"]["prt_matrix"]))
        measured.append("at %d vertices on synthetic designs (%.1f nodes on average, each vertex drawn "
                        "independently%s)" % (synthetic["vertices"], synthetic["design_nodes_mean"], baselines))
    if baked:
        scales.append(("baked", "%s baked" % baked["model"]))
        measured.append("on %s baked for real (%d vertices, %.1f nodes on average, neighbours alike; MSD (13) "
                        "stores %.3fx PRT (8)'s bytes)" % (baked["model"], baked["vertices"],
                                                          baked["design_nodes_mean"], baked["bytes"]))
    if measured:
        lines[-1] += (" Beside them, from blender_tests/benchmark_viewport.py --json (%s, Blender %s, medians of "
                      "%d interleaved rounds; without the bright sources' per-pixel shadows, the same for every method): the "
                      "same ratios %s." % (
                          viewport["renderer"], viewport["blender"], viewport["rounds"], ", and ".join(measured)))
    large = "".join(" | GPU frame / PRT, %s" % label for _, label in scales)
    lines += ["", "| formula | seed: terms | seed: floats | measured CPU ns/vertex (Lambert, Phong 16) "
              "| GPU frame / PRT (texture; SH sum)%s | stored floats | design nodes mean / max |" % large,
              "|---|---|---|---|---|%s---|---|" % ("---|" * len(scales))]
    gpu = report["gpu_rows"]

    def gpu_ratios(method, base, light):
        values = [row["frame_ms"] / ref["frame_ms"] for row in gpu
                  if row["method"] == method and row["light"] == light and row["shading"] == "vertex"
                  for ref in gpu if ref["scene"] == row["scene"] and ref["method"] == base and ref["shading"] == "vertex"]
        return "%.2f-%.2fx" % (min(values), max(values)) if values else "-"
    frame = defaultdict(list)
    for row in report["rows"]:
        if row["reference"] == "monte_carlo" and row["s"] == 4 and row.get("s_v") in (2, None) \
                and row["material"] in ("lambert", "phong16") and row.get("frame_ns_per_vertex"):
            frame[row["method"], row["material"]].append(row)
    seed = {"prt_gaunt": ("659", "9"), "msd_lobe": ("18 x 9 = 162", "9"), "prt_matrix": ("25 x 9 = 225", "225"),
            "msd_visibility": ("18 x 3 = 54", "72")}
    for method, (terms, floats) in seed.items():
        lam, pho = frame.get((method, "lambert"), []), frame.get((method, "phong16"), [])
        rows = lam or pho
        if not rows:
            continue
        nodes = [r for r in rows if r.get("design_nodes_mean")]
        base = {"msd_visibility": "prt_matrix", "msd_lobe": "prt_gaunt"}.get(method)
        at_scale = "".join(" | %.2fx; %.2fx" % (viewport[k][method]["texture"], viewport[k][method]["sh"])
                           if method in viewport[k] else " | -" for k, _ in scales)
        lines.append("| %s | %s | %s | %.0f, %.0f | %s%s | %d | %s |" % (
            LABELS[method], terms, floats, np.median([r["frame_ns_per_vertex"] for r in lam]) if lam else float("nan"),
            np.median([r["frame_ns_per_vertex"] for r in pho]) if pho else float("nan"),
            "%s; %s" % (gpu_ratios(method, base, "texture"), gpu_ratios(method, base, "sh")) if base else "-", at_scale,
            int(np.median([r["bytes_per_vertex"] for r in rows]) // 4),
            "%.1f / %d" % (np.mean([r["design_nodes_mean"] for r in nodes]), max(r["design_nodes_max"] for r in nodes))
            if nodes else "-"))

    cycles = [r for r in report["rows"] if r["reference"] == "cycles" and r["material"] == "lambert"]
    if cycles:
        lines += ["", "## How far from Cycles", "",
                  "The add-on's preview (bake, live shading with its ringing window and clamp) against Cycles from the "
                  "same camera, Lambert (white Diffuse BSDF), relative RMS over 4 x 4 blocks (Cycles' own noise, from "
                  "two seeds, beside it):", "",
                  "| scene | HDRI | setting | s | shading | L~ | error | p99 | Cycles noise | bake s |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for row in cycles:
            lines.append("| %s | %s | %s | %d | %s | %s | %s | %s | %s | %.2f |" % (
                row["scene"], row["hdri"], row["setting"], row["s"], row["shading"], row["light"], percent(row["rel_rms"]), percent(row["p99"]),
                percent(row["reference_se"]), row["bake_seconds"]))

    lines += ggx_table(report)

    if comparison:
        def cell(row):
            return "%s: %s, %.0f ns, %.2f s, %d B" % (
                setting(row), percent(row["rel_rms"]), row["frame_ns"], row["bake_seconds"], row["bytes_per_vertex"])
        lines += ["", "## Automatic against hand-picked settings (issue 10)", "",
                  "Against Cycles, per vertex: the automatic mode's choice, the fixed defaults (%s) and the "
                  "cheapest of the hand-picked settings above whose error is equal or lower (CPU frame cost "
                  "from the grid, then bake time and memory); each as setting: error, frame ns per vertex, bake "
                  "seconds, bytes per vertex." % report["recommended"], "",
                  "| scene | HDRI | automatic | fixed defaults | cheapest hand-picked at equal error |",
                  "|---|---|---|---|---|"]
        for c in comparison:
            lines.append("| %s | %s | %s | %s | %s |" % (c["scene"], c["hdri"], cell(c["automatic"]), cell(c["fixed"]),
                                                     cell(c["best"]) if c["best"] else "none as accurate"))
        lines += ["", "Over the whole grid (Lambert, against the Monte Carlo reference at the probes): the "
                  "automatic choice's setting (at the largest grid ray count not above its own, so an error at "
                  "least its own) and the cheapest grid setting with an error no larger; setting: error, CPU frame "
                  "ns per vertex, bake seconds, bytes per vertex.", "",
                  "| scene | HDRI | automatic's setting | cheapest at equal or lower error | frame cost ratio |",
                  "|---|---|---|---|---|"]
        for c in comparison:
            if c["grid"]:
                a, b = c["grid"]["automatic"], c["grid"]["best"]
                lines.append("| %s | %s | %s | %s | %.2f |" % (
                    c["scene"], c["hdri"], grid_cell(a), grid_cell(b),
                    b["frame_ns_per_vertex"] / a["frame_ns_per_vertex"]))

    lines += ["", "## Plots", ""]
    lines += ["![%s](%s)" % (p, p) for p in plots]
    if strip_file:
        lines += ["", "## Image strip (Suzanne, forest.exr, Lambert)", "",
                  "Top: Cycles and the add-on's previews, then |preview - Cycles|; below: the reference at the "
                  "vertices and each method (s = 4, s' = 2, 1024 rays) at the vertices, then its error.", "",
                  "![strip](%s)" % strip_file]
    model = report["cost_model"]
    lines += ["", "## The fitted cost model", "",
              "frame ns per vertex = intercept + ns_per_term x terms (per method and lobe); bake seconds = "
              "vertices x rays x seconds_per_vertex_per_ray (per kind of data), a design bake's seconds per vertex "
              "at its orders (1024 rays).", "",
              "| method | lobe | terms | intercept ns | ns/term |", "|---|---|---|---|---|"]
    for method, lobes in model["frame_ns_per_vertex"].items():
        for lobe, fit in lobes.items():
            lines.append("| %s | %s | %s | %.1f | %.3f |" % (LABELS[method], lobe, fit["terms"], fit["intercept_ns"],
                                                            fit["ns_per_term"]))
    lines += ["", "| bake data | seconds per vertex per ray (median) |", "|---|---|"]
    for kind, fit in model["bake_seconds_per_vertex_per_ray"].items():
        lines.append("| %s | %.3g |" % (kind, fit["median"]))
    for orders, fit in model["design_bake_seconds_per_vertex"].items():
        lines.append("| design (s, s') = (%s) | %.3g (%.3g s per vertex) |" % (
            orders, fit["median_seconds_per_vertex_per_ray"], fit["median_seconds_per_vertex"]))
    return "\n".join(lines) + "\n"


def load(out):
    """The report's JSON; a fresh accuracy_report.json (tens of MB for the full grid) is stored
    as accuracy_report.json.gz, with its cost model also in cost_model.json."""
    path = os.path.join(out, "accuracy_report.json")
    if os.path.isfile(path):
        with open(path) as f:
            report = json.load(f)
        with gzip.open(path + ".gz", "wt") as f:
            json.dump(report, f, separators=(",", ":"))
        with open(os.path.join(out, "cost_model.json"), "w") as f:
            json.dump(report["cost_model"], f, indent=1)
        os.remove(path)
        return report
    with gzip.open(path + ".gz", "rt") as f:
        return json.load(f)


def main():
    out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "docs/report")
    work = os.path.abspath(sys.argv[2] if len(sys.argv) > 2 else "build/accuracy_report_work")
    report = load(out)
    averaged = mean_over_hdris(report["rows"])
    plots = plot(report, averaged, "frame_ns_per_vertex", "CPU frame cost (ns per vertex)", "error_vs_frame", out)
    plots += plot(report, averaged, "bake_seconds", "bake time (s)", "error_vs_bake", out)
    strip_file = strip(work, out)
    viewport = None
    if os.path.isfile(os.path.join(out, "viewport_frames.json")):
        with open(os.path.join(out, "viewport_frames.json")) as f:
            viewport = json.load(f)
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write(markdown(report, averaged, plots, strip_file, viewport))
    print("accuracy summary: %s (%d plots%s)" % (os.path.join(out, "report.md"), len(plots),
                                                 ", strip.png" if strip_file else ""))


if __name__ == "__main__":
    main()
