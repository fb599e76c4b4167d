"""Baking: from the scene's evaluated geometry to a baked mesh with the results as attributes.

A bake runs in three steps:
1. `prepare` (main thread): for every selected mesh object that can be baked (the others are
   left out with a warning: not meshes, no faces, linked from a library), the evaluated mesh
   (modifiers applied) as arrays, its vertex normals, the triangles of every other visible object
   as occluders, all in the object's bake frame (its local frame with its scale applied:
   transforms.bake_frame), the lobe, the orders s and s' and what the method needs. Nothing in
   the .blend changes.
2. `BakeJob.run` (a worker thread in the UI, or the caller's thread): sdnative.bake_transfer for
   each object, with progress and cancellation; it only reads the arrays of step 1 and computes
   what follows from them (the corner split: Geometry), bpy is never touched off the main
   thread, and the native bake releases the GIL.
3. `BakeJob.apply` (main thread, only after every object baked): for each object a new mesh
   datablock "SD <object>", a copy of the evaluated geometry carrying the results as `sd_`
   attributes (attributes.py), with a fake user so it persists; the object links it in the custom
   property `sd_baked_mesh` and records the settings in `sd_bake` (README.md, "Where the results
   live", lists its keys). A previous baked mesh is removed only then, and only when no other
   object (a Shift+D or Alt+D copy) still links it. The object's own mesh is never modified: a
   cancelled or failed bake leaves the file as it was.

Texture-space data (the `lightmap` setting, utils/lightmap.py): step 1 also unwraps the baked
copy (`lightmap_uvs`: Smart UV Project of a temporary copy in a temporary scene, so that nothing
of the user's changes), step 2 bakes the texels after the vertices, step 3 gives the baked mesh
the UV map "SD Lightmap" and links the texels' mesh "SD Lightmap <object>" (one point per texel
stored, the same attributes) in its `sd_lightmap` property.
"""

import functools
import hashlib
import threading
import time
import uuid

import numpy as np

from . import analysis, attributes, compat, environment, materials, native
from .view import View
from .utils import automatic, corners, least_squares, lightmap, lobes, methods, refine, transforms
from .utils.bake_data import BAKE, BAKED_MESH, LIGHTMAP, LIGHTMAP_UV, UV

MESH_PREFIX = "SD "
LIGHTMAP_PREFIX = "SD Lightmap "
GEOMETRY_TYPES = {'MESH', 'CURVE', 'SURFACE', 'META', 'FONT'}
FIT_START = 0.8   # of a least-squares bake's progress: the rays before it, the fit after
TEXELS_START = 0.1   # of a texture-space bake's progress: the vertices before it, the texels after


def _share(progress, start, end):
    """progress(done, total) moving [start, end] of the caller's progress(done, total)."""
    def shared(done, total):
        return progress(start + (end - start) * (done / total if total else 1.0), 1.0)
    return shared


class BakeError(Exception):
    """A bake that cannot run or failed, with a message for the user."""


# --------------------------------------------------------------------------------------------
# Geometry

def _unit_or_zero(vectors):
    """Unit rows; zero (and non-finite) rows become zero, for the native bake's fallback."""
    length = np.linalg.norm(vectors, axis=1)
    good = np.isfinite(length) & (length > 0.0)
    out = np.zeros_like(vectors)
    out[good] = vectors[good] / length[good, None]
    return out


