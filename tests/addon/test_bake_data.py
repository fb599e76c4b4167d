"""Per-vertex bake data: vec4 grouping and design padding round trips, names, bake requests."""

import numpy as np
import pytest

from sd_lighting.store import bake_data
from sd_lighting.store.bake_data import (AMBIENT_OCCLUSION, ARRAYS, DESIGN, PRODUCT_MATRIX,
                                         TRANSFER, VISIBILITY)


def test_vec4_groups_pad_the_last_group_with_zeros():
    values = np.arange(2 * 9, dtype=np.float64).reshape(2, 9)
    groups = bake_data.vec4_groups(values)
    assert groups.shape == (2, 3, 4) and groups.dtype == np.float32
    assert groups[1, 0].tolist() == [9, 10, 11, 12]
    assert groups[1, 2].tolist() == [17, 0, 0, 0]


def designs(counts, seed=0):
    rng = np.random.default_rng(seed)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    nodes = rng.normal(size=(offsets[-1], 3))
    nodes /= np.linalg.norm(nodes, axis=1)[:, None]
    weights = rng.uniform(0.01, 1.0, size=offsets[-1])
    return offsets, nodes, weights


def test_design_padding_round_trip():
    counts = [3, 0, 5, 1]
    offsets, nodes, weights = designs(counts)
    padded = bake_data.padded_designs(offsets, nodes, weights)
    assert padded.shape == (4, 5, 4)
    assert (padded[1] == 0).all() and (padded[0, 3:] == 0).all()
    assert np.allclose(padded[2, :, :3], nodes[3:8], atol=1e-7)
    back_offsets, back_nodes, back_weights = bake_data.unpadded_designs(padded)
    assert back_offsets.tolist() == offsets.tolist()
    assert np.allclose(back_nodes, nodes, atol=1e-7) and np.allclose(back_weights, weights, atol=1e-7)


def test_no_nodes_at_all_still_gives_one_texel():
    padded = bake_data.padded_designs([0, 0, 0], np.zeros((0, 3)), np.zeros(0))
    assert padded.shape == (2, 1, 4) and not padded.any()


@pytest.mark.parametrize("array", [VISIBILITY, TRANSFER, PRODUCT_MATRIX])
def test_coefficient_arrays_round_trip_through_texels(array):
    s, sv, n = 3, 2, 7
    shape = array.shape(s, sv)
    values = np.random.default_rng(1).normal(size=(n,) + shape)
    texels = array.texels({array.keys[0]: values})
    assert texels.shape == (n, (int(np.prod(shape)) + 3) // 4, 4)
    back = array.from_texels(texels, s, sv)[array.keys[0]]
    assert back.shape == values.shape and back.dtype == np.float64
    assert np.array_equal(back, values.astype(np.float32))


def test_product_matrix_is_row_major():
    s, sv = 1, 1
    matrix = np.arange(16, dtype=np.float64).reshape(1, 4, 4)
    texels = PRODUCT_MATRIX.texels({"product_matrices": matrix})
    assert texels[0, 1].tolist() == [4, 5, 6, 7]   # row 1 of M


def test_ambient_occlusion_is_one_texel_and_a_float():
    ao = np.array([0.25, 1.0])
    texels = AMBIENT_OCCLUSION.texels({"ambient_occlusion": ao})
    assert texels.tolist() == [[[0.25, 0, 0, 0]], [[1.0, 0, 0, 0]]]
    assert not AMBIENT_OCCLUSION.grouped and AMBIENT_OCCLUSION.attribute == "sd_ambient_occlusion"
    assert AMBIENT_OCCLUSION.from_texels(texels, 4, 2)["ambient_occlusion"].tolist() == [0.25, 1.0]


def test_design_round_trip_through_texels():
    offsets, nodes, weights = designs([2, 4, 1], seed=2)
    result = dict(zip(DESIGN.keys, (offsets, nodes, weights)))
    back = DESIGN.from_texels(DESIGN.texels(result), 4, 2)
    assert back["design_offsets"].tolist() == offsets.tolist()
    assert np.allclose(back["design_nodes"], nodes, atol=1e-7)


def test_stored_names_are_the_file_format():
    """README's table: renaming any of these breaks saved bakes."""
    assert bake_data.NORMAL == "sd_normal" and bake_data.BAKE == "sd_bake"
    assert bake_data.BAKED_MESH == "sd_baked_mesh"
    assert [a.group_name(10) for a in ARRAYS if a.grouped] == [
        "sd_visibility_010", "sd_transfer_010", "sd_product_matrix_010", "sd_design_010"]


def test_bake_requests():
    assert VISIBILITY.bake_arguments(4, 2) == {"visibility_order": 2}
    assert TRANSFER.bake_arguments(4, 2) == {"transfer_order": 4}
    assert PRODUCT_MATRIX.bake_arguments(4, 2) == {"product_orders": (4, 2)}
    assert DESIGN.bake_arguments(4, 2) == {"design_orders": (4, 2)}
    assert AMBIENT_OCCLUSION.bake_arguments(4, 2) == {}
