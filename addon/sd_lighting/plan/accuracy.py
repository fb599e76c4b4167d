"""The error each shading setting would have on an object, measured before its bake on a sample of
its vertices against the Monte Carlo reference of eq. (1) (sdnative.reference): what the
automatic mode chooses from (plan/automatic.py) and what the panel predicts.

The sample is a few triangles drawn at random (plan/bake_time.sample_mesh) baked against the
whole object and its occluders, so each sampled vertex sees what it sees in the bake. One bake at
the largest orders serves every order: the baked arrays of order s, s' are prefixes of those of
a higher order (the same rays project onto the same basis), so each setting is the shading of
truncated arrays, no further rays. A method's error at its own orders mixes two parts, told
apart by a second bake with another seed:
- the truncation of L, V and the lobe at s, s' (and the missing shadows of the methods without V),
  which more rays do not lower;
- the bake's ray noise, which falls as 1/sqrt(rays) (the difference of the two seeds' results is
  sqrt(2) times it).
The reference's own noise is removed from the squared error (its variance is known), so a
reference noisier than the target still measures it without bias.

MSD (13) equals PRT (8) and MSD (12) equals PRT (10) for the same rays and orders (Theorems 2.2
and 2.1), so their errors are those of the PRT forms, which need no designs (methods.Method.equal_to).

A glossy lobe the live shading lights by the prefiltered environment (*Prefiltered Glossy*) is
measured as it is drawn: the lobe's unshadowed light, exact (the reference with nothing in the
way but the surface's own tangent plane, the same samples), times the setting's visibility ratio
(msd-notes, "Glossy light"), over the sampled vertices that face the eye (the two references'
noise largely cancels where V = 1, so removing the reference's variance puts these errors low by
at most its own error). Its
truncated B alone would put every setting near 100 % off for a sharp lobe, and the cheapest,
with little or no shadowing, was often chosen. Where the live shading also traces that lobe's
visibility (*Reflection Rays*), it is drawn as its shadowed light whatever the setting: the
setting's error is then the other lobe's alone (a plastic's Lambert lobe), and a metal's is none,
so the cheapest setting is chosen - its bake is not drawn.

Nothing here needs Blender; the sdnative module is passed in.
"""

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from .. import methods as method_table
from ..scene import lobes
from . import bake_time

SAMPLE_TRIANGLES = 96        # about 250 sampled vertices
REFERENCE_SAMPLES = 2048     # sample pairs per vertex of the reference
MAX_VISIBILITY_ORDER = 4     # the largest s' measured
SHADE_SHARE = 0.5            # a sampled vertex the sources give less of its light is in their shade
MIN_SHADE_VERTICES = 16      # fewer in the shade: their error is not measured on its own
SHADE_FLOOR = 0.05           # of the sample's mean light: darker vertices are not in the shade part


def relative_error(values, reference, reference_variance=None, whole=None):
    """Relative RMS error of `values` against `reference` over points and channels ([N, 3]), with
    the reference's own variance (its squared standard error, [N, 3]) removed from the square;
    relative to `whole` (default: the reference), e.g. the remainder's error against the B of the
    whole map."""
    difference = np.mean(np.sum((np.asarray(values) - reference) ** 2, axis=1))
    if reference_variance is not None:
        difference = max(difference - np.mean(np.sum(reference_variance, axis=1)), 0.0)
    energy = np.mean(np.sum(np.asarray(reference if whole is None else whole) ** 2, axis=1))
    return float(np.sqrt(difference / energy)) if energy > 0.0 else 0.0


@dataclass(frozen=True)
class Setting:
    """What a bake and its live shading are set to (methods.py ids)."""
    method: str
    light_order: int
    visibility_order: int
    rays: int


@dataclass(frozen=True)
class Measured:
    """A setting's error on the sample at the rays it was measured with, split into its parts."""
    truncation: float        # what more rays do not lower
    noise: float             # the ray noise at `rays`
    rays: int

    def at(self, rays):
        """The relative RMS error with `rays` rays per vertex."""
        return float(np.hypot(self.truncation, self.noise * np.sqrt(self.rays / rays)))