class Geometry:
    """A mesh as arrays: its positions and polygons in the object's local frame (to rebuild it as
    the baked mesh), and the vertices, normals and triangles that are baked, in the bake frame
    (transforms.bake_frame: the local frame with the object's scale K applied).

    The vertices are the mesh's split where its corners shade differently (utils/corners.py): each
    carries the corner normal Blender and Cycles shade with, its material slot and, when a material
    reads an image texture, its UV (`material_slots`, `uvs`: per vertex, or None). A vertex whose
    corners have no normal (Blender finds none for degenerate faces: docs/blender-notes.md, "Zero
    vertex normals") keeps a zero one: the native bake gives it its faces' normal and lists it.
    Loose vertices (no face) are left out: nothing draws them."""

    def __init__(self, mesh, shape, uv_map=None):
        """mesh: a temporary mesh (Object.to_mesh()), which this scales by K; uv_map: the name of
        the UV layer an albedo texture is read through ("" for the active render layer), or None."""
        self._local_positions = attributes.read_positions(mesh)
        self._loop_vertices = np.empty(len(mesh.loops), dtype=np.int32)
        mesh.loops.foreach_get('vertex_index', self._loop_vertices)
        self.loop_starts = np.empty(len(mesh.polygons), dtype=np.int32)
        mesh.polygons.foreach_get('loop_start', self.loop_starts)
        self.loop_totals = np.empty(len(mesh.polygons), dtype=np.int32)
        mesh.polygons.foreach_get('loop_total', self.loop_totals)
        self._loop_slots = attributes.read_loop_material_slots(mesh) if len(mesh.materials) > 1 else None
        self._loop_uvs = attributes.read_loop_uvs(mesh, uv_map) if uv_map is not None else None
        # The scale applied as Object > Apply > Scale does (normals recomputed from the scaled
        # faces); a mirror's normals and triangles turned outside out (the bake reads their winding).
        matrix = np.eye(4)
        matrix[:3, :3] = shape
        mesh.transform([list(row) for row in matrix])
        self._mirrored = bool(np.linalg.det(shape) < 0)
        normals = compat.corner_normals(mesh).astype(np.float64)
        self._corner_normals = -normals if self._mirrored else normals
        self._scaled_positions = attributes.read_positions(mesh).astype(np.float64)
        self._triangle_loops = attributes.read_triangle_loops(mesh)
        self.triangle_count = len(self._triangle_loops)
        self.lightmap_uvs = None   # each loop's lightmap UV [L, 2], for texture-space data (lightmap_uvs)
        self.unwrap_seconds = 0.0  # what finding them took

    def inputs(self):
        """What was read from the mesh: everything the other arrays are computed from."""
        return (self._local_positions, self._loop_vertices, self.loop_starts, self.loop_totals,
                self._loop_slots, self._loop_uvs, np.array(self._mirrored), self._corner_normals,
                self._scaled_positions, self._triangle_loops)

    @property
    def mesh_positions(self):
        """The mesh's own vertex positions in the local frame (before the split)."""
        return self._local_positions

    @property
    def _wound_triangle_loops(self):
        loops = self._triangle_loops
        return loops[:, ::-1] if self._mirrored else loops

    @property
    def lightmap_corner_uvs(self):
        """Each triangle corner's lightmap UV [T, 3, 2], as `triangles`."""
        return self.lightmap_uvs[self._wound_triangle_loops]

    @property
    def mesh_triangles(self):
        """`triangles` over the mesh's own vertices: the same faces, without computing the split."""
        return self._loop_vertices[self._wound_triangle_loops]

    # The split and what follows from it are computed when first read - for a bake from the UI in
    # its worker thread (BakeJob.run), not on the main thread, except for a texture-space bake's
    # unwrap (lightmap_uvs) - and kept.
    @functools.cached_property
    def _split(self):
        return corners.split(self._loop_vertices, self._corner_normals, self._loop_slots, self._loop_uvs)

    @functools.cached_property
    def positions(self):
        return self._local_positions[self._split.origin]

    @property
    def loop_vertices(self):
        return self._split.loop_vertex

    @functools.cached_property
    def vertices(self):
        return self._scaled_positions[self._split.origin]

    @functools.cached_property
    def normals(self):
        return _unit_or_zero(self._split.normal_sums)

    @functools.cached_property
    def triangles(self):
        return self._split.loop_vertex[self._wound_triangle_loops]

    @functools.cached_property
    def material_slots(self):
        return None if self._loop_slots is None else corners.vertex_values(self._split, self._loop_slots)

    @functools.cached_property
    def uvs(self):
        return None if self._loop_uvs is None else corners.vertex_values(self._split, self._loop_uvs)

    def build_mesh(self, name):
        """A new mesh datablock with this geometry in the local frame, vertices in the same order."""
        return attributes.new_mesh(name, self.positions, self.loop_vertices, self.loop_starts,
                                   self.loop_totals)

    def surface(self):
        """The baked vertices and triangles as a refine.Surface. Vertices at one point weld: the
        corner copies of a mesh vertex, and the corners of a mesh whose faces share none (a
        triangle soup, as some exporters write), so that the split stays conforming there too."""
        weld = np.unique(self.vertices, axis=0, return_inverse=True)[1].reshape(-1)
        return refine.Surface(self.vertices, self.normals, self.positions, weld, self.triangles,
                              self.material_slots, self.uvs)

    def refined(self, surface):
        """The geometry of a refined copy (refine.refine's surface from this one's)."""
        return RefinedGeometry(surface, self._mirrored)


class RefinedGeometry:
    """A baked copy refined (utils/refine.py): the Geometry arrays of its surface, all triangles."""

    def __init__(self, surface, mirrored):
        self.vertices, self.normals, self.positions = surface.vertices, surface.normals, surface.positions
        self.triangles, self.material_slots, self.uvs = surface.triangles, surface.slots, surface.uvs
        self._mirrored = mirrored

    def build_mesh(self, name):
        """A new mesh datablock of these triangles in the local frame (the object's winding)."""
        faces = self.triangles[:, ::-1] if self._mirrored else self.triangles
        count = len(faces)
        return attributes.new_mesh(name, self.positions, faces.ravel(), 3 * np.arange(count),
                                   np.full(count, 3))


