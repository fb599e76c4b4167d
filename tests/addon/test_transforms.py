"""Euler angles, the Mapping node's g and the rotation of an object's matrix."""

import math

import numpy as np
import pytest

from sd_lighting.scene import transforms


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


def test_rotation_part_of_a_mirror_is_blenders_decompose():
    # Matrix.Diagonal((-1, 1, 1)).decompose() is a rotation of 180 degrees about X and scale -1.
    assert np.allclose(transforms.rotation_part(np.diag([-1.0, 1.0, 1.0])), np.diag([1.0, -1.0, -1.0]))


@pytest.mark.parametrize("scale", [(-1.0, 1.0, 1.0), (1.0, 2.0, 0.5), (0.7, -1.3, 0.9), (-2.0, -2.0, -2.0)])
def test_rotation_part_turns_with_the_object(scale):
    # What is baked in the frame R^T (world) must stay attached to the object when it turns:
    # the rotation of Q A is Q R, also for mirrors, whose polar factor alone is no rotation.
    a = transforms.euler_xyz((0.3, -0.2, 0.5)) @ np.diag(scale)
    q = transforms.euler_xyz((1.1, 0.4, -2.0))
    r = transforms.rotation_part(a)
    assert np.linalg.det(r) == pytest.approx(1.0)
    assert np.allclose(transforms.rotation_part(q @ a), q @ r, atol=1e-12)


def test_bake_frame_applies_scale_but_not_rotation_or_translation():
    matrix = np.eye(4)
    matrix[:3, :3] = transforms.euler_xyz((0.3, -0.2, 0.5)) @ np.diag([0.7, -1.3, 0.9])
    matrix[:3, 3] = (1.0, -2.0, 3.0)
    shape, to_bake_space = transforms.bake_space(matrix)
    points = np.array([[0.1, 0.2, 0.3], [-1.0, 0.5, 2.0], [0.0, 0.0, 0.0]])
    world = transforms.transform_points(matrix, points)
    # the local points with K applied are where the world points are in the frame
    assert np.allclose(transforms.transform_points(to_bake_space, world), points @ shape.T, atol=1e-12)
    # a rigid frame: distances and angles of the world are kept
    assert np.allclose(to_bake_space[:3, :3] @ to_bake_space[:3, :3].T, np.eye(3), atol=1e-12)
    assert np.allclose(shape, shape.T, atol=1e-12) and np.linalg.det(shape) < 0
    uniform = np.diag([2.0, 2.0, 2.0, 1.0])
    assert np.allclose(transforms.bake_space(uniform)[0], 2.0 * np.eye(3))


def test_transform_points_rotates_scales_and_translates():
    matrix = np.eye(4)
    matrix[:3, :3] = 2.0 * transforms.euler_xyz((0, 0, math.pi / 2))
    matrix[:3, 3] = (1, 2, 3)
    points = np.array([[1, 0, 0], [0, 0, 1]], dtype=np.float32)
    moved = transforms.transform_points(matrix, points)
    assert moved.dtype == np.float64 and np.allclose(moved, [[1, 4, 3], [1, 2, 5]])