@dataclass
class Sample:
    """An object's sampled vertices and what they see: vertices, normals [n, 3], triangles [t, 3]
    of the sample; views [n, 3] (unit, to the eye) or None; occluders: the whole object and every
    other object (bake_transfer's keywords occluder_vertices, occluder_triangles) or {}."""
    vertices: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    views: object
    occluders: dict

    @classmethod
    def of_mesh(cls, vertices, normals, triangles, occluders=None, views=None, seed=0,
                count=SAMPLE_TRIANGLES):
        """A sample of `count` triangles of a mesh; the mesh itself joins `occluders` (the other
        objects', bake_transfer's keywords). views: a function of the sampled vertices giving
        their view directions, or None."""
        sample_vertices, sample_normals, sample_triangles = bake_time.sample_mesh(
            vertices, normals, triangles, count, seed)
        blockers = [(np.asarray(vertices, dtype=np.float64), np.asarray(triangles).reshape(-1, 3))]
        if occluders:
            blockers.append((occluders["occluder_vertices"], occluders["occluder_triangles"]))
        base = np.cumsum([0] + [len(v) for v, _ in blockers])
        joined = {"occluder_vertices": np.concatenate([v for v, _ in blockers]),
                  "occluder_triangles": np.concatenate(
                      [t + b for (_, t), b in zip(blockers, base)]).astype(np.int32)}
        return cls(sample_vertices, sample_normals, sample_triangles,
                   None if views is None else views(sample_vertices), joined)


def _reporter(start, share, progress, stop):
    """A native progress callback reporting start + share times its own fraction to
    progress(fraction), and cancelling when stop() says so."""
    def report(done, total):
        if progress is not None:
            progress(start + share * done / max(total, 1))
        return stop is None or not stop()
    return report


@dataclass
class Remainder:
    """The map without its bright sources (scene/environment.source_split), which the live shading
    lights through SH while each source is shaded on its own: its sdnative.Environment, and
    order -> its unrotated L (as ErrorTable's `light`)."""
    environment: object
    light: object


