"""Texture-space data (bake/lightmap.py): texel centres in UV triangles, their points on the
surface, and the dilation around the charts."""

import numpy as np
import pytest

from sd_lighting import methods
from sd_lighting.bake import lightmap

SQUARE = np.array([[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]])


def test_two_triangles_over_the_square_cover_every_texel_once():
    entries, triangles, barycentric = lightmap.texels(SQUARE, 8, 4)
    assert entries.tolist() == list(range(32))
    corners = SQUARE[triangles]
    uv = (corners * barycentric[:, :, None]).sum(axis=1)
    x, y = entries % 8, entries // 8
    np.testing.assert_allclose(uv, np.stack([(x + 0.5) / 8, (y + 0.5) / 4], axis=1), atol=1e-12)
    assert np.all(barycentric >= -1e-12) and np.allclose(barycentric.sum(axis=1), 1.0)
    # below the diagonal the first triangle, above it the second
    assert np.all(triangles[x > y * 2 + 1] == 0) and np.all(triangles[x < y * 2] == 1)


def test_a_triangle_holds_about_its_area_in_texels():
    rng = np.random.default_rng(1)
    corners = rng.random((200, 3, 2))
    for triangle in corners:
        area = 0.5 * abs(np.cross(triangle[1] - triangle[0], triangle[2] - triangle[0]))
        entries, _, _ = lightmap.texels(triangle[None], 256, 256)
        assert abs(len(entries) - area * 256 * 256) <= 3 * 256 * 2 + 3


def test_a_triangle_smaller_than_a_texel_gives_its_centroid_to_the_texel_under_it():
    tiny = np.array([[[0.30, 0.30], [0.31, 0.30], [0.30, 0.31]]])
    entries, triangles, barycentric = lightmap.texels(np.concatenate([SQUARE * 0.1, tiny]), 10, 10)
    assert 3 * 10 + 3 in entries
    k = entries.tolist().index(33)
    assert triangles[k] == 2 and np.allclose(barycentric[k], 1.0 / 3.0)
    # the first texel of the square's corner stays the square's
    assert entries[0] == 0 and triangles[0] in (0, 1)


def test_the_chunks_give_what_one_pass_gives(monkeypatch):
    rng = np.random.default_rng(2)
    corners = rng.random((50, 3, 2))
    whole = lightmap.texels(corners, 64, 64)
    monkeypatch.setattr(lightmap, "_CHUNK", 97)
    chunked = lightmap.texels(corners, 64, 64)
    for a, b in zip(whole, chunked):
        np.testing.assert_array_equal(a, b)


def test_degenerate_and_outside_triangles_hold_no_texel_centre():
    flat = np.array([[[0.1, 0.1], [0.5, 0.5], [0.9, 0.9]]])
    entries, triangles, _ = lightmap.texels(flat, 16, 16)
    assert len(entries) == 1 and triangles[0] == 0   # its centroid's texel only
    outside = np.array([[[1.5, 1.5], [2.0, 1.5], [1.5, 2.0]]])
    entries, _, _ = lightmap.texels(outside, 16, 16)
    assert entries.tolist() == [15 * 16 + 15]          # clamped into the map, as the GPU would


def test_sample_points_blend_corners_and_fall_back_to_the_face_normal():
    vertices = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    normals = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    points, unit = lightmap.sample_points(vertices, normals, np.array([[0, 1, 2]]), np.array([0, 0]),
                                          np.array([[0.5, 0.5, 0.0], [0.5, 0.0, 0.5]]))
    np.testing.assert_allclose(points, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    np.testing.assert_allclose(unit[0], np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0))
    np.testing.assert_allclose(unit[1], [0.0, 0.0, 1.0])   # +z and -z cancel: the winding's normal
    # other per-vertex values (the local space's positions) blend the same way
    np.testing.assert_allclose(lightmap.blend(vertices + 1.0, np.array([[0, 1, 2]]), np.array([0, 0]),
                                              np.array([[0.5, 0.5, 0.0], [0.5, 0.0, 0.5]])), points + 1.0)


