"""Baked meshes in the .blend: storing a bake's results, finding an object's bake and its record,
and removing them.

Each baked object links a mesh datablock "SD <object>" in its custom property `sd_baked_mesh`: a
copy of the evaluated geometry carrying the results as `sd_` attributes (attributes.py), with a fake
user so it persists, and the bake record (record.py) in `sd_bake`, on the mesh and, as a copy, on
the object. A bake with texture-space data also has the UV map "SD Lightmap" and links the
texels' mesh "SD Lightmap <object>" (one point per texel stored, the same attributes) in the baked
mesh's `sd_lightmap` property. A bake with designs (eq. 13) links their nodes' mesh "SD <object>
Design" (attributes.py). Shift+D and Alt+D copies of a baked object link the same baked mesh:
it is removed only when no object links it any more (Clear Bake), and before the file is saved
once the objects that linked it were deleted (remove_unlinked).
"""

import contextlib
import dataclasses

import numpy as np

from ..errors import BakeError
from ..scene import materials, transforms
from . import attributes
from .bake_data import BAKE, BAKED_MESH, DESIGN_TOTAL, LIGHTMAP, LIGHTMAP_UV, TEXEL, UV
from .record import BakeRecord, RecordError

MESH_PREFIX = "SD "
LIGHTMAP_PREFIX = "SD Lightmap "


@dataclasses.dataclass
class Bake:
    """One object's finished bake, to store: the geometry baked (bake/geometry.py: its build_mesh,
    material_slots, uvs and, with texels, lightmap_uvs), sdnative.bake_transfer's result (with
    "lightmap": the texels, bake/task.py) and the record, whose floats and bytes per vertex
    `store` fills in."""
    object_name: str
    geometry: object
    result: dict
    record: BakeRecord


def store(bakes):
    """Stores the bakes (main thread) and returns the baked objects' names. All or nothing: the
    new meshes are built first; only when every one is complete are they linked and the previous
    baked meshes removed."""
    import bpy
    built = []
    try:
        for bake in bakes:
            obj = bpy.data.objects.get((bake.object_name, None))   # the local one
            if obj is None:
                raise BakeError("%s was deleted during the bake" % bake.object_name)
            mesh = bake.geometry.build_mesh(MESH_PREFIX + bake.object_name)
            built.append((obj, mesh))
            stored = attributes.write(mesh, bake.result["normals"], bake.result)
            attributes.write_surface(mesh, bake.geometry.material_slots, bake.geometry.uvs, bake.geometry.sides)
            if "lightmap" in bake.result:
                mesh.uv_layers.new(name=LIGHTMAP_UV).data.foreach_set("uv", bake.geometry.lightmap_uvs.ravel())
                mesh[LIGHTMAP] = _lightmap_mesh(LIGHTMAP_PREFIX + bake.object_name, bake.result["lightmap"])
            record = dataclasses.replace(bake.record, floats_per_vertex=stored / 4, bytes_per_vertex=stored)
            mesh[BAKE] = record.to_dict()
            mesh.use_fake_user = True
    except Exception:
        for _, mesh in built:
            _remove_baked_mesh(mesh)
        raise
    released = {}
    for obj, mesh in built:
        old = baked_mesh(obj)
        obj[BAKED_MESH] = mesh
        obj[BAKE] = dict(mesh[BAKE])
        if old is not None:
            released[old.as_pointer()] = old
    for old in released.values():
        _release(old)
    for obj, mesh in built:
        name = MESH_PREFIX + obj.name
        if mesh.name != name and name not in bpy.data.meshes:  # free now that the old one went
            mesh.name = name
        nodes = attributes.design_nodes_mesh(mesh)
        if nodes is not None and nodes.name != mesh.name + attributes.DESIGN_SUFFIX:
            nodes.name = mesh.name + attributes.DESIGN_SUFFIX
    return [obj.name for obj, _ in built]


def _lightmap_mesh(name, texels):
    """The texels' mesh of a bake's "lightmap" (BakeTask.bake_lightmap): one point per texel
    stored, in entry order, at its point in the local space, with its values of the bake's
    attributes and its entry (attributes.write_texels)."""
    import bpy
    mesh = bpy.data.meshes.new(name)
    try:
        mesh.vertices.add(len(texels["stored"]))
        mesh.vertices.foreach_set("co", texels["positions"].astype(np.float32).ravel())
        attributes.write(mesh, texels["normals"], texels["values"])
        attributes.write_texels(mesh, texels["stored"])
        mesh.use_fake_user = True
    except Exception:
        bpy.data.meshes.remove(mesh)
        raise
    return mesh


def baked_mesh(obj):
    """The object's baked mesh, or None."""
    import bpy
    mesh = obj.get(BAKED_MESH) if obj is not None else None
    if isinstance(mesh, bpy.types.Mesh) and BAKE in mesh:
        return mesh
    return None


_frame_records = None   # mesh pointer -> its BakeRecord or RecordError, inside records_once()


