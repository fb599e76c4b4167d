"""One object's bake (any thread): its automatic choice, refinement, rays and least-squares fit or
texels - sdnative.bake_transfer on the arrays prepare.py gathered, never touching bpy."""

import functools
import hashlib
import os
import time
import uuid
from dataclasses import dataclass

import numpy as np

from .. import methods
from ..errors import BakeError
from ..plan import analysis, automatic, bake_time, budget, cost
from ..scene import lobes
from ..store.record import BakeRecord
from . import geometry as geometry_module, least_squares, lightmap, refine

FIT_START = 0.8   # of a least-squares bake's progress: the rays before it, the fit after
TEXELS_START = 0.1   # of a texture-space bake's progress: the vertices before it, the texels after


def above_horizon(arguments):
    """sdnative.bake_transfer's keywords with `horizon` set for a bake that asks for T alone: rays
    below a vertex's horizon add nothing to T (eq. 2's max(0, n . x)), so about half the rays are
    not traced; a bake of V~, M or designs, which need them, traces every ray."""
    others = ("visibility_order", "product_orders", "design_orders")
    return dict(arguments, horizon="transfer_order" in arguments and not any(key in arguments for key in others))


def share(progress, start, end):
    """progress(done, total) moving [start, end] of the caller's progress(done, total) (total 0:
    nothing counted yet, as sdnative reports a bake's set-up)."""
    def shared(done, total):
        return progress(start + (end - start) * (done / total if total else 0.0), 1.0)
    return shared



@dataclass(frozen=True)
class RefinementEstimate:
    """A refinement predicted from a sample (BakeTask.refinement_estimate): its seconds, and how
    many times the copy's vertices and triangles it leaves."""
    seconds: float
    vertex_growth: float
    triangle_growth: float


class SharedChoices:
    """The automatic choices made so far, by the tasks' share_key: identical meshes turned alike,
    alike surrounded, with one material and the same overrides under the same light take the first
    one's choice instead of measuring again - one choice, one setting (200 copies of a cube in a
    grid got 20 settings from 20 noisy measurements)."""

    def __init__(self):
        self._leaders = {}

    def choose(self, task, stop, progress=None):
        """task.choose, or the choice of an earlier task with its share key."""
        leader = self._leaders.get(task.share_key) if task.share_key is not None else None
        if leader is None:
            task.choose(stop, progress)
            if task.share_key is not None:
                self._leaders[task.share_key] = task
            return
        task.adopt(leader.settings, leader.predicted_error)
        # the setting is shared; how it is evaluated follows this object's own size on screen
        per_pixel, evaluation = automatic.evaluation(task.analysis.triangle_pixels)
        reasons = [line for line in leader.settings["automatic"].split("\n") if not line.startswith("Evaluation:")]
        task.settings.update(per_pixel=per_pixel, automatic="\n".join(reasons + [
            evaluation, "Shared: measured on %s (the same mesh, turned alike, alike surrounded, under the "
            "same light)" % leader.object_name]))


