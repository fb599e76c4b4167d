"""Rotations and affine transforms in float64 numpy: Blender's Euler angles, the world Mapping
node's g, the rotation of an object's matrix, points through a matrix. mathutils works in float32,
not orthogonal enough for the SH rotation's 1e-9 check.
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
    """The rotation of a 3x3 or 4x4 affine matrix (polar decomposition of its 3x3 part)."""
    u, _, vt = np.linalg.svd(np.asarray(matrix, dtype=np.float64)[:3, :3])
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] = -u[:, -1]
        r = u @ vt
    return r


def transform_points(matrix, points):
    """Points [N, 3] through a 4x4 affine matrix, float64."""
    matrix = np.asarray(matrix, dtype=np.float64)
    return np.asarray(points, dtype=np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
