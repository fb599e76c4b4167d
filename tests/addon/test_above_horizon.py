"""Which bakes trace only the rays above each vertex's horizon (bake/task.above_horizon): those that
ask for T alone, never one that needs V~, M or designs."""

from sd_lighting import methods
from sd_lighting.bake.task import above_horizon


def test_a_bake_of_the_transfer_alone_traces_above_the_horizon():
    assert above_horizon({"rays": 64, "transfer_order": 6})["horizon"] is True


def test_a_bake_that_needs_the_whole_sphere_traces_every_ray():
    for extra in ({"visibility_order": 2}, {"product_orders": (4, 2)}, {"design_orders": (4, 2)}):
        assert above_horizon(dict(rays=64, transfer_order=0, **extra))["horizon"] is False
    assert above_horizon({"rays": 64})["horizon"] is False   # ambient occlusion alone


def test_only_prt_diffuse_of_the_methods_bakes_above_the_horizon():
    chosen = [m.id for m in methods.METHODS if above_horizon(m.bake_arguments(4, 2))["horizon"]]
    assert chosen == ["prt_diffuse"]