@contextlib.contextmanager
def records_once():
    """Within it (the main thread's draw of a frame), each baked mesh's record is read from its
    property once: a frame asks for an object's record in each of its steps, and reading one
    takes tens of microseconds. Records are frozen; nothing edits them while a frame is drawn."""
    global _frame_records
    _frame_records = {}
    try:
        yield
    finally:
        _frame_records = None


def mesh_record(mesh):
    """The BakeRecord of a baked mesh; record.RecordError when it cannot be read."""
    if _frame_records is None:
        return BakeRecord.from_dict(mesh[BAKE].to_dict())
    key = mesh.as_pointer()
    known = _frame_records.get(key)
    if known is None:
        try:
            known = BakeRecord.from_dict(mesh[BAKE].to_dict())
        except RecordError as exc:
            known = exc
        _frame_records[key] = known
    if isinstance(known, RecordError):
        raise known
    return known


def record(obj):
    """The BakeRecord of the object's bake, or None without one; record.RecordError when it
    cannot be read (bake again)."""
    mesh = baked_mesh(obj)
    return mesh_record(mesh) if mesh is not None else None


def scale_changed(obj):
    """Whether the object's scale (with shear and mirror) differs from the one it was baked with,
    e.g. an animated scale at another frame: its bake then shades the shape it had, until baked
    again. False for a bake that did not record it."""
    baked = record(obj)
    if baked is None or not baked.shape:
        return False
    shape = np.array(baked.shape, dtype=np.float64).reshape(3, 3)
    current = transforms.bake_space(obj.matrix_world)[0]
    return not np.allclose(current, shape, rtol=0.0, atol=1e-5 * np.abs(shape).max())


def placed_elsewhere(obj, matrix=None):
    """Whether the object drawn with `matrix` (default: its world matrix; an instance's, or a linked
    copy's own) stands elsewhere than its bake was made - moved, turned, or another copy - while
    other objects occluded that bake: their shadows on it are then those of the baked place. False
    for a bake that did not record its place or had nothing else to occlude it."""
    baked = record(obj)
    if baked is None or not baked.placement or not baked.occluder_triangles:
        return False
    placement = np.array(baked.placement, dtype=np.float64).reshape(4, 4)
    current = np.array(obj.matrix_world if matrix is None else matrix, dtype=np.float64)
    size = max(np.abs(placement[:3, :3]).max(), 1e-12)
    return not (np.allclose(current[:3, :3], placement[:3, :3], rtol=0.0, atol=1e-5 * size) and
                np.allclose(current[:3, 3], placement[:3, 3], rtol=0.0, atol=1e-5 * (size + np.abs(placement[:3, 3]).max())))


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


def _owned_meshes(mesh):
    """The meshes that go with a baked mesh: its texels' mesh and the nodes' meshes of both."""
    texels = lightmap_mesh(mesh)
    holders = [m for m in (mesh, texels) if m is not None]
    return [m for m in [texels] + [attributes.design_nodes_mesh(h) for h in holders] if m is not None]


def _remove_baked_mesh(mesh):
    """Removes a baked mesh and the meshes that go with it."""
    import bpy
    owned = _owned_meshes(mesh)
    bpy.data.meshes.remove(mesh)
    for other in owned:
        if other.library is None:
            bpy.data.meshes.remove(other)


def _release(mesh):
    """Removes a baked mesh that no object links any more."""
    import bpy
    if mesh.library is None and not any(o.get(BAKED_MESH) == mesh for o in bpy.data.objects):
        _remove_baked_mesh(mesh)


def remove_unlinked():
    """Removes the baked meshes (with the meshes that go with them) that no object in use links:
    those of deleted objects, which their fake user would otherwise keep in the file; and texels'
    or nodes' meshes that no baked mesh links any more. Returns their names."""
    import bpy
    linked = set()
    for obj in bpy.data.objects:
        mesh = obj.get(BAKED_MESH)
        if obj.users > 0 and isinstance(mesh, bpy.types.Mesh):
            linked.add(mesh.as_pointer())
    # Chosen before anything is removed: removing one also removes the meshes that go with it,
    # which a loop over bpy.data.meshes would reach afterwards.
    unlinked = [mesh for mesh in bpy.data.meshes
                if mesh.library is None and BAKE in mesh and mesh.as_pointer() not in linked]
    removed = [mesh.name for mesh in unlinked]
    for mesh in unlinked:
        _remove_baked_mesh(mesh)
    owned = {other.as_pointer() for mesh in bpy.data.meshes if BAKE in mesh for other in _owned_meshes(mesh)}
    orphans = [mesh for mesh in bpy.data.meshes if mesh.library is None and mesh.as_pointer() not in owned
               and (TEXEL in mesh.attributes or DESIGN_TOTAL in mesh)]
    removed += [mesh.name for mesh in orphans]
    for mesh in orphans:
        bpy.data.meshes.remove(mesh)
    return removed


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
