"""The settings' upper limits from sdnative's constants."""

from types import SimpleNamespace

from sd_lighting.ui import limits


def test_limits_of_the_built_module(sdnative):
    got = limits.from_module(sdnative)
    assert got == limits.Limits(light_order=16, visibility_order=8, rays=65536,
                                phong_exponent=1e4)


def test_the_smallest_limit_wins():
    module = SimpleNamespace(MAX_VISIBILITY_ORDER=8, MAX_SHADING_ORDER=16, MAX_TRANSFER_ORDER=12,
                             MAX_PROJECTION_ORDER=16, MAX_DESIGN_DEGREE=30,
                             MAX_RAYS_PER_VERTEX=1000, MAX_PHONG_EXPONENT=50.0)
    assert limits.from_module(module).light_order == 12
    module.MAX_DESIGN_DEGREE = 18    # s + s' must stay a valid design degree
    assert limits.from_module(module).light_order == 10


def test_without_sdnative_there_are_no_limits():
    assert limits.from_module(None) == limits.Limits()
    assert limits.maximum(None) == {} and limits.maximum(8) == {"max": 8}
