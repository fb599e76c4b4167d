"""The automatic mode: per object, the cheapest setting whose error, measured on a sample of the
object before its bake (plan/accuracy.ErrorTable), stays within the target - and a line saying
why for each choice.

Among every method, s <= max_order, s' <= accuracy.MAX_VISIBILITY_ORDER and ray count, a setting
qualifies when its predicted error is within the target and its predicted bake within the bake
budget (plan/cost.bake_seconds); the one chosen has the fewest frame terms, then the fewest stored
floats, then the shortest bake. So a convex object, whose unshadowed result already meets the
target, stores no visibility; a diffuse one gets PRT (2), exact in V, when it is cheapest; and a
soft environment gets a lower s than one with a sun, whose truncation error is larger - unless the
sun is shaded on its own (Sharp Source Shadows): a Lambert lobe's table (and a glossy one's that
the prefiltered light draws) then measures every setting also with the map's bright sources taken
out (accuracy.Remainder), the target holding for the whole B, and for a Lambert lobe they are
taken where they pay (the setting chosen with them would be more than NEAR_BEST worse through SH
alone), usually at a lower s and fewer rays. When no
setting qualifies, the cheapest within NEAR_BEST of the most accurate one's error (within the
budget) is chosen and the reason says so: a last few percent of accuracy at many times the frame
cost is not worth it (the report's bowl under forest: PRT (8) at s = 7, s' = 4, 5022 ns per vertex
for 6.2 % against Cycles, where PRT (2) at s = 8 has 5.7 % at 300 ns).

Per-vertex or per-pixel evaluation follows the mesh's density on screen: `evaluation`.

Nothing here needs Blender.
"""

from dataclasses import dataclass, field

import numpy as np

from .. import methods
from ..bake import least_squares
from . import accuracy, cost

RAYS = (64, 128, 256, 512, 1024, 2048, 4096)
# Per-vertex shading blends B linearly across a triangle; once a triangle covers more pixels than
# this at the camera's resolution, evaluating per pixel (about 3 evaluations a pixel) shows the
# normal's and view's variation inside it at a cost the few vertices no longer dwarf.
PER_PIXEL_TRIANGLE_PIXELS = 50.0
NEAR_BEST = 1.1     # a setting within 10 % of the most accurate one's error is as good (see above)


@dataclass(frozen=True)
class Choice:
    """What the automatic mode chose for one object."""
    setting: accuracy.Setting
    error: float               # predicted relative RMS error
    frame_terms: int           # per vertex and colour
    floats: int                # stored per vertex
    bake_seconds: float
    met_target: bool
    reasons: tuple = field(default=())   # one line per choice, for the panel and the bake's record
    sources: object = None     # whether the map's bright sources are shaded on their own (None:
                               # not measured - none in the map, or a glossy lobe lit through SH
                               # alone: the scene's option)


@dataclass(frozen=True)
class _Candidate:
    setting: accuracy.Setting
    error: float
    frame_terms: int
    floats: int
    bake_seconds: float
    points: int                # that its bake traces

    def cost(self):
        return (self.frame_terms, self.floats, self.bake_seconds)


def _candidates(table, gaunt, vertices, threads, fixed, fitted_points, sources=False):
    for method_id in table.methods:
        method = methods.get(method_id)
        if fixed.get("method", method_id) != method_id:
            continue
        traced = fitted_points if fitted_points and least_squares.applies(method) else vertices
        for s in range(table.max_order + 1):
            visibility_orders = (range(accuracy.MAX_VISIBILITY_ORDER + 1)
                                 if method.uses_visibility_order else (0,))
            for sv in visibility_orders:
                if fixed.get("light_order", s) != s or (method.uses_visibility_order and
                                                        fixed.get("visibility_order", sv) != sv):
                    continue
                # The unshadowed shading reads none of the rays its bake traces.
                rays_options = (fixed["rays"],) if "rays" in fixed else RAYS
                for rays in rays_options if method.data is not None else rays_options[:1]:
                    setting = accuracy.Setting(method_id, s, sv, rays)
                    yield _Candidate(setting, table.error(setting, sources), method.frame_terms(s, sv, gaunt),
                                     cost.stored_floats(method, s, sv),
                                     cost.bake_seconds(method, s, sv, rays, traced, threads), traced)