def test_dilation_takes_the_nearest_baked_texel_within_the_radius():
    sources = lightmap.dilation_sources(np.array([2 * 8 + 2]), 8, 6, radius=2)
    grid = sources.reshape(6, 8)
    assert np.all(grid[0:5, 0:5] == 18)
    assert np.all(grid[:, 5:] == -1) and np.all(grid[5, :] == -1)
    two = lightmap.dilation_sources(np.array([0, 7]), 8, 1, radius=3)
    assert two.tolist() == [0, 0, 0, 0, 7, 7, 7, 7]


def test_spread_gives_the_stored_texels_their_sources_values():
    entries = np.array([1, 5])
    sources = np.array([1, 1, -1, 5, 5, 5])
    assert lightmap.stored(sources).tolist() == [0, 1, 3, 4, 5]
    out = lightmap.spread(np.array([[1.0, 2.0], [3.0, 4.0]]), entries, sources)
    np.testing.assert_array_equal(out, [[1, 2], [1, 2], [3, 4], [3, 4], [3, 4]])
    index = lightmap.index_map(lightmap.stored(sources), 3, 2)
    np.testing.assert_array_equal(index, [[0, 1, -1], [2, 3, 4]])


def test_a_triangle_larger_than_a_chunk_is_rasterized_in_pieces(monkeypatch):
    whole = lightmap.texels(SQUARE, 32, 32)
    monkeypatch.setattr(lightmap, "_CHUNK", 50)
    for a, b in zip(whole, lightmap.texels(SQUARE, 32, 32)):
        np.testing.assert_array_equal(a, b)


def test_which_methods_texels_hold_and_what_their_data_take():
    held = {m.id for m in methods.METHODS if lightmap.applies(m)}
    assert held == {"ambient_occlusion", "prt_diffuse", "prt_matrix", "prt_gaunt", "msd_lobe"}
    assert lightmap.data_entries(methods.get("ambient_occlusion"), 4, 2, 1000) == 1000
    assert lightmap.data_entries(methods.get("prt_diffuse"), 2, 0, 1000) == 3 * 1000       # 9 floats
    assert lightmap.data_entries(methods.get("prt_matrix"), 2, 2, 1000) == 21 * 1000      # 81 floats
    assert lightmap.data_entries(methods.get("prt_matrix"), 2, 2, 2048 ** 2) > lightmap.MAX_DATA_TEXELS
    assert lightmap.data_entries(methods.get("prt_diffuse"), 2, 0, 4096 ** 2) <= lightmap.MAX_DATA_TEXELS
    assert lightmap.expected_texels(1000) == int(lightmap.COVERAGE * 1e6)


def test_the_add_margin_leaves_the_margin_at_the_scale_the_charts_get():
    uv = np.array([[[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]]])     # a right triangle of area 1/8 ...
    assert lightmap.uv_scale(uv, 2.0) == pytest.approx(0.25)  # ... from one of area 2
    scale = lightmap.expected_scale(1.0)
    assert scale == pytest.approx(np.sqrt(lightmap.COVERAGE))
    margin = lightmap.add_margin(1024, scale)
    assert lightmap.gap_texels(margin, scale, 1024) == pytest.approx(lightmap.MARGIN_SLACK * lightmap.MARGIN_TEXELS)
    assert lightmap.gap_texels(margin, 0.8 * scale, 1024) < lightmap.MARGIN_TEXELS   # a tighter packing: again
    assert margin < 1.0 and lightmap.add_margin(256, scale) < 1.0   # under the operator's cap at unit area


@pytest.mark.parametrize("size", lightmap.SIZES)
def test_sizes_are_powers_of_two(size):
    assert size & (size - 1) == 0 and lightmap.DEFAULT_SIZE in lightmap.SIZES
