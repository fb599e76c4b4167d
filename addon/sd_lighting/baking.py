"""Baking: from the scene's evaluated geometry to a baked mesh with the results as attributes.

A bake runs in three steps:
1. `prepare` (main thread): for every selected mesh object, the evaluated mesh (modifiers
   applied) as arrays, its vertex normals, the triangles of every other visible object as
   occluders in the object's local frame, the lobe, the orders s and s' and what the method needs.
   Nothing in the .blend changes.
2. `BakeJob.run` (a worker thread in the UI, or the caller's thread): sdnative.bake_transfer for
   each object, with progress and cancellation; it only reads the arrays of step 1 (bpy is never
   touched off the main thread), and the native bake releases the GIL.
3. `BakeJob.apply` (main thread, only after every object baked): for each object a new mesh
   datablock "SD <object>", a copy of the evaluated geometry carrying the results as `sd_`
   attributes (attributes.py), with a fake user so it persists; the object links it in the custom
   property `sd_baked_mesh` and records the settings in `sd_bake` (README.md, "Where the results
   live", lists its keys). A previous baked mesh is removed only then. The object's own mesh is
   never modified: a cancelled or failed bake leaves the file as it was.
"""

import os
import threading
import time
import uuid

import numpy as np

from . import attributes, compat, environment, materials, native
from .utils import methods, transforms
from .utils.bake_data import BAKE, BAKED_MESH

MESH_PREFIX = "SD "
GEOMETRY_TYPES = {'MESH', 'CURVE', 'SURFACE', 'META', 'FONT'}


class BakeError(Exception):
    """A bake that cannot run or failed, with a message for the user."""


# --------------------------------------------------------------------------------------------
# Geometry

def _vertex_normals(mesh):
    normals = compat.vertex_normals(mesh).astype(np.float64)
    length = np.linalg.norm(normals, axis=1)
    bad = ~(length > 1e-12)
    normals[bad] = (0.0, 0.0, 1.0)
    length[bad] = 1.0
    return normals / length[:, None]


class Geometry:
    """A mesh as arrays: vertices, normals, triangles and its polygons (to rebuild it)."""

    def __init__(self, mesh):
        self.vertices = attributes.read_positions(mesh).astype(np.float64)
        self.triangles = attributes.read_triangles(mesh)
        self.normals = _vertex_normals(mesh)
        self.loop_vertices = np.empty(len(mesh.loops), dtype=np.int32)
        mesh.loops.foreach_get('vertex_index', self.loop_vertices)
        self.loop_starts = np.empty(len(mesh.polygons), dtype=np.int32)
        mesh.polygons.foreach_get('loop_start', self.loop_starts)
        self.loop_totals = np.empty(len(mesh.polygons), dtype=np.int32)
        mesh.polygons.foreach_get('loop_total', self.loop_totals)

    def build_mesh(self, name):
        """A new mesh datablock with this geometry, vertices in the same order."""
        return attributes.new_mesh(name, self.vertices, self.loop_vertices, self.loop_starts,
                                   self.loop_totals)


def _evaluated_arrays(obj, depsgraph):
    """Geometry of the object's evaluated mesh (modifiers applied)."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if mesh is None:
            return None
        return Geometry(mesh)
    finally:
        evaluated.to_mesh_clear()


def world_triangles(obj, depsgraph, view_layer):
    """World-space triangles of a visible object with geometry: (vertices float64 [V, 3],
    triangles [T, 3]) or None."""
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
        return (transforms.transform_points(evaluated.matrix_world, attributes.read_positions(mesh)),
                triangles)
    finally:
        evaluated.to_mesh_clear()


# --------------------------------------------------------------------------------------------
# Step 1: what to bake

class BakeTask:
    """One object to bake: inputs (arrays) and settings; the worker fills `result`."""

    def __init__(self, obj_name, geometry, occluders, settings):
        self.object_name = obj_name
        self.geometry = geometry
        self.occluder_vertices, self.occluder_triangles = occluders
        self.settings = settings      # dict, becomes the `sd_bake` property
        self.result = None

    def bake_arguments(self):
        s = self.settings
        method = methods.get(s["method"])
        kwargs = {"rays": int(s["rays"]), "seed": int(s["seed"])}
        kwargs.update(method.bake_arguments(int(s["light_order"]), int(s["visibility_order"])))
        if self.occluder_vertices is not None:
            kwargs["occluder_vertices"] = self.occluder_vertices
            kwargs["occluder_triangles"] = self.occluder_triangles
        return kwargs


def bake_settings(scene, obj, env_source):
    """The settings dict of a bake of `obj` under the scene's panel settings."""
    settings = scene.sd_lighting
    method = methods.get(settings.method)
    lobe, exponent = materials.lobe_for(obj, settings)
    if method.lambert_only and lobe != "lambert":
        raise BakeError("%s needs a Lambert material; %s is Phong (sigma %.3g)"
                        % (method.label, obj.name, exponent))
    if settings.automatic_orders:
        try:
            order = environment.smallest_order(env_source, lobe, exponent, settings.target_error,
                                               settings.max_automatic_order)
        except Exception as exc:
            raise BakeError("cannot choose s automatically: %s" % exc) from exc
    else:
        order = settings.light_order
    v_order = settings.visibility_order if method.uses_visibility_order else 0
    return {
        "method": method.id, "lobe": lobe, "exponent": float(exponent),
        "light_order": int(order), "visibility_order": int(v_order),
        "rays": int(settings.rays), "seed": int(settings.seed),
        "environment": env_source.description,
    }