class ErrorTable:
    """Every setting's measured error on one sample under one environment and lobe.

    sdnative: the module; environment: its Environment (the reference reads the full-resolution
    map); light: order -> the unrotated L of that order the live shading uses ([(s+1)^2, 3]);
    rotation: g R, the environment's rotation into the bake space (as shade's `rotation`);
    methods: the ids (methods.py) to measure; orders s up to max_order and s' up to
    MAX_VISIBILITY_ORDER; rays: the bake's rays per vertex; stop: returns True to cancel (the
    measurement then raises InterruptedError); diffuse_share: with a Phong lobe, the share of a
    Lambert lobe shaded besides it (scene/lobes.Lobes): B and its reference are then the two
    lobes' sum with these weights; progress(fraction) is called as the references (the first half)
    and the bakes (the second) go. remainder: a Remainder, to measure each setting also with the
    sources shaded on their own (measured_sources): their exact light added to the remainder's SH
    result, whose error is then the remainder's against its own reference, relative to the whole
    map's B (the sources' shadow maps and disc model taken as exact); or None. With a remainder,
    both are measured over the whole sample and over the vertices in the sources' shade
    (SHADE_SHARE), relative to their own B, the larger counting: a view of that side shows it.
    prefiltered: a Phong lobe is drawn by the prefiltered light times the visibility ratio (see
    the module's doc), with a remainder the remainder's prefiltered light (the sources' highlights
    taken as exact too); traced: its visibility is traced too, the lobe drawn as its shadowed
    light (the module's doc)."""

    def __init__(self, sdnative, sample, environment, light, lobe, exponent, rotation, methods,
                 max_order, rays, seed=0, stop=None, diffuse_share=0.0, progress=None, remainder=None,
                 prefiltered=False, traced=False):
        self.lobe, self.exponent, self.rays = lobe, float(exponent), int(rays)
        self.max_order = int(max_order)
        self.prefiltered = bool(prefiltered) and lobe != "lambert"
        self.traced = self.prefiltered and bool(traced)
        self._lobes = [(lobe, self.exponent, 1.0 - diffuse_share)]
        if diffuse_share > 0.0:
            self._lobes.append(("lambert", 1.0, float(diffuse_share)))
        self.methods = tuple(m for m in methods
                             if lobe == "lambert" or not method_table.get(m).lambert_only)
        self._sd, self._sample, self._rotation = sdnative, sample, rotation
        self._views = sample.views if sample.views is not None else sample.normals
        count = (1 + (remainder is not None)) * (1 + self.prefiltered)
        references = iter(range(count))
        self._progress = [_reporter(0.5 * k / count, 0.5 / count, progress, stop)
                          for k in range(count)] + [_reporter(0.5, 0.5, progress, stop)]

        def measured_reference(env, occluded=True):
            """(B, its standard error, lobe 0's (B, error) alone) of the table's lobes (occluded),
            or lobe 0's where V = 1 - what the prefiltered light stands for (None without it);
            progress in the order made."""
            if not occluded and not self.prefiltered:
                return None, None, None
            lobe_weights = None if occluded else [(self.lobe, self.exponent, 1.0)]
            return self._reference(env, seed, stop, self._progress[next(references)], lobe_weights, occluded)

        def traced_reference(first, whole_error):
            """(lobe 0's shadowed light, the variance of the table's reference without its part) -
            what the traced lobe is drawn as (None without tracing), from measured_reference's
            lobe 0 `first`. Its noise is the reference's own, so it is not the setting's error."""
            if not self.traced:
                return None, whole_error ** 2
            value, error = first
            return value, np.maximum(whole_error ** 2 - (self._lobes[0][2] * error) ** 2, 0.0)
        self.reference, error, first = measured_reference(environment)
        self._open_reference = measured_reference(environment, occluded=False)[0]
        self._traced_reference, self._traced_variance = traced_reference(first, error)
        self.reference_variance = error ** 2
        self.reference_error = relative_error(self.reference + np.sqrt(self.reference_variance),
                                              self.reference)   # its own, over the sample
        # a glossy vertex turned from the eye is not drawn, and its lobe lies below its plane
        seen = np.ones(len(sample.vertices), dtype=bool)
        if self.prefiltered and sample.views is not None:
            facing = np.einsum("ij,ij->i", sample.normals, sample.views) > 0.0
            seen = facing if facing.any() else seen
        parts = [seen]
        if remainder is not None:
            remainder_reference, remainder_error, remainder_first = measured_reference(remainder.environment)
            remainder_open = measured_reference(remainder.environment, occluded=False)[0]
            remainder_traced, remainder_variance = traced_reference(remainder_first, remainder_error)
            # the vertices the sources give under half their light: a view of that side shows the
            # error against their own B, which the whole sample's B would hide
            luminance = np.asarray(lobes.LUMINANCE)
            whole = self.reference @ luminance
            shade = seen & (remainder_reference @ luminance >= (1.0 - SHADE_SHARE) * whole) & \
                (whole > SHADE_FLOOR * np.mean(whole))   # not the unlit, whose error nobody sees
            if MIN_SHADE_VERTICES <= shade.sum() < seen.sum():
                parts.append(shade)
        measured = [method_table.get(m) for m in sorted({method_table.get(m).measured_as for m in self.methods})]
        bakes = self._bakes(measured, seed, stop)
        # The cosine-weighted fraction of the hemisphere the rays escape through: T_00 against
        # T_00 of the same rays with nothing in their way (the vertices as probes).
        free = sdnative.bake_transfer(sample.vertices, sample.normals, np.zeros((0, 3), np.int32),
                                      rays=self.rays, seed=seed, transfer_order=0)
        self.lit_fraction = np.asarray(bakes[0]["transfer"])[:, 0] / np.asarray(free["transfer"])[:, 0]
        self.measured = self._measure(measured, bakes, light, self.reference, self._traced_variance, stop, parts,
                                      self._open_reference, self._traced_reference)
        self.measured_sources = None if remainder is None else self._measure(
            measured, bakes, remainder.light, remainder_reference, remainder_variance, stop, parts,
            remainder_open, remainder_traced)

    def _measure(self, measured, bakes, light, reference, variance, stop, parts=None, open_reference=None,
                 traced_reference=None):
        """{(method, s, s'): [Measured per part]} of the two bakes shaded with `light` against
        `reference` (of variance `variance`: without the traced lobe's part, which the shading
        shares), relative to the whole map's B, over each of `parts` (masks of the sample;
        default: all of it); open_reference: lobe 0's unshadowed light of the same map
        (prefiltered); traced_reference: its shadowed light (traced), or None."""
        parts = [slice(None)] if parts is None else parts
        out = {}
        for method in measured:
            for s in range(self.max_order + 1):
                for sv in range(MAX_VISIBILITY_ORDER + 1) if method.uses_visibility_order else (0,):
                    if stop is not None and stop():
                        raise InterruptedError("cancelled")
                    first, second = (self._shade(method, s, sv, bake, light, open_reference, traced_reference)
                                     for bake in bakes)
                    out[(method.id, s, sv)] = []
                    for rows in parts:
                        noise = relative_error(first[rows], second[rows], whole=self.reference[rows]) / np.sqrt(2.0)
                        total = relative_error(first[rows], reference[rows], variance[rows], whole=self.reference[rows])
                        out[(method.id, s, sv)].append(
                            Measured(float(np.sqrt(max(total ** 2 - noise ** 2, 0.0))), noise, self.rays))
        return out

    def _reference(self, environment, seed, stop, progress, lobe_weights=None, occluded=True):
        """sdnative.reference on the sample (one scene: against a large mesh its build is most of
        the time), cancelled within a few vertices by stop: of `lobe_weights` (default: the
        table's lobes), the weighted sum and its standard error, and the first lobe's (B, error)
        unweighted; occluded False: with nothing in the way. A prefiltered lobe is cut at each
        vertex's tangent plane, as the split sum's and Cycles' are."""
        sample = self._sample
        triangles = sample.triangles if occluded else np.zeros((0, 3), dtype=np.int32)
        try:
            parts = [(weight, self._sd.reference(
                environment, sample.vertices, sample.normals, triangles, views=self._lobe_views(lobe),
                rotation=self._rotation, lobe=lobe, exponent=exponent, samples=REFERENCE_SAMPLES,
                seed=seed, progress=progress, horizon=self.prefiltered, **(sample.occluders if occluded else {})))
                for lobe, exponent, weight in (lobe_weights or self._lobes)]
        except self._sd.BakeCancelled as exc:
            raise InterruptedError("cancelled") from exc
        radiance = sum(weight * np.asarray(value) for weight, (value, _) in parts)
        error = np.sqrt(sum((weight * np.asarray(e)) ** 2 for weight, (_, e) in parts))
        return radiance, error, tuple(np.asarray(x) for x in parts[0][1])

    def _lobe_views(self, lobe):
        """The sampled views a lobe reads (Lambert: none)."""
        return self._views if lobe != "lambert" else None

    def _bakes(self, methods, seed, stop):
        """Two independent bakes of the sample (their difference is the rays' noise), as one call:
        the sample twice over, each vertex's copy with rays of its own rotation (one scene: against
        a large mesh its build is most of the time)."""
        arguments = {}
        for method in methods:
            arguments.update(method.bake_arguments(self.max_order, MAX_VISIBILITY_ORDER))
        arguments.setdefault("transfer_order", 0)     # for lit_fraction
        sample, count = self._sample, len(self._sample.vertices)
        twice = dict(self._sd.bake_transfer(
            np.concatenate([sample.vertices] * 2), np.concatenate([sample.normals] * 2),
            np.concatenate([sample.triangles, sample.triangles + count]), rays=self.rays, seed=seed,
            progress=self._progress[-1], **arguments, **sample.occluders))
        return [{key: value[half * count:(half + 1) * count]
                 for key, value in twice.items() if isinstance(value, np.ndarray) and len(value) == 2 * count}
                for half in (0, 1)]

    def _shade(self, method, s, sv, bake, light, open_reference=None, traced_reference=None):
        data = {}
        if method.data is not None:   # the arrays of order s, s': prefixes of the baked ones
            shape = method.data.shape(s, sv) if method.data.shape else ()
            for key in method.data.keys:
                data[key] = np.ascontiguousarray(bake[key][(slice(None),) + tuple(slice(0, n) for n in shape)])
        if method.uses_visibility_order:
            data["visibility_order"] = sv
        out, coefficients = 0.0, light(s)
        for k, (lobe, exponent, weight) in enumerate(self._lobes):
            b = self._sd.shade(method.id, coefficients, self._sample.normals, views=self._lobe_views(lobe),
                               rotation=self._rotation, lobe=lobe, exponent=exponent, **data)
            if k == 0 and traced_reference is not None:
                b = traced_reference
            elif k == 0 and self.prefiltered:
                b = self._visibility_ratio(method, s, sv, b, coefficients)[:, None] * open_reference
            out = out + weight * np.maximum(b, 0.0)   # displayed radiance is never negative (sd_surface)
        return out

    def _visibility_ratio(self, method, s, sv, b, light):
        """The visibility ratio of lobe 0 of raw B `b` at order s, s' with the light L of order s
        (shaders/sd_shading_lib.glsl, sd_visibility_ratio; live/shader_variant.py, open_order and
        horizon_order), per sampled vertex."""
        luminance = np.asarray(lobes.LUMINANCE)
        lobe, exponent = self.lobe, self.exponent
        normals, views = self._sample.normals, self._lobe_views(lobe)
        order = method.open_order(s, sv)
        open_light = self._sd.shade("unshadowed", np.ascontiguousarray(light[:(order + 1) ** 2]), normals,
                                    views=views, rotation=self._rotation, lobe=lobe, exponent=exponent)
        horizon = np.ones(len(normals))
        if method.uses_visibility_order:   # the mirrored view's cosine to the normal is the view's
            factors = lobes.horizon_factors(sv) * np.asarray(self._sd.zonal_coefficients(lobe, exponent, sv))
            cosine = np.einsum("ij,ij->i", normals, views) / np.linalg.norm(normals, axis=1)
            horizon = np.minimum(legendre.legval(np.clip(cosine, -1.0, 1.0),
                                                 (2 * np.arange(sv + 1) + 1) * factors), 1.0)
        offset = max(0.1 * float(np.asarray(light)[0] @ luminance), 1e-8)
        open_part = np.maximum(horizon * (open_light @ luminance), 0.0)
        return np.clip((np.maximum(b @ luminance, 0.0) + offset) / (open_part + offset), 0.0, 1.0)

    def error(self, setting, sources=False):
        """The predicted relative RMS error of a setting (KeyError for one not measured); sources:
        with the bright sources shaded on their own (measured_sources)."""
        return self.measurement(setting, sources).at(setting.rays)

    def measurement(self, setting, sources=False):
        """The setting's Measured (sources: as `error`), of the part of the sample whose error is
        larger at its rays."""
        method = method_table.get(setting.method)
        key = (method.measured_as, setting.light_order,
               setting.visibility_order if method.uses_visibility_order else 0)
        return max((self.measured_sources if sources else self.measured)[key], key=lambda part: part.at(setting.rays))

    def shadowing(self):
        """The sampled vertices' mean blocked fraction of the hemisphere, cosine-weighted: 0 when
        V = 1 over every sampled vertex's hemisphere, where any lobe reaches."""
        return float(1.0 - np.mean(self.lit_fraction))
