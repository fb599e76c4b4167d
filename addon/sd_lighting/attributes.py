"""Bake results as mesh attributes: names, writing and reading.

Every result is a POINT attribute (one value per vertex) of the baked mesh, with the prefix `sd_`
and 1-4 float components:

  sd_normal              FLOAT_VECTOR  the unit normal the vertex was baked (and is shaded) with
  sd_ambient_occlusion   FLOAT         AO = V~_00, the visible fraction of the sphere of directions
  sd_visibility_NNN      FLOAT_COLOR   SH coefficients 4N..4N+3 of the visibility V~ (order s');
                                       PRT (10) and MSD Theorem 2.1 (12)
  sd_transfer_NNN        FLOAT_COLOR   coefficients 4N..4N+3 of the diffuse transfer vector T
                                       (order s); PRT (2)
  sd_matrix_NNN          FLOAT_COLOR   entries 4N..4N+3 of the product matrix M, row-major
                                       ((s+1)^2 rows, (s'+1)^2 columns); PRT (8)
  sd_design_NNN          FLOAT_COLOR   node N of the vertex's design of V (MSD Theorem 2.2, eq. 13):
                                       x, y, z (unit direction) and weight lambda; lambda = 0 pads
                                       vertices with fewer nodes

NNN counts from 000; a vector's last group is padded with zeros. SH coefficients follow sdnative's
convention (index l^2 + l + m). Directions are in the object's local frame at bake time. Bake
settings are in the custom property `sd_bake` of the mesh and of the object (see baking.py).
"""

import numpy as np

PREFIX = "sd_"
NORMAL = PREFIX + "normal"
AMBIENT_OCCLUSION = PREFIX + "ambient_occlusion"
GROUPS = ("visibility", "transfer", "matrix", "design")


def group_name(kind, index):
    """Name of the index-th vec4 attribute of a kind: sd_visibility_000, ..."""
    return "%s%s_%03d" % (PREFIX, kind, index)


def _group_names(mesh, kind):
    names = []
    while group_name(kind, len(names)) in mesh.attributes:
        names.append(group_name(kind, len(names)))
    return names


def _as_vec4_groups(values):
    """[N, K] -> [G, N, 4] with G = ceil(K / 4), zero padded."""
    values = np.asarray(values, dtype=np.float32)
    n, k = values.shape
    groups = (k + 3) // 4
    padded = np.zeros((n, 4 * groups), dtype=np.float32)
    padded[:, :k] = values
    return padded.reshape(n, groups, 4).transpose(1, 0, 2)


def padded_designs(offsets, nodes, weights):
    """Per-vertex designs as [N, max_nodes, 4] (x, y, z, lambda), lambda = 0 padding."""
    offsets = np.asarray(offsets, dtype=np.int64)
    counts = np.diff(offsets)
    n = counts.size
    width = int(counts.max()) if n else 0
    padded = np.zeros((n, max(width, 1), 4), dtype=np.float32)
    if offsets[-1] > 0:
        vertex = np.repeat(np.arange(n), counts)
        slot = np.arange(offsets[-1]) - offsets[vertex]
        padded[vertex, slot, :3] = np.asarray(nodes, dtype=np.float32).reshape(-1, 3)
        padded[vertex, slot, 3] = np.asarray(weights, dtype=np.float32)
    return padded


def unpadded_designs(padded):
    """Inverse of padded_designs: (offsets int64 [N+1], nodes [total, 3], weights [total])."""
    used = padded[:, :, 3] > 0.0
    offsets = np.zeros(padded.shape[0] + 1, dtype=np.int64)
    np.cumsum(used.sum(axis=1), out=offsets[1:])
    return offsets, padded[used][:, :3].astype(np.float64), padded[used][:, 3].astype(np.float64)


def remove_all(mesh):
    """Removes every sd_ attribute."""
    for name in [a.name for a in mesh.attributes if a.name.startswith(PREFIX)]:
        mesh.attributes.remove(mesh.attributes[name])


def _new(mesh, name, data_type, prop, values):
    attribute = mesh.attributes.new(name, data_type, 'POINT')
    attribute.data.foreach_set(prop, np.ascontiguousarray(values, dtype=np.float32).ravel())


