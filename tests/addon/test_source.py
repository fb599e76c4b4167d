"""What a bake was baked from (store/source.py): the digest follows the mesh's positions and
topology, exactly, and nothing else."""

import numpy as np

from sd_lighting.store.source import digest

POSITIONS = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.5]], np.float32)
QUAD = np.array([0, 1, 2, 3], np.int32)      # one quad
TRIANGLES = np.array([0, 1, 2, 0, 2, 3], np.int32)   # the same corners as two triangles


def test_the_same_mesh_gives_the_same_digest_whatever_the_arrays_types():
    a = digest(POSITIONS, QUAD, [4])
    assert a == digest(POSITIONS.astype(np.float64), QUAD.astype(np.int64), np.array([4]))
    assert len(a) == 32


def test_a_position_one_float32_step_away_changes_it():
    moved = POSITIONS.copy()
    moved[3, 2] = np.nextafter(moved[3, 2], np.float32(1.0))
    assert digest(moved, QUAD, [4]) != digest(POSITIONS, QUAD, [4])


def test_topology_changes_it():
    assert digest(POSITIONS, TRIANGLES, [3, 3]) != digest(POSITIONS, QUAD, [4])
    assert digest(POSITIONS, QUAD[::-1].copy(), [4]) != digest(POSITIONS, QUAD, [4])   # flipped
    assert digest(POSITIONS[:3], QUAD[:3], [3]) != digest(POSITIONS, QUAD[:3], [3])    # a loose vertex gone

