"""Per-vertex bake data: vec4 grouping round trips, designs at their own length in the data
texture, names, bake requests."""

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


def test_design_texels_are_headers_then_the_nodes_at_their_own_length():
    counts = [3, 0, 5, 1]
    offsets, nodes, weights = designs(counts)
    texels, stride = DESIGN.texels(dict(zip(DESIGN.keys, (offsets, nodes, weights))))
    assert stride == 1 and texels.shape == (4 + 9, 4) and texels.dtype == np.float32
    assert texels[:4, 2].tolist() == counts and not texels[:4, 3].any()
    first = texels[:4, 1] * bake_data.TEXTURE_WIDTH + texels[:4, 0]
    assert first.tolist() == (4 + offsets[:-1]).tolist()
    assert np.allclose(texels[4:, :3], nodes, atol=1e-7) and np.allclose(texels[4:, 3], weights, atol=1e-7)


def test_design_headers_split_a_first_node_beyond_float_precision():
    """A node index above 2^24 would round as one float: column and row stay exact."""
    first = (1 << 24) + 3
    header = bake_data.design_headers([first, first + 2])    # one vertex after `first` nodes
    assert int(header[0, 1]) * bake_data.TEXTURE_WIDTH + int(header[0, 0]) == 1 + first
    assert header[0, 2] == 2


def test_weighted_nodes_give_back_nodes_and_weights_to_float32_rounding():
    """A node is stored as lambda x (12 bytes): weights over 40 decades keep their direction."""
    offsets, nodes, weights = designs([6, 2])
    weights = weights * 10.0 ** np.linspace(-20, 20, len(weights))
    points = bake_data.weighted_nodes(nodes, weights)
    assert points.dtype == np.float32 and points.shape == nodes.shape
    back_nodes, back_weights = bake_data.split_weighted_nodes(points)
    assert np.allclose(back_nodes, nodes, rtol=0, atol=3e-7)
    assert np.allclose(back_weights, weights, rtol=3e-7, atol=0)


def test_no_nodes_at_all_still_gives_each_vertex_its_header():
    texels, stride = DESIGN.texels(dict(zip(DESIGN.keys, ([0, 0, 0], np.zeros((0, 3)), np.zeros(0)))))
    assert stride == 1 and texels.shape == (2, 4) and not texels[:, 2:].any()


@pytest.mark.parametrize("array", [VISIBILITY, TRANSFER, PRODUCT_MATRIX])
def test_coefficient_arrays_round_trip_through_groups(array):
    s, sv, n = 3, 2, 7
    shape = array.shape(s, sv)
    values = np.random.default_rng(1).normal(size=(n,) + shape)
    groups = array.groups({array.keys[0]: values})
    assert groups.shape == (n, array.stride(s, sv), 4) and array.stride(s, sv) == (int(np.prod(shape)) + 3) // 4
    back = array.from_groups(groups, s, sv)[array.keys[0]]
    assert back.shape == values.shape and back.dtype == np.float64
    assert np.array_equal(back, values.astype(np.float32))
    texels, stride = array.texels({array.keys[0]: values})
    assert stride == array.stride(s, sv) and np.array_equal(texels, groups.reshape(-1, 4))


def test_product_matrix_is_row_major():
    matrix = np.arange(16, dtype=np.float64).reshape(1, 4, 4)
    groups = PRODUCT_MATRIX.groups({"product_matrices": matrix})
    assert groups[0, 1].tolist() == [4, 5, 6, 7]   # row 1 of M


def test_ambient_occlusion_is_one_texel_and_a_float():
    ao = np.array([0.25, 1.0])
    groups = AMBIENT_OCCLUSION.groups({"ambient_occlusion": ao})
    assert groups.tolist() == [[[0.25, 0, 0, 0]], [[1.0, 0, 0, 0]]]
    assert not AMBIENT_OCCLUSION.grouped and AMBIENT_OCCLUSION.attribute == "sd_ambient_occlusion"
    assert AMBIENT_OCCLUSION.stride(4, 2) == 1
    assert AMBIENT_OCCLUSION.from_groups(groups, 4, 2)["ambient_occlusion"].tolist() == [0.25, 1.0]


def test_stored_names_are_the_file_format():
    """README's table: renaming any of these breaks saved bakes."""
    assert bake_data.NORMAL == "sd_normal" and bake_data.BAKE == "sd_bake"
    assert bake_data.BAKED_MESH == "sd_baked_mesh"
    assert [a.group_name(10) for a in ARRAYS if a.grouped] == [
        "sd_visibility_010", "sd_transfer_010", "sd_product_matrix_010"]
    assert (bake_data.DESIGN_COUNT, bake_data.DESIGN_NODES, bake_data.DESIGN_TOTAL) == (
        "sd_design_count", "sd_design_nodes", "sd_design_total")


def test_bake_requests():
    assert VISIBILITY.bake_arguments(4, 2) == {"visibility_order": 2}
    assert TRANSFER.bake_arguments(4, 2) == {"transfer_order": 4}
    assert PRODUCT_MATRIX.bake_arguments(4, 2) == {"product_orders": (4, 2)}
    assert DESIGN.bake_arguments(4, 2) == {"design_orders": (4, 2)}
    assert AMBIENT_OCCLUSION.bake_arguments(4, 2) == {}
