"""What a bake was baked from (issue 32, item 1): a digest of the evaluated mesh - its topology (each
polygon's corner count and vertices) and its vertex positions in the object's local space, as
float32 bits - recorded as the bake record's `source`. The same mesh evaluated again gives the
same digest; an edit, a modifier added or changed, a shape key or an armature at another frame
changes it. Moving, rotating or scaling the object does not (scale: store.baked.scale_changed).

Nothing here needs Blender beyond reading the mesh's arrays.
"""

import hashlib

import numpy as np

from . import attributes


def digest(positions, loop_vertices, loop_totals):
    """The source digest of a mesh's arrays: positions float32 [V, 3] (local space), each loop's
    vertex, each polygon's loop count. A hex string."""
    hasher = hashlib.blake2b(digest_size=16)
    for array, dtype in ((positions, np.float32), (loop_vertices, np.int32), (loop_totals, np.int32)):
        array = np.ascontiguousarray(array, dtype=dtype)
        hasher.update(np.int64(array.size).tobytes())
        hasher.update(array.tobytes())
    return hasher.hexdigest()


def mesh_digest(mesh):
    """The source digest of a mesh (an evaluated object's to_mesh())."""
    loop_vertices = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get('vertex_index', loop_vertices)
    loop_totals = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get('loop_total', loop_totals)
    return digest(attributes.read_positions(mesh), loop_vertices, loop_totals)