def _evaluated_arrays(obj, depsgraph, shape):
    """Geometry of the object's evaluated mesh (modifiers applied)."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if mesh is None:
            return None
        return Geometry(mesh, shape, materials.albedo_uv_map(obj))
    finally:
        evaluated.to_mesh_clear()


def lightmap_uvs(context, geometry, size):
    """Each loop's lightmap UV of the geometry (float32 [L, 2]): Blender's Smart UV Project of a
    copy in the bake frame scaled to unit area (texel density follows the scaled surface), its
    charts at least lightmap.MARGIN_TEXELS texels of a size x size map apart. The margin is
    'ADD'ed in the copy's units around each chart before the charts are scaled into the map, so it
    is chosen from the scale they get (lightmap.add_margin; at unit area it stays far below the
    operator's cap of 1), and the unwrap repeated, up to lightmap.UNWRAP_TRIES times, while the
    scale came out smaller than that margin needs (the last is kept): the default 'SCALED'
    margin shrinks with few charts (to about a texel on a cube), and the exact 'FRACTION' one
    packs ten times slower (13 s on the 85k-vertex engine). The copy is of the split vertices, so
    its charts also end at sharp edges, material borders and albedo UV seams. It lives in a
    temporary scene, so that Edit Mode reaches it alone; nothing else changes. Raises BakeError
    outside Object Mode (another object would share that Edit Mode), for a copy without area, or
    when the unwrap fails."""
    import bpy
    if context.mode != 'OBJECT':
        raise BakeError("texture-space data are unwrapped in Object Mode (the mode is %s): switch "
                        "to Object Mode to bake them" % context.mode)
    corners = geometry.vertices[geometry.triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    if not area > 0.0:
        raise BakeError("the baked copy has no area to unwrap a lightmap over")
    mesh = attributes.new_mesh("sd_lightmap unwrap", geometry.vertices / np.sqrt(area), geometry.loop_vertices,
                               geometry.loop_starts, geometry.loop_totals)
    scene = obj = None
    try:
        scene = bpy.data.scenes.new("sd_lightmap unwrap")
        obj = bpy.data.objects.new(mesh.name, mesh)
        scene.collection.objects.link(obj)
        layer = scene.view_layers[0]
        layer.objects.active = obj
        obj.select_set(True, view_layer=layer)
        loops = len(mesh.loops)
        scale = lightmap.expected_scale(1.0)
        for _ in range(lightmap.UNWRAP_TRIES):
            margin = lightmap.add_margin(size, scale)
            try:
                with context.temp_override(scene=scene, view_layer=layer, active_object=obj, object=obj,
                                           selected_objects=[obj], selected_editable_objects=[obj]):
                    bpy.ops.object.mode_set(mode='EDIT')
                    try:
                        with context.temp_override(edit_object=obj):
                            bpy.ops.mesh.select_all(action='SELECT')
                            bpy.ops.uv.smart_project(angle_limit=np.radians(lightmap.ANGLE_LIMIT_DEGREES),
                                                     margin_method='ADD', island_margin=margin)
                    finally:
                        bpy.ops.object.mode_set(mode='OBJECT')
            except RuntimeError as exc:   # an operator's poll or report, e.g. from a timer's context
                raise BakeError("Smart UV Project failed: %s" % exc) from exc
            layer_uv = mesh.uv_layers.active
            if layer_uv is None or len(mesh.loops) != loops:
                raise BakeError("Smart UV Project gave no UV map of the baked copy's %d face corners" % loops)
            uvs = attributes.read_loop_uvs(mesh, layer_uv.name)
            scale = lightmap.uv_scale(uvs[geometry._wound_triangle_loops], 1.0)
            if lightmap.gap_texels(margin, scale, size) >= lightmap.MARGIN_TEXELS:
                break
        return uvs
    finally:
        if obj is not None:
            bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)
        if scene is not None:
            bpy.data.scenes.remove(scene)


def world_triangles(obj, depsgraph, view_layer):
    """World-space triangles of a visible object with geometry: (vertices float64 [V, 3],
    triangles [T, 3], wound outside-out also for a mirrored object) or None."""
    if obj.type not in GEOMETRY_TYPES or not obj.visible_get(view_layer=view_layer):
        return None
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if mesh is None or len(mesh.vertices) == 0:
            return None
        triangles = attributes.read_triangles(mesh)
        if len(triangles) == 0:
            return None
        matrix = np.array(evaluated.matrix_world, dtype=np.float64)
        if np.linalg.det(matrix[:3, :3]) < 0:
            triangles = triangles[:, ::-1].copy()
        return transforms.transform_points(matrix, attributes.read_positions(mesh)), triangles
    finally:
        evaluated.to_mesh_clear()


# --------------------------------------------------------------------------------------------
# Step 1: what to bake

class BakeTask:
    """One object to bake: inputs (arrays) and settings; the worker fills `result`."""

    def __init__(self, obj_name, geometry, occluders, settings, analysis_inputs):
        self.object_name = obj_name
        self.geometry = geometry
        self.occluder_vertices, self.occluder_triangles = occluders
        self.settings = settings      # dict, becomes the `sd_bake` property
        self.analysis = analysis_inputs   # analysis.Inputs: what its error is measured with
        self.predicted_error = None   # of a chosen method's settings, once predicted
        self.baked = None             # the geometry baked: `geometry` or its refinement
        self.refinement = None        # refine.Refinement, when the settings ask for one
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
                          int(self.settings.get("refine_max_vertices", 0)))
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

    def choose(self, stop):
        """The automatic mode (any thread): measures, chooses and puts the choice in settings."""
        choice = analysis.choose(self.analysis, self.geometry, self.occluders(),
                                 lobes.Lobes.of_bake(self.settings), stop,
                                 fitted=bool(self.settings.get("least_squares")),
                                 texels=lightmap.expected_texels(int(self.settings.get("lightmap", 0))))
        per_pixel, evaluation = automatic.evaluation(self.analysis.triangle_pixels)
        self.settings.update(
            per_pixel=per_pixel, automatic="\n".join(choice.reasons + (evaluation,)),
            method=choice.setting.method, light_order=choice.setting.light_order,
            visibility_order=choice.setting.visibility_order, rays=choice.setting.rays,
            predicted_error=float(choice.error),
            frame_terms=int(choice.frame_terms))
        self.predicted_error = float(choice.error)

    def adopt(self, settings, predicted_error):
        """Takes over an automatic choice already made for this object (the prediction's), with
        this bake's own shape."""
        self.settings = dict(settings, shape=self.settings["shape"])
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

    @property
    def bakes_lightmap(self):
        """Whether the bake adds texture-space data (lightmap_size, the copy unwrapped by prepare)."""
        return self.lightmap_size > 0 and self.geometry.lightmap_uvs is not None

    @property
    def fits_least_squares(self):
        """Whether the bake fits its data by least squares: Least Squares on, and a method it fits
        (once an automatic task has chosen one); not with texture-space data, which the shading
        reads instead of the vertices'."""
        return (bool(self.settings.get("least_squares")) and not self.lightmap_size
                and least_squares.applies(methods.get(self.settings["method"])))

    def bake(self, sd, progress):
        """sdnative.bake_transfer of the baked copy (any thread), least-squares fitted when the
        settings ask for it and the method's data can be (utils/least_squares.py), and its texels
        under "lightmap" (bake_lightmap) when it bakes texture-space data. Returns the result dict."""
        geometry = self.baked
        points, normals, triangles = geometry.vertices, geometry.normals, geometry.triangles
        if self.bakes_lightmap:
            plan = self.lightmap_texels()   # refused before anything is baked when too large
            result = dict(sd.bake_transfer(points, normals, triangles, progress=_share(progress, 0.0, TEXELS_START),
                                           **self.bake_arguments()))
            result["lightmap"] = self.bake_lightmap(sd, plan, _share(progress, TEXELS_START, 1.0))
            return result
        if not self.fits_least_squares:
            return dict(sd.bake_transfer(points, normals, triangles, progress=progress, **self.bake_arguments()))
        points, normals, triangles = least_squares.centroid_split(points, normals, triangles)
        result = dict(sd.bake_transfer(points, normals, triangles, progress=_share(progress, 0.0, FIT_START),
                                       **self.bake_arguments()))
        return least_squares.fit(sd, result, geometry.vertices, geometry.triangles,
                                 progress=_share(progress, FIT_START, 1.0))

    def lightmap_texels(self):
        """The copy's lightmap texels (utils/lightmap.py): (entries, triangle, barycentric,
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
        triangles and the occluders: {"size", "entries", "sources" (dilation), "positions" (in the
        local frame), "result" (bake_transfer's dict of the baked texels, in `entries` order),
        "seconds" (with lightmap_texels')}."""
        entries, triangle, barycentric, sources, seconds = texels
        start = time.perf_counter() - seconds
        size = self.lightmap_size
        geometry = self.baked
        points, normals = lightmap.sample_points(geometry.vertices, geometry.normals, geometry.triangles,
                                                 triangle, barycentric)
        # the same points in the local frame (what the baked mesh's positions are in)
        positions = lightmap.blend(geometry.positions, geometry.triangles, triangle, barycentric)
        arguments = self.bake_arguments()
        vertices, triangles = geometry.vertices, np.asarray(geometry.triangles, np.int32)
        if "occluder_vertices" in arguments:
            triangles = np.concatenate([triangles, arguments["occluder_triangles"] + len(vertices)])
            vertices = np.concatenate([vertices, arguments["occluder_vertices"]])
        arguments.update(occluder_vertices=vertices, occluder_triangles=triangles.astype(np.int32))
        result = dict(sd.bake_transfer(points, normals, np.zeros((0, 3), np.int32), progress=progress,
                                       **arguments))
        return {"size": size, "entries": entries, "sources": sources, "positions": positions, "result": result,
                "seconds": time.perf_counter() - start}

    def refine(self, sd, progress):
        """Sets `baked` (any thread): the Geometry, or with `refine` on, its refinement
        (utils/refine.py, recorded in `refinement`) tested against this task's light and
        occluders with common rays. progress(done, total) as bake_transfer's, over all levels."""
        s = self.settings
        self.baked = self.geometry
        if not s.get("refine") or self.lightmap_size:
            return
        occluders = self.occluders()
        kwargs = {"rays": min(int(s["rays"]), refine.CRITERION_RAYS), "seed": int(s["seed"]),
                  "transfer_order": refine.CRITERION_ORDER, "common_rotation": True}
        levels = []

        def bake(vertices, normals, triangles, rest_vertices, rest_triangles):
            level = len(levels)
            levels.append(level)

            def level_progress(done, total):   # each level a share of one bar
                return progress(level * total + done, refine.MAX_LEVELS * total)

            verts, tris = [rest_vertices], [rest_triangles]
            if occluders:
                verts.append(occluders["occluder_vertices"])
                tris.append(occluders["occluder_triangles"] + len(rest_vertices))
            extra = {}
            if sum(len(t) for t in tris):
                extra = {"occluder_vertices": np.concatenate(verts),
                         "occluder_triangles": np.concatenate(tris).astype(np.int32)}
            return sd.bake_transfer(vertices, normals, triangles.astype(np.int32), **kwargs, **extra,
                                    progress=level_progress)["transfer"]

        weights = refine.band_weights(self.analysis.light(refine.CRITERION_ORDER))
        self.refinement = refine.refine(self.geometry.surface(), bake, weights,
                                        float(s["refine_target"]), int(s["refine_max_vertices"]))
        if self.refinement.levels:
            self.baked = self.geometry.refined(self.refinement.surface)

    def bake_arguments(self):
        s = self.settings
        method = methods.get(s["method"])
        kwargs = {"rays": int(s["rays"]), "seed": int(s["seed"])}
        kwargs.update(method.bake_arguments(int(s["light_order"]), int(s["visibility_order"])))
        kwargs.update(self.occluders())
        return kwargs


def bake_settings(scene, obj, env_source):
    """The settings dict of a bake of `obj` under the scene's panel settings and the object's
    overrides (properties.ObjectOverrides). The automatic mode's dict says method "automatic":
    the bake's worker fills in the choice (analysis.choose), with the lines saying why."""
    settings = scene.sd_lighting
    fixed = obj.sd_lighting.fixed() if hasattr(obj, "sd_lighting") else {}
    method_id = fixed.get("method", settings.method)
    lobe_set = materials.lobe_for(obj, settings)
    lobe, exponent = lobe_set.lobe, lobe_set.exponent
    common = {"lobe": lobe, "exponent": float(exponent), "diffuse_lobe": lobe_set.diffuse,
              "lobe_weights": lobe_set.weighted, "diffuse_share": lobe_set.diffuse_share,
              "seed": int(settings.seed),
              "environment": env_source.description, "refine": bool(settings.refine),
              "refine_target": float(settings.target_error),
              "refine_max_vertices": int(settings.refine_max_vertices),
              "least_squares": bool(settings.least_squares),
              "lightmap": int(settings.lightmap_size) if settings.texture_space else 0}
    if method_id == analysis.AUTOMATIC:
        return dict(common, method=analysis.AUTOMATIC, light_order=0, visibility_order=0,
                    rays=int(fixed.get("rays", settings.rays)))
    method = methods.get(method_id)
    if method.lambert_only and lobe != "lambert":
        raise BakeError("%s needs a Lambert material; %s is %s"
                        % (method.label, obj.name, lobe_set.label))
    if "light_order" in fixed:
        order = fixed["light_order"]
    elif settings.automatic_orders:
        try:
            order = environment.smallest_order(env_source, lobe, exponent, settings.target_error,
                                               settings.max_automatic_order)
        except Exception as exc:
            raise BakeError("cannot choose s automatically: %s" % exc) from exc
    else:
        order = settings.light_order
    v_order = fixed.get("visibility_order", settings.visibility_order) if method.uses_visibility_order else 0
    return dict(common, method=method.id, light_order=int(order), visibility_order=int(v_order),
                rays=int(fixed.get("rays", settings.rays)))


def _analysis_inputs(scene, obj, geometry, env_source, settings, to_frame, depsgraph):
    """What the object's error is measured with (analysis.Inputs), in its bake frame."""
    matrix = np.array(obj.matrix_world, dtype=np.float64)
    rotation = environment.rotation_matrix(scene) @ transforms.rotation_part(matrix)
    eye = triangle_pixels = None
    if scene.camera is not None:
        eye = transforms.transform_points(to_frame, np.array([scene.camera.matrix_world.translation]))[0]
        render = scene.render
        width = render.resolution_x * render.resolution_percentage // 100
        height = render.resolution_y * render.resolution_percentage // 100
        if settings["method"] == analysis.AUTOMATIC:   # only its choice reads the mesh on screen
            view = View.from_camera(scene.camera, depsgraph, width, height, scene)
            triangle_pixels = automatic.projected_triangle_pixels(
                transforms.transform_points(matrix, geometry.mesh_positions), geometry.mesh_triangles,
                view.view_projection, width, height)
    fixed = obj.sd_lighting.fixed() if hasattr(obj, "sd_lighting") else {}
    fixed.pop("method", None)
    panel = scene.sd_lighting
    return analysis.gather(env_source, settings["lobe"], settings["exponent"], rotation, eye,
                           panel.target_error, panel.max_automatic_order, fixed,
                           panel.ringing_window.lower(), triangle_pixels)


def recorded_settings(scene, obj, env_source):
    """The settings the object's bake recorded - what it was asked for and, from the automatic
    mode, what was chosen - for a re-bake (not the panel's); BakeError without a bake."""
    mesh = baked_mesh(obj)
    if mesh is None:
        raise BakeError("%s has no bake" % obj.name)
    return {key: value for key, value in mesh[BAKE].to_dict().items() if key not in SUMMARY_KEYS}


def _refusal(obj):
    """Why the object cannot be baked (a message for the user), or None."""
    if obj.type != 'MESH':
        return "%s is not a mesh (%s)" % (obj.name, obj.type.lower())
    if obj.library is not None:
        return ("%s is linked from %s, which keeps no change made here: make it local (Object > "
                "Relations > Make Local) to bake it" % (obj.name, obj.library.filepath))
    if obj.override_library is not None:
        return ("%s is a library override, whose bake Blender would drop when the file is "
                "reopened: make it local to bake it" % obj.name)
    return None


def _occluders(others, to_frame):
    """The other objects' world triangles in a bake frame, as one mesh: (vertices, triangles) or
    (None, None)."""
    verts, tris, base = [], [], 0
    for world, triangles in others:
        verts.append(transforms.transform_points(to_frame, world))
        tris.append(triangles + base)
        base += len(world)
    if not verts:
        return None, None
    return np.concatenate(verts), np.concatenate(tris).astype(np.int32)


def _may_bake_lightmap(method_id):
    """Whether a bake of this method (or the automatic mode's choice) may hold texels."""
    return method_id == analysis.AUTOMATIC or lightmap.applies(methods.get(method_id))


def unwrap_lightmap(context, task):
    """Gives a task whose settings ask for texture-space data its lightmap UVs (lightmap_uvs;
    main thread, BakeError as there); nothing for the others."""
    settings = task.settings
    if int(settings.get("lightmap", 0)) > 0 and _may_bake_lightmap(settings["method"]):
        start = time.perf_counter()
        task.geometry.lightmap_uvs = lightmap_uvs(context, task.geometry, int(settings["lightmap"]))
        task.geometry.unwrap_seconds = time.perf_counter() - start


def prepare(context, objects, settings_of=bake_settings, unwrap=True):
    """What to bake (main thread): (BakeTasks, warnings). Objects that cannot be baked (not
    meshes, without faces, linked from a library) are left out, each with a warning; raises
    BakeError when none is left or the bake cannot start (no sdnative, no environment).
    settings_of(scene, obj, env_source): the settings of an object's bake (bake_settings: the
    panel's; recorded_settings: those of its last bake). unwrap: False leaves texture-space
    bakes without their UVs (unwrap_lightmap: the bake-time prediction estimates the texels
    instead; a live re-bake unwraps only what it bakes)."""
    scene = context.scene
    depsgraph = context.evaluated_depsgraph_get()
    view_layer = context.view_layer
    if not native.available():
        raise BakeError(native.error_message())
    try:
        env_source = environment.source(scene)
        if env_source.kind != "uniform":
            environment.environment(env_source)  # an unreadable file fails now, not at every frame
    except environment.Unavailable as exc:
        raise BakeError(str(exc)) from exc

    # The other objects' world triangles, each read when first needed: an object baked alone (a
    # live re-bake) never reads its own.
    triangles = {}

    def occluders_of(obj):
        for other in scene.objects:
            if other != obj:
                if other.name_full not in triangles:
                    triangles[other.name_full] = world_triangles(other, depsgraph, view_layer)
                if triangles[other.name_full] is not None:
                    yield triangles[other.name_full]

    tasks, skipped = [], []
    for obj in objects:
        reason = _refusal(obj)
        if reason is None:
            shape, to_frame = transforms.bake_frame(obj.evaluated_get(depsgraph).matrix_world)
            if np.linalg.matrix_rank(shape) < 3:
                reason = "%s has a zero scale" % obj.name
        if reason is None:
            geometry = _evaluated_arrays(obj, depsgraph, shape)
            if geometry is None or geometry.triangle_count == 0:
                reason = "%s has no faces" % obj.name
        if reason is not None:
            skipped.append(reason)
            continue
        occluders = _occluders(occluders_of(obj), to_frame)
        settings = settings_of(scene, obj, env_source)
        settings["shape"] = [float(x) for x in shape.ravel()]
        inputs = _analysis_inputs(scene, obj, geometry, env_source, settings, to_frame, depsgraph)
        tasks.append(BakeTask(obj.name, geometry, occluders, settings, inputs))
        if unwrap:
            unwrap_lightmap(context, tasks[-1])
    if not tasks:
        raise BakeError("nothing to bake: " + "; ".join(skipped) if skipped else
                        "select one or more mesh objects to bake")
    warnings = ["skipped: " + reason for reason in skipped]
    if env_source.kind == "uniform":
        warnings.append("world '%s' has no Environment Texture: lit by its %s"
                        % (scene.world.name, env_source.description))
    return tasks, warnings


# --------------------------------------------------------------------------------------------
# Step 2: the worker

class BakeJob:
    """Bakes a list of BakeTasks; run() in any thread, apply() on the main thread afterwards."""

    def __init__(self, tasks, warnings=()):
        self.tasks = tasks
        self.warnings = list(warnings)   # for the user, with the result (prepare's, run's)
        self.current = 0              # index of the task being baked
        self.fraction = 0.0           # overall progress in [0, 1]
        self.cancel_requested = False
        self.choosing = False         # the automatic mode is measuring the current object
        self.refining = False         # the current object's copy is being refined
        self.cancelled = False
        self.error = None             # message when the bake failed
        self.finished = False
        self.seconds = 0.0
        self._thread = None

    # -- control
    def start(self):
        """Runs the bake in a worker thread."""
        self._thread = threading.Thread(target=self.run, name="sd_lighting bake", daemon=True)
        self._thread.start()

    def cancel(self):
        self.cancel_requested = True

    def join(self, timeout=None):
        if self._thread is not None:
            self._thread.join(timeout)

    def status_text(self):
        if not self.tasks:
            return ""
        task = self.tasks[min(self.current, len(self.tasks) - 1)]
        doing = ("choosing the settings of" if self.choosing else
                 "refining" if self.refining else "baking")
        return "SD Lighting: %s %s (%d/%d), %d %%  -  Esc to cancel" % (
            doing, task.object_name, min(self.current + 1, len(self.tasks)), len(self.tasks),
            int(100 * self.fraction))

    # -- work
    def run(self):
        sd = None
        start = time.perf_counter()
        try:
            sd = native.get()
            count = len(self.tasks)
            for index, task in enumerate(self.tasks):
                self.current = index
                if self.cancel_requested:
                    raise sd.BakeCancelled("cancelled")

                def task_progress(done, total, index=index):
                    self.fraction = (index + (done / total if total else 1.0)) / count
                    return not self.cancel_requested

                if task.automatic:
                    self.choosing = True
                    task.choose(lambda: self.cancel_requested)
                    self.choosing = False
                # Refinement takes the first half of the task's bar, when it runs.
                halfway = 0.5 if task.settings.get("refine") and not task.lightmap_size else 0.0
                t0 = time.perf_counter()
                self.refining = True
                task.refine(sd, _share(task_progress, 0.0, halfway))
                self.refining = False
                task.refine_seconds = time.perf_counter() - t0
                t0 = time.perf_counter()
                result = task.bake(sd, _share(task_progress, halfway, 1.0))
                result["seconds"] = time.perf_counter() - t0   # the least-squares fit included
                task.result = result
                if "least_squares_skipped" in result:
                    self.warnings.append("%s: least squares skipped, the vertices keep their baked "
                                         "values (%s)" % (task.object_name, result["least_squares_skipped"]))
                fallbacks = len(result["fallback_normals"])
                if fallbacks:
                    self.warnings.append("%d %s of %s had no usable normal; their faces' normal "
                                         "was used" % (fallbacks, "vertex" if fallbacks == 1 else "vertices",
                                                       task.object_name))
            self.fraction = 1.0
        except Exception as exc:
            if sd is not None and isinstance(exc, getattr(sd, "BakeCancelled", ())):
                self.cancelled = True
            elif self.cancel_requested:
                self.cancelled = True
            else:
                self.error = "%s: %s" % (type(exc).__name__, exc)
        finally:
            self.seconds = time.perf_counter() - start
            self.finished = True

    # -- step 3
    def apply(self):
        """Stores the results (main thread). Returns the baked objects' names.

        All or nothing: the new meshes are built first; only when every one is complete are they
        linked and the previous baked meshes removed."""
        import bpy
        if not self.finished or self.cancelled or self.error:
            raise BakeError("nothing to apply")
        built = []
        try:
            for task in self.tasks:
                obj = bpy.data.objects.get((task.object_name, None))   # the local one
                if obj is None:
                    raise BakeError("%s was deleted during the bake" % task.object_name)
                mesh = task.baked.build_mesh(MESH_PREFIX + task.object_name)
                built.append((obj, mesh, task))
                floats = attributes.write(mesh, task.result["normals"], task.result)
                attributes.write_surface(mesh, task.baked.material_slots, task.baked.uvs)
                settings = dict(task.settings)
                settings.update(_result_summary(task, floats))
                if "lightmap" in task.result:
                    mesh.uv_layers.new(name=LIGHTMAP_UV).data.foreach_set("uv", task.baked.lightmap_uvs.ravel())
                    mesh[LIGHTMAP] = _build_lightmap_mesh(LIGHTMAP_PREFIX + task.object_name, task.result["lightmap"])
                mesh[BAKE] = settings
                mesh.use_fake_user = True
        except Exception:
            for _, mesh, _ in built:
                _remove_baked_mesh(mesh)
            raise
        released = {}
        for obj, mesh, task in built:
            old = baked_mesh(obj)
            obj[BAKED_MESH] = mesh
            obj[BAKE] = dict(mesh[BAKE])
            if old is not None:
                released[old.as_pointer()] = old
        for old in released.values():
            _release(old)
        for obj, mesh, _ in built:
            name = MESH_PREFIX + obj.name
            if mesh.name != name and name not in bpy.data.meshes:  # free now that the old one went
                mesh.name = name
        return [obj.name for obj, _, _ in built]


# The keys _result_summary adds to a bake's settings in `sd_bake`: what the bake found, not what it
# was asked for.
SUMMARY_KEYS = ("seconds", "vertices", "floats_per_vertex", "bytes_per_vertex", "bake_id", "inputs",
                "design_nodes_max", "design_nodes_mean", "unrefined_vertices", "refine_levels",
                "refine_seconds", "refine_worst_left", "refine_estimated_left",
                "refine_budget_reached", "lightmap_texels", "lightmap_stored", "lightmap_seconds")


def _build_lightmap_mesh(name, texels):
    """The texels' mesh of a bake's "lightmap" (BakeTask.bake_lightmap): one point per texel
    stored (lightmap.stored: baked, or within the dilation of a chart), in entry order, at its
    source's point in the local frame, with its source's values of the bake's attributes and its
    entry (attributes.write_texels)."""
    import bpy
    entries, sources, result = texels["entries"], texels["sources"], texels["result"]
    spread = {key: lightmap.spread(result[key], entries, sources)
              for key in least_squares.FITTED if result.get(key) is not None}
    mesh = bpy.data.meshes.new(name)
    try:
        mesh.vertices.add(len(lightmap.stored(sources)))
        mesh.vertices.foreach_set("co", lightmap.spread(texels["positions"], entries, sources).astype(np.float32).ravel())
        attributes.write(mesh, lightmap.spread(result["normals"], entries, sources), spread)
        attributes.write_texels(mesh, lightmap.stored(sources))
        mesh.use_fake_user = True
    except Exception:
        bpy.data.meshes.remove(mesh)
        raise
    return mesh


def _result_summary(task, floats):
    """The summary of a task's result for `sd_bake` (SUMMARY_KEYS)."""
    result = task.result
    n = len(task.baked.vertices)
    summary = {
        "seconds": float(result.get("seconds", 0.0)) + task.refine_seconds + task.geometry.unwrap_seconds,
        "vertices": int(n),
        "floats_per_vertex": int(floats),
        "bytes_per_vertex": int(4 * floats),
        "bake_id": uuid.uuid4().hex,
        "inputs": task.inputs_hash(),
    }
    refinement = task.refinement
    if refinement is not None:
        summary.update(unrefined_vertices=int(len(task.geometry.vertices)),
                       refine_seconds=float(task.refine_seconds), refine_levels=int(refinement.levels),
                       refine_worst_left=float(refinement.worst_left),
                       refine_estimated_left=float(refinement.estimated_left),
                       refine_budget_reached=bool(refinement.budget_reached))
    texels = result.get("lightmap")
    if texels is not None:   # the unwrap (step 1) and the texels' bake
        summary.update(lightmap_texels=int(len(texels["entries"])),
                       lightmap_stored=int(len(lightmap.stored(texels["sources"]))),
                       lightmap_seconds=float(texels["seconds"]) + task.geometry.unwrap_seconds)
    offsets = result.get("design_offsets")
    if offsets is not None:
        counts = np.diff(np.asarray(offsets))
        summary["design_nodes_max"] = int(counts.max()) if counts.size else 0
        summary["design_nodes_mean"] = float(counts.mean()) if counts.size else 0.0
    return summary


# --------------------------------------------------------------------------------------------
# Queries and removal

def baked_mesh(obj):
    """The object's baked mesh, or None."""
    import bpy
    mesh = obj.get(BAKED_MESH) if obj is not None else None
    if isinstance(mesh, bpy.types.Mesh) and BAKE in mesh:
        return mesh
    return None


def bake_info(obj):
    """The object's `sd_bake` settings as a dict, or None."""
    mesh = baked_mesh(obj)
    return dict(mesh[BAKE]) if mesh is not None else None


def scale_changed(obj):
    """Whether the object's scale (with shear and mirror) differs from the one it was baked with,
    e.g. an animated scale at another frame: its bake then shades the shape it had, until baked
    again. False for a bake that did not record it."""
    info = bake_info(obj)
    if info is None or "shape" not in info:
        return False
    baked = np.array(list(info["shape"]), dtype=np.float64).reshape(3, 3)
    current = transforms.bake_frame(obj.matrix_world)[0]
    return not np.allclose(current, baked, rtol=0.0, atol=1e-5 * np.abs(baked).max())


def albedo_texture_unbaked(obj):
    """Whether the object's material reads an image texture its bake kept no UVs for (the texture
    was added since): the live shading then shows the material's flat colour."""
    mesh = baked_mesh(obj)
    return (mesh is not None and materials.albedo_uv_map(obj) is not None
            and UV not in mesh.attributes)


def lightmap_mesh(mesh):
    """The texels' mesh of a baked mesh with texture-space data, or None."""
    import bpy
    texels = mesh.get(LIGHTMAP) if mesh is not None else None
    return texels if isinstance(texels, bpy.types.Mesh) else None


def _remove_baked_mesh(mesh):
    """Removes a baked mesh and its texels' mesh."""
    import bpy
    texels = lightmap_mesh(mesh)
    bpy.data.meshes.remove(mesh)
    if texels is not None and texels.library is None:
        bpy.data.meshes.remove(texels)


def _release(mesh):
    """Removes a baked mesh that no object links any more. Shift+D and Alt+D copies of a baked
    object link the same baked mesh: it stays while one of them does."""
    import bpy
    if mesh.library is None and not any(o.get(BAKED_MESH) == mesh for o in bpy.data.objects):
        _remove_baked_mesh(mesh)


def clear(obj):
    """Removes the object's bake: its custom properties, and its baked mesh unless another object
    still links it. Raises BakeError for an object linked from a library."""
    if obj.library is not None:
        raise BakeError("%s is linked from %s: its bake can only be cleared there"
                        % (obj.name, obj.library.filepath))
    mesh = baked_mesh(obj)
    for key in (BAKED_MESH, BAKE):
        if key in obj:
            del obj[key]
    if mesh is not None:
        _release(mesh)
