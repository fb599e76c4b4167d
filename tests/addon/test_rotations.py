"""Euler angles, the Mapping node's g and the rotation of an object's matrix."""

import math

import numpy as np
import pytest

from sd_lighting.utils import rotations


def test_euler_xyz_is_rz_ry_rx():
    assert np.allclose(rotations.euler_xyz((0, 0, math.pi / 2)) @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(rotations.euler_xyz((math.pi / 2, 0, 0)) @ [0, 1, 0], [0, 0, 1])
    assert np.allclose(rotations.euler_xyz((0, math.pi / 2, 0)) @ [0, 0, 1], [1, 0, 0])
    # X first, then Z: +X turned about X stays +X, then about Z by 90 degrees is +Y
    assert np.allclose(rotations.euler_xyz((0.7, 0, math.pi / 2)) @ [1, 0, 0], [0, 1, 0])


def test_euler_xyz_is_orthogonal_to_float64():
    g = rotations.euler_xyz((0.3, -1.2, 2.5))
    assert np.abs(g @ g.T - np.eye(3)).max() < 1e-15 and np.linalg.det(g) == pytest.approx(1.0)


def test_mapping_rotation_inverts_for_texture_type():
    angles = (0.1, 0.2, 0.3)
    g = rotations.mapping_rotation(angles, 'POINT')
    assert np.array_equal(g, rotations.euler_xyz(angles))
    assert np.array_equal(rotations.mapping_rotation(angles, 'TEXTURE'), g.T)
    assert np.array_equal(rotations.mapping_rotation(angles, 'VECTOR'), g)


def test_rotation_part_of_scaled_and_mirrored_matrices():
    r = rotations.euler_xyz((0.4, 0.1, -0.7))
    matrix = np.eye(4)
    matrix[:3, :3] = r * 0.8
    matrix[:3, 3] = (1, 2, 3)
    assert np.allclose(rotations.rotation_part(matrix), r, atol=1e-14)
    mirrored = r @ np.diag([1.0, -2.0, 3.0])
    part = rotations.rotation_part(mirrored)
    assert np.linalg.det(part) == pytest.approx(1.0) and np.allclose(part @ part.T, np.eye(3))
