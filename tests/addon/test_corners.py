"""Corner data: which face corners share a vertex of the baked copy (bake/corners.py)."""

import numpy as np

from sd_lighting.bake import corners


def _cube():
    """A unit cube's 6 quads as loops: 24 loops over 8 vertices, each corner with its face normal."""
    faces = [((0, 1, 3, 2), (-1, 0, 0)), ((4, 6, 7, 5), (1, 0, 0)), ((0, 4, 5, 1), (0, -1, 0)),
             ((2, 3, 7, 6), (0, 1, 0)), ((0, 2, 6, 4), (0, 0, -1)), ((1, 5, 7, 3), (0, 0, 1))]
    loop_vertices = np.array([v for quad, _ in faces for v in quad])
    normals = np.array([n for _, n in faces for _ in range(4)], dtype=float)
    return loop_vertices, normals


def test_a_smooth_mesh_keeps_its_vertices_in_order():
    loop_vertices = np.array([0, 1, 2, 2, 1, 3, 3, 1, 4])
    normal_of_vertex = np.random.default_rng(1).normal(size=(5, 3))
    normal_of_vertex /= np.linalg.norm(normal_of_vertex, axis=1)[:, None]
    split = corners.split(loop_vertices, normal_of_vertex[loop_vertices])
    assert split.count == 5
    assert np.array_equal(split.origin, np.arange(5))
    assert np.array_equal(split.loop_vertex, loop_vertices)
    sums = split.normal_sums / np.linalg.norm(split.normal_sums, axis=1)[:, None]
    assert np.allclose(sums, normal_of_vertex)


def test_a_flat_cube_splits_every_corner_by_its_face_normal():
    loop_vertices, normals = _cube()
    split = corners.split(loop_vertices, normals)
    assert split.count == 24
    assert np.array_equal(np.bincount(split.origin), [3] * 8)
    assert np.array_equal(split.origin[split.loop_vertex], loop_vertices)
    assert np.allclose(split.normal_sums[split.loop_vertex], normals)


def test_normals_within_the_tolerance_share_a_vertex_and_wider_ones_split():
    angle = np.radians(corners.NORMAL_TOLERANCE_DEGREES)
    near = [np.sin(angle / 8), 0.0, np.cos(angle / 8)]
    far = [np.sin(4 * angle), 0.0, np.cos(4 * angle)]
    assert corners.split([0, 0], [[0, 0, 1], near]).count == 1
    assert corners.split([0, 0], [[0, 0, 1], far]).count == 2


def test_material_slots_and_uv_seams_split_and_are_kept_per_vertex():
    loop_vertices = np.array([0, 1, 2, 0, 2, 3])
    normals = np.tile([0.0, 0.0, 1.0], (6, 1))
    slots = np.array([0, 0, 0, 1, 1, 1])
    split = corners.split(loop_vertices, normals, loop_materials=slots)
    assert split.count == 6      # vertices 0 and 2 lie on both faces
    assert np.array_equal(corners.vertex_values(split, slots)[split.loop_vertex], slots)
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0.5, 0], [1, 1], [0, 1]], dtype=np.float32)
    split = corners.split(loop_vertices, normals, loop_uvs=uvs)
    assert split.count == 5      # a seam at vertex 0 only
    assert np.array_equal(corners.vertex_values(split, uvs)[split.loop_vertex], uvs)


def test_the_split_does_not_depend_on_the_frame_or_on_rounding():
    # A mirrored object is baked in a frame turned against its applied-scale twin, and the same
    # normals computed twice differ in the last bits: both must split alike, in the same order.
    loop_vertices, normals = _cube()
    rng = np.random.default_rng(7)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    base = corners.split(loop_vertices, normals)
    for other in (normals @ q.T, normals + rng.normal(scale=1e-7, size=normals.shape)):
        split = corners.split(loop_vertices, other)
        assert np.array_equal(split.loop_vertex, base.loop_vertex)
        assert np.array_equal(split.origin, base.origin)


def test_corners_without_a_normal_share_one_copy_apart_from_the_others():
    # Blender's corner normals of a smooth vertex whose faces cancel are zero: the copy keeps a
    # zero normal, which the native bake replaces by its faces' normal.
    split = corners.split([0, 0, 0, 0], [[0, 0, 0], [0, 0, 1], [0, 0, 0], [0, 0, 1]])
    assert split.count == 2 and np.array_equal(split.loop_vertex, [0, 1, 0, 1])
    assert np.array_equal(split.normal_sums[0], [0, 0, 0])


def test_a_mesh_without_loops_has_no_vertices():
    split = corners.split(np.zeros(0, dtype=int), np.zeros((0, 3)))
    assert split.count == 0 and split.loop_vertex.size == 0
