"""Rotations and affine transforms in float64 numpy: Blender's Euler angles, the world Mapping
node's g, the rotation of an object's matrix and the space it is baked in, points through a
matrix. mathutils works in float32, not orthogonal enough for the SH rotation's 1e-9 check.
"""

import numpy as np


def euler_xyz(angles):
    """The rotation matrix of Blender's XYZ Euler angles: Rz Ry Rx."""
    x, y, z = (float(a) for a in angles)
    cx, sx, cy, sy, cz, sz = np.cos(x), np.sin(x), np.cos(y), np.sin(y), np.cos(z), np.sin(z)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def mapping_rotation(angles, vector_type):
    """g of eq. (1) for a Mapping node in front of the Environment Texture: for vector types
    Point, Vector and Normal the texture is looked up at R d, so the world is L(R d) and g = R; for
    Texture the node applies the inverse, g = R^T (R: the node's XYZ Euler rotation)."""
    g = euler_xyz(angles)
    return g.T if vector_type == 'TEXTURE' else g


def rotation_part(matrix):
    """The rotation R of a 3x3 or 4x4 affine matrix whose 3x3 part is A = R K (K = R^T A: the
    scale, shear and mirror). R is the orthogonal factor of A's polar decomposition, negated when
    A mirrors - the same choice as Blender's Matrix.decompose(), which reports a mirror as a
    negative scale on every axis. It is unique and turns with the object (the rotation of Q A is
    Q R), so directions baked in the space R^T (world) stay attached to it."""
    u, _, vt = np.linalg.svd(np.asarray(matrix, dtype=np.float64)[:3, :3])
    r = u @ vt
    return -r if np.linalg.det(r) < 0 else r


def bake_space(matrix):
    """The space an object is baked in: its local space with the scale applied and the rotation
    and translation not. Returns (K, to_bake_space): K [3, 3] takes the object's local coordinates
    into it (p -> K p), to_bake_space [4, 4] world coordinates (w -> R^T (w - t)); R, K as in
    rotation_part."""
    matrix = np.asarray(matrix, dtype=np.float64)
    r = rotation_part(matrix)
    to_bake_space = np.eye(4)
    to_bake_space[:3, :3] = r.T
    to_bake_space[:3, 3] = -r.T @ matrix[:3, 3]
    return r.T @ matrix[:3, :3], to_bake_space


def transform_points(matrix, points):
    """Points [N, 3] through a 4x4 affine matrix, float64."""
    matrix = np.asarray(matrix, dtype=np.float64)
    return np.asarray(points, dtype=np.float64) @ matrix[:3, :3].T + matrix[:3, 3]


def equirect_directions(width, height):
    """The unit directions of the texel centres of a width x height equirect map in Blender's
    orientation (u = 0.5 - atan2(y, x) / 2pi, v = 1 - acos(z) / pi; texel (i, j) centred at
    u = (i + 0.5) / width, v = (j + 0.5) / height), rows bottom-first (j = 0 at the south pole),
    as GPU textures hold them: float64 [height, width, 3]."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    phi = (0.5 - u)[None, :] * 2.0 * np.pi
    theta = (1.0 - v)[:, None] * np.pi
    sin_theta = np.sin(theta)
    return np.stack(np.broadcast_arrays(sin_theta * np.cos(phi), sin_theta * np.sin(phi),
                                        np.cos(theta)), axis=-1)