def choose(table, target_error, gaunt, vertices, threads, bake_budget, fixed=None, fitted_points=None):
    """The Choice for an object from its ErrorTable, among the methods it measured: target_error
    relative RMS; gaunt: s, s' -> Gaunt term count (cost.gaunt_terms); vertices: the object's baked
    vertex count; threads: the bake's cores; bake_budget: seconds a chosen bake may take; fixed:
    the user's overrides, Setting fields to values (e.g. {"light_order": 6}); fitted_points: with
    Least Squares, the points its bake traces for the methods it fits (bake/least_squares.py:
    vertices and face centres). Raises ValueError when no measured setting matches the
    overrides."""
    fixed = dict(fixed or {})
    candidates = list(_candidates(table, gaunt, vertices, threads, fixed, fitted_points))
    if not candidates:
        raise ValueError("no measured setting matches the overrides %s" % fixed)
    best, qualified = _best(candidates, target_error, bake_budget)
    sources = None
    if table.measured_sources is not None:
        # The sources pay where the setting chosen with them would be more than NEAR_BEST worse
        # through SH alone; otherwise the SH alone does as well and their shadow maps cost frames.
        # A glossy lobe's prefiltered light is measured as exact with the sources in it, which the
        # atlas is not (a sun's highlight as the sampled lobe's spots): there the scene's option
        # decides, and the setting is chosen for what is drawn then.
        with_sources = list(_candidates(table, gaunt, vertices, threads, fixed, fitted_points, sources=True))
        best_with, qualified_with = _best(with_sources, target_error, bake_budget)
        alone = table.error(best_with.setting)
        sources = None if table.prefiltered else alone > NEAR_BEST * best_with.error
        if sources is not False:
            best, qualified, candidates = best_with, qualified_with, with_sources
    measured_with = table.measured_sources is not None and sources is not False
    reasons = _reasons(table, best, candidates, target_error, qualified, fixed, measured_with)
    if table.measured_sources is not None:
        reasons.insert(2 if fixed else 1, (   # after the visibility's line
            "Sources: as Sharp Source Shadows says (a glossy lobe's prefiltered light) - predicted "
            "%.1f %% with them on their own, %.1f %% through SH alone" if sources is None else
            "Sources: shaded on their own - predicted %.1f %% with them, %.1f %% through SH alone"
            if sources else "Sources: through SH - predicted %.1f %% with them on their own, %.1f %% "
            "through SH alone: not worth their shadow maps") % (100 * best_with.error, 100 * alone))
    return Choice(best.setting, best.error, best.frame_terms, best.floats, best.bake_seconds,
                  qualified, tuple(reasons), sources)


def _best(candidates, target_error, bake_budget):
    """(the candidate chosen, whether it met the target): the cheapest within the target and the
    budget, else the cheapest within NEAR_BEST of the most accurate one's error."""
    affordable = [c for c in candidates if c.bake_seconds <= bake_budget] or candidates
    qualified = [c for c in affordable if c.error <= target_error]
    if not qualified:
        most_accurate = min(c.error for c in affordable)
    near = qualified or [c for c in affordable if c.error <= NEAR_BEST * most_accurate]
    return min(near, key=_Candidate.cost), bool(qualified)


def projected_triangle_pixels(world_positions, triangles, view_projection, width, height):
    """The mean area in pixels of the triangles that face a camera and lie in front of it
    (view_projection: world -> clip, 4 x 4; width, height: the render's pixels), 0 when none."""
    points = np.c_[world_positions, np.ones(len(world_positions))] @ np.asarray(view_projection).T
    in_front = points[:, 3] > 1e-9
    pixels = points[:, :2] / np.where(in_front, points[:, 3], 1.0)[:, None] * (0.5 * np.array([width, height]))
    a, b, c = (pixels[triangles[:, k]] for k in range(3))
    area = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    seen = in_front[triangles].all(axis=1) & (area > 0.0)
    return float(area[seen].mean()) if seen.any() else 0.0


def evaluation(triangle_pixels):
    """(per_pixel, the reason's line) for an object whose triangles cover `triangle_pixels` pixels
    on average at the camera's resolution (None: no camera)."""
    if triangle_pixels is None:
        return False, "Evaluation: per vertex - no scene camera to size the triangles with"
    if triangle_pixels == 0.0:
        return False, "Evaluation: per vertex - none of its triangles faces the scene camera"
    per_pixel = triangle_pixels > PER_PIXEL_TRIANGLE_PIXELS
    return per_pixel, "Evaluation: per %s - a triangle covers %.0f pixels at the camera's resolution" \
        " (per pixel above %.0f)" % ("pixel" if per_pixel else "vertex", triangle_pixels,
                                     PER_PIXEL_TRIANGLE_PIXELS)


def _best_error(candidates, **fixed):
    matching = [c.error for c in candidates
                if all(getattr(c.setting, k) == v for k, v in fixed.items())]
    return min(matching) if matching else None


def _reasons(table, best, candidates, target, met, fixed, sources):
    setting = best.setting
    method = methods.get(setting.method)
    lines = ["Overridden: %s" % ", ".join("%s = %s" % kv for kv in sorted(fixed.items()))] if fixed else []
    lines.append("Visibility: %s - %.1f %% of the sampled rays blocked (cosine-weighted)" % (
        "none stored" if method.data is None else "needed", 100 * table.shadowing()))
    if met:
        lines.append("Method: %s - the fewest frame terms (%d per vertex) within the %.1f %% target"
                     % (method.label, best.frame_terms, 100 * target))
    else:
        lines.append("Method: %s - no setting reaches the %.1f %% target; the cheapest within %.0f %% "
                     "of the most accurate one's error" % (method.label, 100 * target, 100 * (NEAR_BEST - 1.0)))
    lower = _best_error(candidates, method=setting.method, light_order=setting.light_order - 1,
                        visibility_order=setting.visibility_order, rays=setting.rays)
    lines.append("s = %d: predicted error %.1f %%%s" % (
        setting.light_order, 100 * best.error,
        "" if lower is None else " (s = %d: %.1f %%)" % (setting.light_order - 1, 100 * lower)))
    if method.uses_visibility_order:
        lines.append("s' = %d: visibility's order (predicted above)" % setting.visibility_order)
    if method.data is not None:
        measured = table.measurement(setting, bool(sources))
        lines.append("Rays: %d - ray noise %.1f %% (measured %.1f %% at %d)" % (
            setting.rays, 100 * measured.noise * (measured.rays / setting.rays) ** 0.5,
            100 * measured.noise, measured.rays))
    # the rays alone, of the copy as it is: the panel's predicted bake time adds the refinement
    lines.append("Cost: %d floats per vertex; rays about %.1f s for its {:,} points before any refinement"
                 .format(best.points) % (best.floats, best.bake_seconds))
    return lines