class BakeTask:
    """One object to bake: inputs (arrays) and settings; the worker fills `result`. share_key:
    what an automatic choice depends on besides the surroundings' details (SharedChoices), or None."""

    def __init__(self, obj_name, geometry, occluders, settings, analysis_inputs, share_key=None):
        self.object_name = obj_name
        self.share_key = share_key
        self.geometry = geometry
        self.occluder_vertices, self.occluder_triangles = occluders
        self.settings = settings      # dict, becomes the `sd_bake` property
        self.analysis = analysis_inputs   # analysis.Inputs: what its error is measured with
        self.predicted_error = None   # of a chosen method's settings, once predicted
        self.baked = None             # the geometry baked: `geometry` or its refinement
        self.refinement = None        # refine.Refinement, when the settings ask for one
        self.predicted_refinement = None   # RefinementEstimate, when a prediction made one
        self.refine_seconds = 0.0
        self.result = None
        self._inputs = None

    def inputs_hash(self):
        """A digest of everything the bake's result depends on: the arrays read from the mesh
        (Geometry.inputs) and sdnative.bake_transfer's arguments. Recorded as `inputs`: an equal
        digest later means that baking again would give the same bake."""
        if self._inputs is None:
            digest = hashlib.blake2b(digest_size=16)
            for value in self.geometry.inputs():
                digest.update(b"-" if value is None else np.ascontiguousarray(value).tobytes())
            # The refinement's settings as the types they are asked in (an ID property keeps a
            # bool as an int): a bake and its recorded settings give one digest.
            refinement = (bool(self.settings.get("refine")), float(self.settings.get("refine_target", 0.0)),
                          int(self.settings.get("refine_max_vertices", 0)), self.settings.get("bake_seconds_budget"),
                          self.settings.get("sources") is not False)   # its edges: the remainder's light
            arguments = dict(self.bake_arguments(), refine=refinement, lightmap=int(self.settings.get("lightmap", 0)))
            for key, value in sorted(arguments.items()):
                digest.update(key.encode())
                digest.update(np.ascontiguousarray(value).tobytes() if isinstance(value, np.ndarray)
                              else repr(value).encode())
            self._inputs = digest.hexdigest()
        return self._inputs

    @property
    def automatic(self):
        """Whether the automatic mode chooses its settings (choose(), before the bake)."""
        return self.settings["method"] == analysis.AUTOMATIC

    def occluders(self):
        """bake_transfer's occluder keywords ({} without occluders)."""
        if self.occluder_vertices is None:
            return {}
        return {"occluder_vertices": self.occluder_vertices,
                "occluder_triangles": self.occluder_triangles}

    def occluder_parts(self):
        """The occluders as a list of (vertices, triangles) for geometry.join: [] without any."""
        return [] if self.occluder_vertices is None else [(self.occluder_vertices, self.occluder_triangles)]

    def choose(self, stop, progress=None):
        """The automatic mode (any thread): measures, chooses and puts the choice in settings;
        progress(fraction) as the measurement goes."""
        choice = analysis.choose(self.analysis, self.geometry, self.occluders(),
                                 lobes.Lobes.of_bake(self.settings), stop,
                                 fitted=bool(self.settings.get("least_squares")),
                                 texels=lightmap.expected_texels(int(self.settings.get("lightmap", 0))),
                                 progress=progress, bake_budget=self.bake_seconds_budget)
        per_pixel, evaluation = automatic.evaluation(self.analysis.triangle_pixels)
        self.settings.update(
            per_pixel=per_pixel, automatic="\n".join(choice.reasons + (evaluation,)),
            method=choice.setting.method, light_order=choice.setting.light_order,
            visibility_order=choice.setting.visibility_order, rays=choice.setting.rays,
            predicted_error=float(choice.error),
            frame_terms=int(choice.frame_terms), sources=choice.sources,
            traced=self.analysis.traced and lobes.Lobes.of_bake(self.settings).prefiltered_glossy(True))
        self.predicted_error = float(choice.error)

    def adopt(self, settings, predicted_error):
        """Takes over an automatic choice already made for this object (the prediction's), with
        this bake's own shape and placement."""
        self.settings = dict(settings, shape=self.settings["shape"], placement=self.settings["placement"])
        self.predicted_error = predicted_error

    def predict(self, stop):
        """The predicted error of its settings (any thread; the bake-time predictor's)."""
        self.predicted_error = analysis.predict(self.analysis, self.geometry, self.occluders(),
                                                self.settings, stop)

    @property
    def lightmap_size(self):
        """The side of the texture-space data the bake adds: asked for, and a method whose data
        texels can hold (once an automatic task has chosen one); 0 for none."""
        size = int(self.settings.get("lightmap", 0))
        return size if size > 0 and lightmap.applies(methods.get(self.settings["method"])) else 0

    def budget_points(self):
        """What the selection's seconds count for it (plan/budget.py): its mesh's vertices and the
        texels of the texture-space data asked for - counted from the mesh as it is, on the main
        thread, where the split it is baked with waits for the worker (geometry.Geometry)."""
        return len(self.geometry.mesh_positions) + lightmap.expected_texels(int(self.settings.get("lightmap", 0)))

    @property
    def bakes_lightmap(self):
        """Whether the bake adds texture-space data (lightmap_size, the copy unwrapped by prepare)."""
        return self.lightmap_size > 0 and self.geometry.lightmap_uvs is not None

    @property
    def _vertex_count(self):
        """The copy's vertices once refined, else the evaluated mesh's (without computing the split)."""
        return len(self.baked.vertices) if self.baked is not None else len(self.geometry.mesh_positions)

    @property
    def fits_least_squares(self):
        """Whether the bake fits its data by least squares: Least Squares on, and a method it fits
        (once an automatic task has chosen one); not with texture-space data, which the shading
        reads instead of the vertices', nor over least_squares.MAX_VERTICES vertices."""
        return (bool(self.settings.get("least_squares")) and not self.lightmap_size
                and least_squares.applies(methods.get(self.settings["method"]))
                and self._vertex_count <= least_squares.MAX_VERTICES)

    def bake(self, sd, progress):
        """sdnative.bake_transfer of the baked copy (any thread), least-squares fitted when the
        settings ask for it and the method's data can be (bake/least_squares.py), and its texels
        under "lightmap" (bake_lightmap) when it bakes texture-space data. Returns the result dict."""
        geometry = self.baked
        points, normals, triangles = geometry.vertices, geometry.normals, geometry.triangles
        if self.bakes_lightmap:
            plan = self.lightmap_texels()   # refused before anything is baked when too large
            result = dict(sd.bake_transfer(points, normals, triangles, progress=share(progress, 0.0, TEXELS_START),
                                           **self.bake_arguments()))
            result["lightmap"] = self.bake_lightmap(sd, plan, share(progress, TEXELS_START, 1.0))
            return result
        if not self.fits_least_squares:
            result = dict(sd.bake_transfer(points, normals, triangles, progress=progress, **self.bake_arguments()))
            if self.settings.get("least_squares") and self._vertex_count > least_squares.MAX_VERTICES:
                result["least_squares_skipped"] = "{:,} vertices, over {:,}: the fit would take minutes".format(
                    self._vertex_count, least_squares.MAX_VERTICES)
            return result
        points, normals, triangles = least_squares.centroid_split(points, normals, triangles)
        result = dict(sd.bake_transfer(points, normals, triangles, progress=share(progress, 0.0, FIT_START),
                                       **self.bake_arguments()))
        return least_squares.fit(sd, result, geometry.vertices, geometry.triangles,
                                 progress=share(progress, FIT_START, 1.0))

    def lightmap_texels(self):
        """The copy's lightmap texels (bake/lightmap.py): (entries, triangle, barycentric,
        dilation sources, seconds taken). Raises BakeError when the texels stored would not fit
        one GPU texture."""
        start = time.perf_counter()
        size, method = self.lightmap_size, methods.get(self.settings["method"])
        entries, triangle, barycentric = lightmap.texels(self.baked.lightmap_corner_uvs, size, size)
        sources = lightmap.dilation_sources(entries, size, size)
        count = lightmap.data_entries(method, int(self.settings["light_order"]),
                                      int(self.settings["visibility_order"]), len(lightmap.stored(sources)))
        if count > lightmap.MAX_DATA_TEXELS:
            raise BakeError("a %d x %d lightmap of %s needs %d data texels, more than a GPU texture holds "
                            "(%d): choose a smaller lightmap" % (size, size, method.label, count,
                                                                 lightmap.MAX_DATA_TEXELS))
        return entries, triangle, barycentric, sources, time.perf_counter() - start

    def bake_lightmap(self, sd, texels, progress):
        """The texels (lightmap_texels) baked as points without faces against the copy's
        triangles and the occluders, and spread over the texels stored (lightmap.stored: baked, or
        within the dilation of a chart), in entry order, each with its source's values: {"size",
        "baked" (the texels baked), "stored" (the entries stored), "positions" (in the local
        space), "normals", "values" (the linear arrays of bake_transfer's result),
        "seconds" (with lightmap_texels')}."""
        entries, triangle, barycentric, sources, seconds = texels
        start = time.perf_counter() - seconds
        size = self.lightmap_size
        geometry = self.baked
        points, normals = lightmap.sample_points(geometry.vertices, geometry.normals, geometry.triangles,
                                                 triangle, barycentric)
        # the same points in the local space (what the baked mesh's positions are in)
        positions = lightmap.blend(geometry.positions, geometry.triangles, triangle, barycentric)
        arguments = self.bake_arguments()
        vertices, triangles = geometry_module.join([(geometry.vertices, geometry.triangles)] + self.occluder_parts())
        arguments.update(occluder_vertices=vertices, occluder_triangles=triangles)
        result = dict(sd.bake_transfer(points, normals, np.zeros((0, 3), np.int32), progress=progress,
                                       **arguments))
        spread = functools.partial(lightmap.spread, entries=entries, sources=sources)
        return {"size": size, "baked": len(entries), "stored": lightmap.stored(sources),
                "positions": spread(positions), "normals": spread(result["normals"]),
                "values": {key: spread(result[key]) for key in least_squares.FITTED if result.get(key) is not None},
                "seconds": time.perf_counter() - start}

    @property
    def bake_seconds_budget(self):
        """The seconds its rays may take: its share of the selection's (plan/budget.py), or, for a
        re-bake of a bake from before the share, the confirmation's."""
        seconds = self.settings.get("bake_seconds_budget")
        return bake_time.CONFIRM_SECONDS if seconds is None else float(seconds)

    @property
    def refines(self):
        """Whether the bake refines its copy first: Refine on, without texture-space data, and not
        for a method that stores no visibility - the refinement splits where the shadowed transfer
        bends, which the unshadowed shading never draws."""
        method = self.settings["method"]
        if method != analysis.AUTOMATIC and methods.get(method).data is None:
            return False
        return bool(self.settings.get("refine")) and not self.lightmap_size

    def refine_budget(self):
        """The vertices its refinement may reach: its share of Max Verts, and, once its method is
        chosen, no more than its share of the selection's seconds affords at its rays and with the
        refinement's tests - with least squares each vertex also traces about two face centres
        (plan/budget.py)."""
        s = self.settings
        vertices = int(s["refine_max_vertices"])
        if s["method"] == analysis.AUTOMATIC or s.get("bake_seconds_budget") is None:
            return vertices
        method = methods.get(s["method"])
        fitted = bool(s.get("least_squares")) and least_squares.applies(method)
        return min(vertices, budget.affordable_vertices(
            float(s["bake_seconds_budget"]), method, int(s["light_order"]), int(s["visibility_order"]),
            int(s["rays"]), os.cpu_count() or 1, 3.0 if fitted else 1.0,
            test=(methods.get("prt_diffuse"), refine.CRITERION_ORDER, refine.criterion_rays(s["rays"]))))

    def refine(self, sd, progress):
        """Sets `baked` (any thread): the Geometry, or with `refine` on, its refinement
        (refine.py, recorded in `refinement`) tested against this task's light and
        occluders with common rays. progress(done, total) as bake_transfer's, over all levels."""
        self.baked = self.geometry
        if not self.refines:
            return
        self.refinement = self._refined(sd, self.geometry.surface(), self.refine_budget(), progress)
        if self.refinement.levels:
            self.baked = self.geometry.refined(self.refinement.surface)

    def _refined(self, sd, surface, max_vertices, progress, others=(), levels=None):
        """refine.refine of `surface` against the task's light and occluders and the parts
        `others` [(vertices, triangles)]; `levels`: None, or a list given each level's
        (setup seconds, seconds) of its bake."""
        s = self.settings
        kwargs = above_horizon({"rays": refine.criterion_rays(s["rays"]), "seed": int(s["seed"]),
                                "transfer_order": refine.CRITERION_ORDER, "common_rotation": True})
        timed = []

        def bake(vertices, normals, triangles, rest_vertices, rest_triangles):
            level = len(timed)

            def level_progress(done, total):   # each level a share of one bar
                return progress(level + (done / total if total else 0.0), refine.MAX_LEVELS)

            parts = [(rest_vertices, rest_triangles)] + list(others) + self.occluder_parts()
            others_vertices, other_triangles = geometry_module.join(parts)
            extra = ({} if others_vertices is None else
                     {"occluder_vertices": others_vertices, "occluder_triangles": other_triangles})
            start = time.perf_counter()
            result = sd.bake_transfer(vertices, normals, triangles.astype(np.int32), **kwargs, **extra,
                                      progress=level_progress)
            timed.append((float(result["setup_seconds"]), time.perf_counter() - start))
            return result["transfer"]

        whole = refine.band_weights(self.analysis.light(refine.CRITERION_ORDER))
        # where the automatic mode shades the bright sources on their own, the SH carries the rest
        remainder = self.analysis.remainder if s.get("sources") is not False else None
        weights = whole if remainder is None else refine.band_weights(remainder.light(refine.CRITERION_ORDER))
        # the automatic mode's prediction, which its settings record: a chosen method's bake
        # predicts none (the panel's estimate does), and the two would refine differently
        target = float(s["refine_target"])
        refinement = refine.refine(surface, bake, weights, target, max_vertices,
                                   aimed=refine.aim(target, s.get("predicted_error")), whole_weights=whole)
        if levels is not None:
            levels.extend(timed)
        return refinement

    def refinement_estimate(self, sd, stop, seed=0):
        """The refinement the bake will make, predicted from the refinement of a sample of the
        copy's triangles alone (bake_time.REFINE_SAMPLE in patches of bake_time.REFINE_PATCH:
        refine.Surface.patches, drawn with `seed`), against the rest of the copy and the occluders
        (any thread): a RefinementEstimate, or None when the bake does not refine. Its time counts
        each level's setup once and the rest per triangle; the copy grows as the sample did,
        within the vertex budget. stop() -> True cancels (sdnative's BakeCancelled)."""
        if not self.refines:
            return None
        surface = self.geometry.surface()
        vertices_allowed = self.refine_budget()
        if len(surface.vertices) >= vertices_allowed or len(surface.triangles) == 0:   # not refined
            return RefinementEstimate(0.0, 1.0, 1.0)
        rows = surface.patches(bake_time.REFINE_SAMPLE, bake_time.REFINE_PATCH, seed)
        total = len(surface.triangles)
        unsampled = np.ones(total, dtype=bool)
        unsampled[rows] = False
        sample = surface.subset(rows)
        others = [(surface.vertices, surface.triangles[unsampled])] if unsampled.any() else []
        scale = total / max(len(rows), 1)
        levels = []
        sample_budget = int(vertices_allowed * len(sample.vertices) / len(surface.vertices))
        refined = self._refined(sd, sample, max(sample_budget, len(sample.vertices) + 1),
                                lambda done, count: not stop(), others, levels).surface
        seconds = sum(setup + (elapsed - setup) * scale for setup, elapsed in levels)
        vertex_growth = min(len(refined.vertices) / len(sample.vertices), vertices_allowed / len(surface.vertices))
        triangle_growth = vertex_growth * (len(refined.triangles) / len(refined.vertices)) / (
            len(sample.triangles) / len(sample.vertices))
        return RefinementEstimate(seconds, vertex_growth, triangle_growth)

    def predicted_bytes(self):
        """The peak memory of this object's bake (plan/cost.bake_bytes): of the copy to bake once it
        is known (the worker, after the choice and the refinement), else of the evaluated mesh's
        vertices and triangles as they are, grown as a predicted refinement says (the split and the
        faces seen from behind add more)."""
        known = "baked" if self.baked is not None else None
        geometry = self.baked if known else self.geometry
        vertices = len(geometry.vertices) if known else len(self.geometry.mesh_positions)
        triangles = len(geometry.triangles) if known else len(self.geometry.mesh_triangles)
        grown = None if known else self.predicted_refinement
        if grown is not None:
            vertices, triangles = int(vertices * grown.vertex_growth), int(triangles * grown.triangle_growth)
        s = self.settings   # read once: the prediction's worker may adopt a choice meanwhile
        unchosen = s["method"] == analysis.AUTOMATIC
        if unchosen:   # not chosen yet: a fit and texels as asked, the largest transfer it may choose
            fitted = bool(s.get("least_squares")) and self._vertex_count <= least_squares.MAX_VERTICES
            texels = lightmap.expected_texels(int(s.get("lightmap", 0)))
        else:
            fitted, texels = self.fits_least_squares, lightmap.expected_texels(self.lightmap_size)
        points = vertices + (triangles if fitted else 0) + texels
        traced = 3 * triangles if fitted else triangles
        if unchosen:
            floats = 1 + (self.analysis.max_order + 1) ** 2
        else:
            floats = cost.stored_floats(methods.get(s["method"]), int(s["light_order"]), int(s["visibility_order"]))
        occluders = 0 if self.occluder_triangles is None else len(self.occluder_triangles)
        return cost.bake_bytes(len(self.geometry.mesh_positions), points, traced + occluders, floats)

    def bake_arguments(self):
        s = self.settings
        method = methods.get(s["method"])
        kwargs = {"rays": int(s["rays"]), "seed": int(s["seed"])}
        kwargs.update(method.bake_arguments(int(s["light_order"]), int(s["visibility_order"])))
        kwargs.update(self.occluders())
        return above_horizon(kwargs)

    def record(self):
        """The BakeRecord of the finished bake: its settings and what it found (the floats per
        vertex are store.baked's, which writes them)."""
        result = self.result
        n = len(self.baked.vertices)
        summary = {
            "seconds": float(result.get("seconds", 0.0)) + self.refine_seconds + self.geometry.unwrap_seconds,
            "vertices": int(n),
            "bake_id": uuid.uuid4().hex,
            "inputs": self.inputs_hash(),
            "source": self.geometry.source,
            "occluder_triangles": 0 if self.occluder_triangles is None else int(len(self.occluder_triangles)),
            "faces_flipped": int(self.baked.faces_flipped),
            "faces_doubled": int(self.baked.faces_doubled),
        }
        refinement = self.refinement
        if refinement is not None:
            summary.update(unrefined_vertices=int(len(self.geometry.vertices)),
                           refine_seconds=float(self.refine_seconds), refine_levels=int(refinement.levels),
                           refine_worst_left=float(refinement.worst_left),
                           refine_estimated_left=float(refinement.estimated_left),
                           refine_budget_reached=bool(refinement.budget_reached))
        texels = result.get("lightmap")
        if texels is not None:   # the unwrap (step 1) and the texels' bake
            summary.update(lightmap_texels=int(texels["baked"]), lightmap_stored=int(len(texels["stored"])),
                           lightmap_seconds=float(texels["seconds"]) + self.geometry.unwrap_seconds)
        offsets = result.get("design_offsets")
        if offsets is not None:
            counts = np.diff(np.asarray(offsets))
            summary["design_nodes_max"] = int(counts.max()) if counts.size else 0
            summary["design_nodes_mean"] = float(counts.mean()) if counts.size else 0.0
        return BakeRecord.from_dict(dict(self.settings, **summary))
