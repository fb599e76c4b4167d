"""Everything that differs between the Blender versions the add-on supports (3.4 - 5.x), in one
place. The rest of the add-on calls these and never tests bpy.app.version itself.

Tested by the Blender suite on Debian's Blender 3.4.1 and on the bpy modules pinned in
blender_tests/bpy_versions.txt:

| API                               | versions     | here                                        |
|-----------------------------------|--------------|---------------------------------------------|
| Mesh.vertex_normals               | 3.5+         | vertex_normals(); MeshVertex.normal before  |
| Mesh.corner_normals               | 4.1+         | corner_normals(); calc_normals_split() and  |
|   (calc_normals_split, auto smooth removed)     |   MeshLoop.normal before                    |
| MeshPolygon.loop_total read-only  | 4.0+         | set_polygon_loops()                         |
| built-in shader '3D_UNIFORM_COLOR'| 'UNIFORM_COLOR' since 3.5, the 3D_ name gone in 4.0: uniform_color_shader() |
| World/Material.use_nodes          | deprecated in 5.0 (node trees always used, gone in 6.0): uses_nodes() |
| Principled BSDF                   | 4.0+ layers its specular over the diffuse, and renames its inputs: principled_layered(), PRINCIPLED_LAYERS |
| GPUVertFormat                     | 4.5 deprecates, 5.0 rejects non-F32 fetch modes; 3.4's batch_for_shader misreads some programs: vertex_buffer() |
| bpy.props on IDs                  | 5.0 keeps them apart from id["..."]: properties.py reads and writes them as attributes |
"""

import numpy as np


def version():
    import bpy
    return tuple(bpy.app.version)


def _has_rna_property(struct_type, name):
    return name in struct_type.bl_rna.properties


def vertex_normals(mesh):
    """float32 [V, 3]: the mesh's vertex normals (Mesh.vertex_normals on 3.5+, MeshVertex.normal
    before)."""
    n = len(mesh.vertices)
    normals = np.empty(n * 3, dtype=np.float32)
    if _has_rna_property(type(mesh), "vertex_normals"):
        mesh.vertex_normals.foreach_get('vector', normals)
    else:
        mesh.vertices.foreach_get('normal', normals)
    return normals.reshape(n, 3)


def corner_normals(mesh):
    """float32 [L, 3]: the mesh's corner (split) normals, one per loop - what the mesh is shaded
    with (flat faces, sharp edges, custom normals). Mesh.corner_normals on 4.1+ (a cache,
    computed on access); before 4.1 Mesh.calc_normals_split() fills MeshLoop.normal (with
    auto smooth off that gives face normals for flat faces and vertex normals for smooth ones,
    as 4.1+ does)."""
    n = len(mesh.loops)
    normals = np.empty(n * 3, dtype=np.float32)
    if _has_rna_property(type(mesh), "corner_normals"):
        mesh.corner_normals.foreach_get('vector', normals)
    else:
        mesh.calc_normals_split()
        mesh.loops.foreach_get('normal', normals)
    return normals.reshape(n, 3)


def set_polygon_loops(mesh, loop_starts, loop_totals):
    """Sets the polygons' loop_start (and loop_total, which 4.0+ derives from the starts and
    makes read-only)."""
    import bpy
    mesh.polygons.foreach_set('loop_start', loop_starts)
    if not bpy.types.MeshPolygon.bl_rna.properties['loop_total'].is_readonly:
        mesh.polygons.foreach_set('loop_total', loop_totals)


def uniform_color_shader():
    """Blender's built-in uniform-colour shader for 3D positions ('pos', uniform 'color')."""
    import gpu
    return gpu.shader.from_builtin('3D_UNIFORM_COLOR' if version() < (3, 5, 0) else 'UNIFORM_COLOR')


def uses_nodes(idblock):
    """Whether a world or material is shaded by its node tree. 5.0 always uses the node tree and
    deprecates `use_nodes` (reading it warns; it goes in 6.0)."""
    if idblock is None or idblock.node_tree is None:
        return False
    if version() >= (5, 0, 0):
        return True
    return bool(idblock.use_nodes)


def principled_layered(node):
    """Whether the Principled BSDF is Blender 4.0's, whose specular layer lies over the diffuse
    and takes its energy from it (it has Specular IOR Level where the earlier one had Specular)."""
    return node.inputs.get("Specular IOR Level") is not None


# The Principled BSDF's layers that Lambert + Phong leave out, by the input that turns each on
# (Blender 4.x's name first, then 3.x's).
PRINCIPLED_LAYERS = (("transmission", ("Transmission Weight", "Transmission")),
                     ("coat", ("Coat Weight", "Clearcoat")),
                     ("sheen", ("Sheen Weight", "Sheen")),
                     ("subsurface", ("Subsurface Weight", "Subsurface")))


def vertex_buffer(content):
    """A GPUVertBuf of float attributes (name -> float32 [N, k], k <= 4) with the vertex format built
    here: gpu_extras' batch_for_shader asks the shader for its attributes, which Blender 3.4
    reports wrongly for some programs (names and types out of order). Only F32 x 1-4 with fetch
    mode FLOAT: 4.5 deprecates formats that are not 4-byte aligned, wider than 4 components or
    INT_TO_FLOAT, and 5.0 rejects the last two."""
    import gpu
    vertex_format = gpu.types.GPUVertFormat()
    arrays = {}
    for name, values in content.items():
        values = np.ascontiguousarray(values, dtype=np.float32)
        values = values.reshape(len(values), -1)
        if not 1 <= values.shape[1] <= 4:
            raise ValueError("vertex attribute %s has %d components (1-4 allowed)" % (name, values.shape[1]))
        arrays[name] = values
        vertex_format.attr_add(id=name, comp_type='F32', len=values.shape[1], fetch_mode='FLOAT')
    count = len(next(iter(arrays.values())))
    buffer = gpu.types.GPUVertBuf(vertex_format, count)
    for name, values in arrays.items():
        buffer.attr_fill(name, values)
    return buffer


def make_batch(primitive, content, indices=None):
    """A GPUBatch of a vertex_buffer(content) or of an existing GPUVertBuf, indexed when indices
    are given."""
    import gpu
    buffer = content if isinstance(content, gpu.types.GPUVertBuf) else vertex_buffer(content)
    if indices is None:
        return gpu.types.GPUBatch(type=primitive, buf=buffer)
    index_buffer = gpu.types.GPUIndexBuf(type=primitive, seq=np.ascontiguousarray(indices, dtype=np.int32))
    return gpu.types.GPUBatch(type=primitive, buf=buffer, elem=index_buffer)


def equirectangular_camera(camera):
    """Makes a camera panoramic, equirectangular over the whole sphere (4.0 moved the panorama's
    settings from Cycles' camera properties to the camera's own)."""
    camera.type = 'PANO'
    if _has_rna_property(type(camera), "panorama_type"):
        camera.panorama_type = 'EQUIRECTANGULAR'
    else:
        camera.cycles.panorama_type = 'EQUIRECTANGULAR'