def prepare(context, objects):
    """BakeTasks for the objects (main thread). Raises BakeError when a bake cannot start."""
    scene = context.scene
    depsgraph = context.evaluated_depsgraph_get()
    view_layer = context.view_layer
    if not native.available():
        raise BakeError(native.error_message())
    objects = [o for o in objects if o.type == 'MESH']
    if not objects:
        raise BakeError("select one or more mesh objects to bake")
    env_source = environment.source(scene)
    if env_source.kind == "file":
        if not os.path.isfile(env_source.path):
            raise BakeError("environment file not found: %s" % env_source.path)

    world_occluders = {}
    for other in scene.objects:
        tris = world_triangles(other, depsgraph, view_layer)
        if tris is not None:
            world_occluders[other.name] = tris

    tasks = []
    for obj in objects:
        geometry = _evaluated_arrays(obj, depsgraph)
        if geometry is None or len(geometry.vertices) == 0 or len(geometry.triangles) == 0:
            raise BakeError("%s has no faces to bake" % obj.name)
        to_local = np.linalg.inv(np.array(obj.evaluated_get(depsgraph).matrix_world, dtype=np.float64))
        verts, tris, base = [], [], 0
        for name, (world, triangles) in world_occluders.items():
            if name == obj.name:
                continue
            verts.append(transforms.transform_points(to_local, world))
            tris.append(triangles + base)
            base += len(world)
        occluders = (np.concatenate(verts), np.concatenate(tris).astype(np.int32)) if verts else (None, None)
        tasks.append(BakeTask(obj.name, geometry, occluders, bake_settings(scene, obj, env_source)))
    return tasks


# --------------------------------------------------------------------------------------------
# Step 2: the worker

class BakeJob:
    """Bakes a list of BakeTasks; run() in any thread, apply() on the main thread afterwards."""

    def __init__(self, tasks):
        self.tasks = tasks
        self.current = 0              # index of the task being baked
        self.fraction = 0.0           # overall progress in [0, 1]
        self.cancel_requested = False
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
        return "SD Lighting: baking %s (%d/%d), %d %%  -  Esc to cancel" % (
            task.object_name, min(self.current + 1, len(self.tasks)), len(self.tasks),
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

                def progress(done, total, index=index):
                    self.fraction = (index + (done / total if total else 1.0)) / count
                    return not self.cancel_requested

                geometry = task.geometry
                t0 = time.perf_counter()
                result = sd.bake_transfer(geometry.vertices, geometry.normals, geometry.triangles,
                                          progress=progress, **task.bake_arguments())
                result = dict(result)
                result.setdefault("seconds", time.perf_counter() - t0)
                task.result = result
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
                obj = bpy.data.objects.get(task.object_name)
                if obj is None:
                    raise BakeError("%s was deleted during the bake" % task.object_name)
                mesh = task.geometry.build_mesh(MESH_PREFIX + task.object_name)
                built.append((obj, mesh, task))
                floats = attributes.write(mesh, task.geometry.normals, task.result)
                settings = dict(task.settings)
                settings.update(_result_summary(task, floats))
                mesh[BAKE] = settings
                mesh.use_fake_user = True
        except Exception:
            for _, mesh, _ in built:
                bpy.data.meshes.remove(mesh)
            raise
        for obj, mesh, task in built:
            old = obj.get(BAKED_MESH)
            obj[BAKED_MESH] = mesh
            obj[BAKE] = dict(mesh[BAKE])
            if old is not None and old != mesh and isinstance(old, bpy.types.Mesh) and BAKE in old:
                bpy.data.meshes.remove(old)
            mesh.name = MESH_PREFIX + obj.name
        return [obj.name for obj, _, _ in built]


def _result_summary(task, floats):
    result = task.result
    n = len(task.geometry.vertices)
    summary = {
        "seconds": float(result.get("seconds", 0.0)),
        "vertices": int(n),
        "floats_per_vertex": int(floats),
        "bytes_per_vertex": int(4 * floats),
        "bake_id": uuid.uuid4().hex,
    }
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


def clear(obj):
    """Removes the object's bake (its baked mesh and custom properties)."""
    import bpy
    mesh = baked_mesh(obj)
    for key in (BAKED_MESH, BAKE):
        if key in obj:
            del obj[key]
    if mesh is not None:
        bpy.data.meshes.remove(mesh)
