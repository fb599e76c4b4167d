"""Bake results as POINT attributes of the baked mesh (and the points of its designs' nodes' mesh):
writing and reading them, and the mesh's geometry as arrays. What is stored and how is the table in
bake_data.py; README.md ("Attributes of the baked mesh") is the user's reference.
"""

import numpy as np

from .. import compat
from . import bake_data
from .bake_data import BAKE, NORMAL, PREFIX
from .record import BakeRecord

DESIGN_SUFFIX = " Design"   # a nodes' mesh is named after the mesh whose designs it holds


def _group_names(mesh, array):
    names = []
    while array.group_name(len(names)) in mesh.attributes:
        names.append(array.group_name(len(names)))
    return names


def design_nodes_mesh(mesh):
    """The nodes' mesh a mesh with designs links (bake_data.py), or None."""
    import bpy
    nodes = mesh.get(bake_data.DESIGN_NODES)
    return nodes if isinstance(nodes, bpy.types.Mesh) else None


def is_stored(mesh, array):
    if array.packing == "design":
        return bake_data.DESIGN_COUNT in mesh.attributes and design_nodes_mesh(mesh) is not None
    return (array.group_name(0) if array.grouped else array.attribute) in mesh.attributes


def remove_all(mesh):
    """Removes every sd_ attribute, and the nodes' mesh of its designs."""
    for name in [a.name for a in mesh.attributes if a.name.startswith(PREFIX)]:
        mesh.attributes.remove(mesh.attributes[name])
    nodes = design_nodes_mesh(mesh)
    if bake_data.DESIGN_NODES in mesh:
        del mesh[bake_data.DESIGN_NODES]
    if nodes is not None and nodes.library is None:
        import bpy
        bpy.data.meshes.remove(nodes)


def _new(mesh, name, data_type, prop, values, dtype=np.float32):
    attribute = mesh.attributes.new(name, data_type, 'POINT')
    attribute.data.foreach_set(prop, np.ascontiguousarray(values, dtype=dtype).ravel())


def _write_design(mesh, offsets, nodes, weights):
    """Stores designs at their own length (bake_data.py)."""
    import bpy
    counts = np.diff(np.asarray(offsets, dtype=np.int64))
    _new(mesh, bake_data.DESIGN_COUNT, 'INT', 'value', counts, np.int32)
    holder = bpy.data.meshes.new(mesh.name + DESIGN_SUFFIX)
    mesh[bake_data.DESIGN_NODES] = holder      # linked first: removing `mesh` removes it too
    holder.use_fake_user = True
    holder.vertices.add(len(weights))
    holder.vertices.foreach_set("co", bake_data.weighted_nodes(nodes, weights).ravel())
    holder[bake_data.DESIGN_TOTAL] = len(weights)


def write(mesh, normals, result):
    """Stores the normals and a bake result (sdnative.bake_transfer's dict) on the mesh; returns
    the bytes per vertex of the bake data (the normals not counted). A bake stores what its method
    reads (and the ambient occlusion, which every bake returns)."""
    remove_all(mesh)
    _new(mesh, NORMAL, 'FLOAT_VECTOR', 'vector', normals)
    stored = [array for array in bake_data.ARRAYS if array.in_result(result)]
    for array in stored:
        if array.packing == "design":
            _write_design(mesh, *(result[key] for key in array.keys))
        elif array.grouped:
            groups = array.groups(result)
            for index in range(groups.shape[1]):
                _new(mesh, array.group_name(index), 'FLOAT_COLOR', 'color', groups[:, index])
        else:
            _new(mesh, array.attribute, 'FLOAT', 'value', result[array.keys[0]])
    return 4 * sum(array.stored_floats(result) for array in stored)


def _read(mesh, name, prop, components, dtype=np.float32):
    attribute = mesh.attributes[name]
    values = np.empty(len(attribute.data) * components, dtype=dtype)
    attribute.data.foreach_get(prop, values)
    return values.reshape(-1, components) if components > 1 else values


def _stored_groups(mesh, array):
    """A scalar or coefficient array as stored: float32 [N, G, 4] vec4 groups."""
    if not array.grouped:
        return array.groups({array.keys[0]: _read(mesh, array.attribute, 'value', 1)})
    names = _group_names(mesh, array)
    out = np.zeros((len(mesh.vertices), len(names), 4), dtype=np.float32)
    for index, name in enumerate(names):
        out[:, index, :] = _read(mesh, name, 'color', 4)
    return out


def _stored_design(mesh):
    """The designs as stored, in sdnative's arrays: offsets int64 [N+1], nodes float64 [total, 3],
    weights float64 [total]."""
    holder = design_nodes_mesh(mesh)
    offsets = np.zeros(len(mesh.vertices) + 1, dtype=np.int64)
    np.cumsum(_read(mesh, bake_data.DESIGN_COUNT, 'value', 1, np.int32), out=offsets[1:])
    if not len(holder.vertices) == holder.get(bake_data.DESIGN_TOTAL) == offsets[-1]:
        raise ValueError("the design nodes of %s (%s) do not match its node counts: bake it again"
                         % (mesh.name, holder.name))
    return (offsets,) + bake_data.split_weighted_nodes(read_positions(holder))


def _check_stored(mesh, array):
    if not is_stored(mesh, array):
        raise ValueError("%s stores no %s data (baked by another version?): bake it again"
                         % (mesh.name, array.name))


