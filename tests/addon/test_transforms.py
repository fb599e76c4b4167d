"""Euler angles, the Mapping node's g and the rotation of an object's matrix."""

import math

import numpy as np
import pytest

from sd_lighting.utils import transforms


def test_euler_xyz_is_rz_ry_rx():
    assert np.allclose(transforms.euler_xyz((0, 0, math.pi / 2)) @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(transforms.euler_xyz((math.pi / 2, 0, 0)) @ [0, 1, 0], [0, 0, 1])
    assert np.allclose(transforms.euler_xyz((0, math.pi / 2, 0)) @ [0, 0, 1], [1, 0, 0])
    # X first, then Z: +X turned about X stays +X, then about Z by 90 degrees is +Y
    assert np.allclose(transforms.euler_xyz((0.7, 0, math.pi / 2)) @ [1, 0, 0], [0, 1, 0])


def test_euler_xyz_is_orthogonal_to_float64():
    g = transforms.euler_xyz((0.3, -1.2, 2.5))
    assert np.abs(g @ g.T - np.eye(3)).max() < 1e-15 and np.linalg.det(g) == pytest.approx(1.0)


def test_mapping_rotation_inverts_for_texture_type():
    angles = (0.1, 0.2, 0.3)
    g = transforms.mapping_rotation(angles, 'POINT')
    assert np.array_equal(g, transforms.euler_xyz(angles))
    assert np.array_equal(transforms.mapping_rotation(angles, 'TEXTURE'), g.T)
    assert np.array_equal(transforms.mapping_rotation(angles, 'VECTOR'), g)


def test_rotation_part_of_scaled_and_mirrored_matrices():
    r = transforms.euler_xyz((0.4, 0.1, -0.7))
    matrix = np.eye(4)
    matrix[:3, :3] = r * 0.8
    matrix[:3, 3] = (1, 2, 3)
    assert np.allclose(transforms.rotation_part(matrix), r, atol=1e-14)
    mirrored = r @ np.diag([1.0, -2.0, 3.0])
    part = transforms.rotation_part(mirrored)
    assert np.linalg.det(part) == pytest.approx(1.0) and np.allclose(part @ part.T, np.eye(3))


def test_transform_points_rotates_scales_and_translates():
    matrix = np.eye(4)
    matrix[:3, :3] = 2.0 * transforms.euler_xyz((0, 0, math.pi / 2))
    matrix[:3, 3] = (1, 2, 3)
    points = np.array([[1, 0, 0], [0, 0, 1]], dtype=np.float32)
    moved = transforms.transform_points(matrix, points)
    assert moved.dtype == np.float64 and np.allclose(moved, [[1, 4, 3], [1, 2, 5]])
