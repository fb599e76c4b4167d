"""The panel's account of the map's bright sources (scene/light_sources.py): what sdnative's
Environment.light_sources finds, as widths, elevations and shares of the light, and the lines."""

import math

import numpy as np
import pytest

from sd_lighting.scene import light_sources


def sun_map(elevation, radius, radiance, height=128, width=256):
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = np.pi * (width - 2 * np.arange(width) - 1) / width
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    sun = np.array([math.cos(math.radians(elevation)), 0.0, math.sin(math.radians(elevation))])
    rgb = np.full((height, width, 3), 0.5, np.float32)
    rgb[d @ sun > math.cos(math.radians(radius))] = radiance
    return rgb


def test_a_sun_is_named_by_its_width_elevation_and_share(sdnative):
    env = sdnative.environment_from_pixels(sun_map(30.0, 3.0, 400.0))
    (width, elevation, share), = light_sources.found(env.light_sources(), float(env.mass[3]))
    assert width == pytest.approx(6.0, abs=1.5)          # 2 x the equivalent disc's radius
    assert elevation == pytest.approx(30.0, abs=1.0)
    # the disc's share of the light, less what stays in the map under the threshold
    disc = 400.0 * (1.0 - math.cos(math.radians(3.0))) / 2.0
    assert 0.85 * disc / (disc + 0.5) < share <= disc / (disc + 0.5)
    lines = light_sources.lines([(width, elevation, share)])
    assert lines[0].startswith("1 bright source: ") and "SH blurs their shadows" in lines[0]
    assert lines[1] == "%.1f\u00b0 wide at 30\u00b0 elevation, %.0f %%" % (width, 100 * share)


def test_a_soft_map_has_none_and_a_search_under_way_says_so(sdnative):
    env = sdnative.environment_from_pixels(np.full((64, 128, 3), 0.7, np.float32))
    assert light_sources.found(env.light_sources(), float(env.mass[3])) == []
    assert light_sources.lines([]) == ["No sun or lamp in the map: its light is soft"]
    assert light_sources.lines(None) == ["Finding the map's bright sources"]
    two = light_sources.lines([(1.0, 10.0, 0.3), (2.0, 50.0, 0.1)])
    assert two[0].startswith("2 bright sources: 40 % of the light") and len(two) == 3


def test_the_panels_search_runs_in_the_background_and_a_failure_is_said(sdnative):
    from sd_lighting import background
    from sd_lighting.scene import environment
    try:
        src = environment.Source("pixels", ("test sun",), "a sun")
        environment._cache[src.key] = sdnative.environment_from_pixels(sun_map(30.0, 3.0, 400.0))
        first = environment.bright_sources(src, wait=False)   # queued: the panel says it is searching
        assert first is None or len(first) == 1
        assert len(environment.bright_sources(src, wait=True)) == 1
        assert environment.bright_sources(environment.Source("uniform", ("grey",), "grey", colour=(0.5,) * 3),
                                          wait=False) == []

        class Broken:
            def light_sources(self):
                raise MemoryError("no room")
        broken = environment.Source("pixels", ("broken",), "broken")
        environment._cache[broken.key] = Broken()
        with pytest.raises(background.Failed, match="no room"):
            environment.bright_sources(broken, wait=True)
        with pytest.raises(background.Failed, match="finding the map's bright sources failed: .*no room"):
            environment.bright_sources(broken, wait=False)
    finally:   # (clear_cache also clears the rendered worlds, which need bpy)
        environment._cache.pop(("test sun",), None)
        environment._cache.pop(("broken",), None)
        environment._workers.pop(environment.LIGHT_SOURCES).close()