def write(mesh, normals, result):
    """Stores a bake result (sdnative.bake_transfer's dict) on the mesh; returns floats per vertex.

    Only the keys present in `result` are written (a bake stores only what its method needs).
    """
    remove_all(mesh)
    floats = 0
    _new(mesh, NORMAL, 'FLOAT_VECTOR', 'vector', normals)
    n = len(mesh.vertices)
    if result.get("ambient_occlusion") is not None:
        _new(mesh, AMBIENT_OCCLUSION, 'FLOAT', 'value', result["ambient_occlusion"])
        floats += 1
    groups = {}
    if result.get("visibility") is not None:
        groups["visibility"] = _as_vec4_groups(result["visibility"])
    if result.get("transfer") is not None:
        groups["transfer"] = _as_vec4_groups(result["transfer"])
    if result.get("product_matrices") is not None:
        groups["matrix"] = _as_vec4_groups(np.asarray(result["product_matrices"]).reshape(n, -1))
    if result.get("design_offsets") is not None:
        groups["design"] = padded_designs(result["design_offsets"], result["design_nodes"],
                                          result["design_weights"]).transpose(1, 0, 2)
    for kind, vec4s in groups.items():
        for index, values in enumerate(vec4s):
            _new(mesh, group_name(kind, index), 'FLOAT_COLOR', 'color', values)
        floats += 4 * len(vec4s)
    return floats


def _read(mesh, name, prop, components):
    attribute = mesh.attributes[name]
    values = np.empty(len(attribute.data) * components, dtype=np.float32)
    attribute.data.foreach_get(prop, values)
    return values.reshape(-1, components) if components > 1 else values


def read_vec4_groups(mesh, kind):
    """The vec4 attributes of a kind as [N, G, 4] float32 (G = 0 when there are none)."""
    names = _group_names(mesh, kind)
    n = len(mesh.vertices)
    out = np.zeros((n, len(names), 4), dtype=np.float32)
    for index, name in enumerate(names):
        out[:, index, :] = _read(mesh, name, 'color', 4)
    return out


def read_normals(mesh):
    """The baked normals, float32 [N, 3]."""
    return _read(mesh, NORMAL, 'vector', 3)


def read_positions(mesh):
    positions = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get('co', positions)
    return positions.reshape(-1, 3)


def read_triangles(mesh):
    mesh.calc_loop_triangles()
    triangles = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get('vertices', triangles)
    return triangles.reshape(-1, 3)


def read(mesh):
    """Everything baked, as arrays in sdnative.shade's shapes (float64 from the stored float32):
    keys normals, ambient_occlusion, visibility, transfer, product_matrices, design_offsets,
    design_nodes, design_weights (those that exist)."""
    out = {"normals": read_normals(mesh).astype(np.float64)}
    n = len(mesh.vertices)
    if AMBIENT_OCCLUSION in mesh.attributes:
        out["ambient_occlusion"] = _read(mesh, AMBIENT_OCCLUSION, 'value', 1).astype(np.float64)
    bake = dict(mesh.get("sd_bake", {}))
    k = (int(bake.get("light_order", 0)) + 1) ** 2
    kv = (int(bake.get("visibility_order", 0)) + 1) ** 2
    if _group_names(mesh, "visibility"):
        out["visibility"] = read_vec4_groups(mesh, "visibility").reshape(n, -1)[:, :kv].astype(np.float64)
    if _group_names(mesh, "transfer"):
        out["transfer"] = read_vec4_groups(mesh, "transfer").reshape(n, -1)[:, :k].astype(np.float64)
    if _group_names(mesh, "matrix"):
        flat = read_vec4_groups(mesh, "matrix").reshape(n, -1)[:, :k * kv]
        out["product_matrices"] = flat.reshape(n, k, kv).astype(np.float64)
    if _group_names(mesh, "design"):
        offsets, nodes, weights = unpadded_designs(read_vec4_groups(mesh, "design"))
        out["design_offsets"], out["design_nodes"], out["design_weights"] = offsets, nodes, weights
    return out


def gpu_texels(mesh, method_needs):
    """Per-vertex texels the shader reads, [N, stride, 4] float32, for a method's data kind
    ("" -> AO only, one texel; see methods.py)."""
    if method_needs == "":
        n = len(mesh.vertices)
        texels = np.zeros((n, 1, 4), dtype=np.float32)
        if AMBIENT_OCCLUSION in mesh.attributes:
            texels[:, 0, 0] = _read(mesh, AMBIENT_OCCLUSION, 'value', 1)
        return texels
    return read_vec4_groups(mesh, method_needs)


def bytes_per_vertex(mesh):
    """Bytes per vertex of the stored bake data (sd_ attributes except the normal)."""
    total = 0
    for attribute in mesh.attributes:
        if attribute.name.startswith(PREFIX) and attribute.name != NORMAL:
            total += {'FLOAT': 4, 'FLOAT_VECTOR': 12, 'FLOAT_COLOR': 16}.get(attribute.data_type, 0)
    return total
