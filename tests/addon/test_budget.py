"""The selection's budget (plan/budget.py) and how a task spends its share (BakeTask.refines,
refine_budget): exact arithmetic, no sdnative."""

import os

import numpy as np
import pytest

from sd_lighting import methods
from sd_lighting.bake import lightmap, refine
from sd_lighting.bake.task import BakeTask
from sd_lighting.plan import analysis, bake_time, budget, cost

SQUARE = (np.array([[0, 0, 0], [2, 0, 0], [2, 3, 0], [0, 3, 0]], dtype=float), np.array([[0, 1, 2], [0, 2, 3]]))


def test_surface_area_of_a_rectangle_and_of_nothing():
    assert budget.surface_area(*SQUARE) == pytest.approx(6.0)
    assert budget.surface_area(SQUARE[0], np.zeros((0, 3), int)) == 0.0
    assert budget.surface_area(*SQUARE, block=1) == pytest.approx(6.0)   # summed over blocks


def test_the_selection_seconds_grow_with_its_points_between_the_floor_and_the_cap():
    per_point = budget.SECONDS_PER_POINT
    assert budget.selection_seconds(0) == budget.MIN_SELECTION_SECONDS
    between = 1.5 * budget.MIN_SELECTION_SECONDS / per_point   # 2 x that is still under the cap
    assert 3.0 * budget.MIN_SELECTION_SECONDS < budget.SELECTION_SECONDS
    assert budget.selection_seconds(between) == pytest.approx(per_point * between)
    assert budget.selection_seconds(2 * between) == pytest.approx(2 * per_point * between)
    assert budget.selection_seconds(10 ** 9) == budget.SELECTION_SECONDS
    # issue 30: a sub-1k-vertex model (assimp's spider: 762 mesh vertices) gets a few seconds, a CAD
    # model of tens of thousands the whole budget
    assert budget.selection_seconds(762) < 0.2 * budget.SELECTION_SECONDS
    assert budget.selection_seconds(20_000) == budget.SELECTION_SECONDS


def test_shares_follow_the_areas_and_sum_to_one():
    shares = budget.shares([1.0, 3.0, 0.0])
    assert shares == pytest.approx([0.25, 0.75, 0.0])
    assert budget.shares([0.0, 0.0]) == pytest.approx([0.5, 0.5])   # nothing to weigh: equal


@pytest.mark.parametrize("method_id, s, sv", [("prt_diffuse", 6, 0), ("prt_matrix", 4, 2), ("msd_lobe", 4, 2)])
def test_affordable_vertices_is_the_bake_time_model_inverted(method_id, s, sv):
    method = methods.get(method_id)
    for rays, points in ((256, 1.0), (1024, 3.0)):
        n = budget.affordable_vertices(10.0, method, s, sv, rays, 2, points)
        assert points * cost.bake_seconds(method, s, sv, rays, n, 2) <= 10.0
        assert points * cost.bake_seconds(method, s, sv, rays, n + 1, 2) > 10.0
    assert budget.affordable_vertices(10.0, method, s, sv, 4096, 2, 1.0) < \
        budget.affordable_vertices(10.0, method, s, sv, 256, 2, 1.0)
    # a refined copy's tests: TESTED_POINTS_PER_VERTEX points a vertex at their own rays
    test = (methods.get("prt_diffuse"), 6, 256)

    def seconds(vertices):
        return (3.0 * cost.bake_seconds(method, s, sv, 1024, vertices, 2) +
                budget.TESTED_POINTS_PER_VERTEX * cost.bake_seconds(test[0], 6, 0, 256, vertices, 2))
    n = budget.affordable_vertices(10.0, method, s, sv, 1024, 2, 3.0, test)
    assert seconds(n) <= 10.0 < seconds(n + 1)
    assert n < budget.affordable_vertices(10.0, method, s, sv, 1024, 2, 3.0)


class _Mesh:
    """A geometry.Geometry as far as the budget reads it: the mesh's own vertices."""
    mesh_positions = np.zeros((500, 3))


def task(**settings):
    defaults = dict(method="prt_diffuse", light_order=6, visibility_order=0, rays=1024, refine=True,
                    refine_max_vertices=250_000, least_squares=True, lightmap=0, bake_seconds_budget=2.0)
    return BakeTask("part", _Mesh(), (None, None), dict(defaults, **settings), None)


def test_the_budget_counts_the_mesh_vertices_and_the_texels_asked_for():
    assert task().budget_points() == 500
    assert task(lightmap=512).budget_points() == 500 + lightmap.expected_texels(512)
    assert lightmap.expected_texels(512) > 0


@pytest.mark.parametrize("method_id, rays", [("prt_diffuse", 1024), ("prt_diffuse", 128), ("msd_visibility", 512)])
def test_a_chosen_task_refines_no_further_than_its_seconds_afford(method_id, rays):
    # its tests too: a Lambert transfer at up to CRITERION_RAYS, whatever the method
    test = (methods.get("prt_diffuse"), refine.CRITERION_ORDER, min(rays, refine.CRITERION_RAYS))
    fitted = 3.0 if method_id == "prt_diffuse" else 1.0   # least squares fits no design
    affordable = budget.affordable_vertices(2.0, methods.get(method_id), 6, 0, rays, os.cpu_count() or 1, fitted,
                                            test)
    assert affordable < 250_000
    assert task(method=method_id, rays=rays).refine_budget() == affordable


def test_a_task_refines_no_further_than_max_verts_and_fewer_rays_afford_more():
    assert task(bake_seconds_budget=1e6).refine_budget() == 250_000      # Max Verts' share binds
    assert task(rays=256).refine_budget() > task().refine_budget()       # fewer rays, more vertices


def test_an_unchosen_or_old_task_has_its_max_verts_share_and_the_confirmation_seconds():
    assert task(method=analysis.AUTOMATIC).refine_budget() == 250_000
    old = task(bake_seconds_budget=None)
    assert old.refine_budget() == 250_000
    assert old.bake_seconds_budget == bake_time.CONFIRM_SECONDS


def test_a_method_without_visibility_is_not_refined():
    assert task().refines
    assert not task(method="unshadowed").refines
    assert task(method=analysis.AUTOMATIC).refines   # unknown until the choice
    assert not task(refine=False).refines
