"""bake/sides.py: polygons turned and doubled as sdnative.face_sides says."""

import numpy as np

from sd_lighting.bake import sides

# a quad (loops 0-3) and a triangle (loops 4-6), triangulated as the bake winds them
STARTS, TOTALS = np.array([0, 4]), np.array([4, 3])
TRIANGLE_LOOPS = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6]])


def test_polygon_codes_take_the_largest_of_their_triangles():
    codes = sides.polygon_codes([sides.FRONT, sides.BOTH, sides.FLIPPED], TRIANGLE_LOOPS, STARTS, TOTALS)
    assert codes.tolist() == [sides.BOTH, sides.FLIPPED]


def test_front_faces_are_kept_as_they_are():
    sided = sides.apply([sides.FRONT, sides.FRONT], STARTS, TOTALS, TRIANGLE_LOOPS)
    assert sided.loop_order.tolist() == list(range(7))
    assert not sided.negated.any()
    assert sided.triangle_loops.tolist() == TRIANGLE_LOOPS.tolist()
    assert sided.loop_sides.tolist() == [sides.SINGLE] * 7
    assert (sided.flipped, sided.doubled) == (0, 0)


def test_a_flipped_polygon_is_wound_the_other_way_with_its_normals_negated():
    sided = sides.apply([sides.FLIPPED, sides.FRONT], STARTS, TOTALS, TRIANGLE_LOOPS)
    assert sided.loop_order.tolist() == [0, 3, 2, 1, 4, 5, 6]
    assert sided.negated.tolist() == [True] * 4 + [False] * 3
    vertices = np.array([10, 11, 12, 13, 14, 15, 16])   # each loop's vertex
    turned = sided.gather(vertices)[sided.triangle_loops]
    assert turned.tolist() == [[12, 11, 10], [13, 12, 10], [14, 15, 16]]
    assert sided.loop_sides.tolist() == [sides.SINGLE] * 7
    assert sided.flipped == 1


def test_a_polygon_seen_from_both_sides_gets_a_reverse_copy():
    sided = sides.apply([sides.FRONT, sides.BOTH], STARTS, TOTALS, TRIANGLE_LOOPS)
    assert sided.loop_starts.tolist() == [0, 4, 7]
    assert sided.loop_totals.tolist() == [4, 3, 3]
    assert sided.loop_order.tolist() == [0, 1, 2, 3, 4, 5, 6, 4, 6, 5]
    assert sided.negated.tolist() == [False] * 7 + [True] * 3
    vertices = np.arange(10, 17)
    corners = sided.gather(vertices)[sided.triangle_loops]
    assert corners.tolist() == [[10, 11, 12], [10, 12, 13], [14, 15, 16], [16, 15, 14]]
    assert sided.loop_sides.tolist() == [sides.SINGLE] * 4 + [sides.FRONT_SIDE] * 3 + [sides.BACK_SIDE] * 3
    assert sided.doubled == 1
    normals = np.tile([[0.0, 0.0, 1.0]], (7, 1))
    assert sided.normals(normals)[:, 2].tolist() == [1.0] * 7 + [-1.0] * 3


def test_a_sheet_is_drawn_from_its_own_side_without_a_copy():
    sided = sides.apply([sides.SHEET, sides.FRONT], STARTS, TOTALS, TRIANGLE_LOOPS)
    assert len(sided.loop_order) == 7
    assert sided.loop_sides.tolist() == [sides.FRONT_SIDE] * 4 + [sides.SINGLE] * 3


def test_codes_match_the_native_module(sdnative):
    assert (sides.FRONT, sides.FLIPPED, sides.BOTH, sides.SHEET) == (
        sdnative.FACE_FRONT, sdnative.FACE_FLIPPED, sdnative.FACE_BOTH, sdnative.FACE_SHEET)