def read_texels(mesh, array):
    """A stored array as the data texture's texels: (float32 [M, 4], texels per vertex)
    (bake_data.VertexArray.texels)."""
    _check_stored(mesh, array)
    if array.packing == "design":
        return array.texels(dict(zip(array.keys, _stored_design(mesh))))
    groups = _stored_groups(mesh, array)
    return groups.reshape(-1, 4), groups.shape[1]


def write_texels(mesh, entries):
    """Stores each point's lightmap texel (entry y W + x) on a texels' mesh."""
    _new(mesh, bake_data.TEXEL, 'FLOAT', 'value', entries)


def read_texels_entries(mesh):
    """Each point's lightmap texel of a texels' mesh, int64 [K]."""
    if bake_data.TEXEL not in mesh.attributes:
        raise ValueError("%s stores no texels (baked by another version?): bake it again" % mesh.name)
    return np.rint(_read(mesh, bake_data.TEXEL, 'value', 1)).astype(np.int64)


def read_normals(mesh):
    """The baked normals, float32 [N, 3]."""
    return _read(mesh, NORMAL, 'vector', 3)


def read_positions(mesh):
    positions = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get('co', positions)
    return positions.reshape(-1, 3)


def new_mesh(name, vertices, loop_vertices, loop_starts, loop_totals):
    """A new mesh datablock from arrays: vertex positions [V, 3], each loop's vertex, each
    polygon's first loop and loop count."""
    import bpy
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set('co', np.asarray(vertices, dtype=np.float32).ravel())
    mesh.loops.add(len(loop_vertices))
    mesh.loops.foreach_set('vertex_index', np.asarray(loop_vertices, dtype=np.int32))
    mesh.polygons.add(len(loop_starts))
    compat.set_polygon_loops(mesh, np.asarray(loop_starts, dtype=np.int32),
                             np.asarray(loop_totals, dtype=np.int32))
    mesh.update(calc_edges=True)
    return mesh


def _loop_triangles(mesh, prop):
    mesh.calc_loop_triangles()
    values = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get(prop, values)
    return values.reshape(-1, 3)


def read_triangles(mesh):
    """Each triangle's three vertices, int32 [T, 3]."""
    return _loop_triangles(mesh, 'vertices')


def read_triangle_loops(mesh):
    """Each triangle's three loops (face corners), int32 [T, 3]."""
    return _loop_triangles(mesh, 'loops')


def read_loop_material_slots(mesh):
    """Each loop's material slot (its polygon's material_index), int32 [L]."""
    starts = np.empty(len(mesh.polygons), dtype=np.int64)
    mesh.polygons.foreach_get('loop_start', starts)
    totals = np.empty(len(mesh.polygons), dtype=np.int64)
    mesh.polygons.foreach_get('loop_total', totals)
    slots = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get('material_index', slots)
    out = np.zeros(len(mesh.loops), dtype=np.int32)
    first = np.repeat(starts, totals)
    within = np.arange(totals.sum()) - np.repeat(np.cumsum(totals) - totals, totals)
    out[first + within] = np.repeat(slots, totals)
    return out


def read_loop_uvs(mesh, name):
    """Each loop's UV in the named UV layer ("": the active render layer), float32 [L, 2]; zeros
    when the mesh has no such layer."""
    layers = mesh.uv_layers
    layer = layers.get(name) if name else next((l for l in layers if l.active_render), None)
    uvs = np.zeros(len(mesh.loops) * 2, dtype=np.float32)
    if layer is not None:
        layer.data.foreach_get('uv', uvs)
    return uvs.reshape(-1, 2)


def write_surface(mesh, material_slots, uvs, sides):
    """Stores what the shading reads besides the bake: each vertex's material slot, albedo-texture
    UV and side (bake/sides.py); any may be None: one material, no texture, every vertex single."""
    if material_slots is not None:
        _new(mesh, bake_data.MATERIAL_SLOT, 'FLOAT', 'value', material_slots)
    if uvs is not None:
        _new(mesh, bake_data.UV, 'FLOAT2', 'vector', uvs)
    if sides is not None:
        _new(mesh, bake_data.SIDE, 'FLOAT', 'value', sides)


def _read_optional(mesh, name, prop, width):
    return _read(mesh, name, prop, width) if name in mesh.attributes else None


def read_surface(mesh):
    """(material slots float32 [N], UVs float32 [N, 2], sides float32 [N]) as write_surface stored
    them, each None when not stored."""
    return (_read_optional(mesh, bake_data.MATERIAL_SLOT, 'value', 1), _read_optional(mesh, bake_data.UV, 'vector', 2),
            _read_optional(mesh, bake_data.SIDE, 'value', 1))


def read(mesh, record=None):
    """Everything baked, in sdnative.shade's keywords and shapes (float64 from the stored float32):
    normals and the keys of every stored array (bake_data.py). record: the BakeRecord the arrays
    were baked with (default: the mesh's own; a texels' mesh has none)."""
    out = {"normals": read_normals(mesh).astype(np.float64)}
    if record is None:
        record = BakeRecord.from_dict(mesh[BAKE].to_dict())
    orders = record.light_order, record.visibility_order
    for array in bake_data.ARRAYS:
        if not is_stored(mesh, array):
            continue
        if array.packing == "design":
            out.update(zip(array.keys, _stored_design(mesh)))
        else:
            out.update(array.from_groups(_stored_groups(mesh, array), *orders))
    return out
