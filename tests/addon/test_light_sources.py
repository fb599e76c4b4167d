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
            def light_sources(self, *args):
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


def test_sources_and_the_remainder_light_a_surface_as_the_whole_map_does(sdnative):
    """Source.irradiance (the Lambert lobe's B of a source facing the surface) plus the
    remainder's B through SH gives the whole map's B, unshadowed, at every normal: the split
    conserves the light the shading adds back."""
    env = sdnative.environment_from_pixels(sun_map(30.0, 2.0, 2000.0))
    split = env.light_sources(light_sources.SPLIT_ORDER)
    sources = [light_sources.Source.from_split(s) for s in split["sources"]]
    assert len(sources) == 1
    order = 16   # Lambert's truncation error there is far below the sun's share
    factors = np.asarray(sdnative.zonal_coefficients("lambert", 1.0, order))
    per_coefficient = np.concatenate([[factors[l]] * (2 * l + 1) for l in range(order + 1)])
    rng = np.random.default_rng(3)
    normals = rng.normal(size=(200, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    basis = np.asarray(sdnative.sh_basis(order, normals))

    def lambert(e):
        return basis @ (per_coefficient[:, None] * np.asarray(e.sh(order)).reshape(-1, 3))

    strength = 2.5
    directions, irradiance = light_sources.shading_rows(sources, np.eye(3), strength)
    added = np.maximum(normals @ directions[0, :3], 0.0)[:, None] * irradiance[0, :3]   # a 2-degree sun: n . l
    whole = strength * lambert(env)
    assert np.abs(strength * lambert(split["remainder"]) + added - whole).max() < 0.02 * np.abs(whole).max()
    assert added.max() > 0.5 * whole.max()   # the sun is most of it


def test_shadow_rows_place_the_casters_sphere_on_the_map_seen_from_the_turned_source():
    g = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # the world turned 90 degrees about z
    source = light_sources.Source((0.6, 0.0, 0.8), (0.0, 1.0, 0.0), 0.02, 0.01, (1.0, 1.0, 1.0))
    centre, radius, size = np.array([1.0, 2.0, 0.5]), 3.0, 1024
    rows, (projection,) = light_sources.shadow_rows([source], g, centre, radius, size)
    d = g.T @ np.array(source.direction)          # towards the source, in the world
    u, v, t, extent, sizes = rows

    def at(p):
        q = np.append(p, 1.0)
        return q @ u, q @ v, q @ t

    assert at(centre) == pytest.approx((0.5, 0.5, 0.0))
    assert at(centre + radius * d) == pytest.approx((0.5, 0.5, radius))      # nearest the source
    side = np.cross(d, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    uu, vv, tt = at(centre + radius * side)       # the sphere's rim, across the map
    assert math.hypot(uu - 0.5, vv - 0.5) == pytest.approx(0.5) and tt == pytest.approx(0.0)
    # the caster pass's clip space agrees: x, y = 2 (u, v) - 1; z falls towards the source, inside [-1, 1]
    for p in (centre, centre + radius * d, centre - radius * d, centre + radius * side):
        clip = projection @ np.append(p, 1.0)
        uu, vv, tt = at(p)
        assert clip[:2] == pytest.approx([2 * uu - 1, 2 * vv - 1]) and clip[3] == 1.0
        assert clip[2] == pytest.approx(-tt / (radius * 1.001)) and abs(clip[2]) < 1.0
    # the major axis (turned with the world) on the map, unit, and the semi-axes' tangents per span
    major = g.T @ np.array(source.major_axis)
    assert extent[:2] == pytest.approx([major @ (u[:3] * 2 * radius), major @ (v[:3] * 2 * radius)])
    assert np.hypot(*extent[:2]) == pytest.approx(1.0)
    assert extent[2:] == pytest.approx([math.tan(0.02) / (2 * radius), math.tan(0.01) / (2 * radius)])
    assert sizes[:3] == pytest.approx([2 * radius / size, radius, 2 * radius])


def test_shading_rows_turn_each_source_into_the_objects_bake_space():
    source = light_sources.Source((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), 0.01, 0.01, (0.1, 0.2, 0.3))
    gr = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])   # 90 degrees about x
    directions, irradiance = light_sources.shading_rows([source, source], gr, 2.0)
    assert directions[:, :3] == pytest.approx(np.tile(gr.T @ [0.0, 0.0, 1.0], (2, 1)))
    assert directions[:, 3] == pytest.approx(math.sin(0.01) ** 2)   # sin^2 of the disc's radius
    assert irradiance[0] == pytest.approx([0.8, 1.6, 2.4, 1.0])   # 4 x strength x power; a highlight


def test_rows_from_an_origin_place_points_given_relative_to_it_as_the_world_rows_place_them():
    source = light_sources.Source((0.0, 0.6, 0.8), (1.0, 0.0, 0.0), 0.01, 0.01, (1.0, 1.0, 1.0))
    origin = np.array([1.0e6, -2.0e5, 30.0])   # far from the world's origin, where float32 would round
    rows, _ = light_sources.shadow_rows([source, source], np.eye(3), origin + [0.0, 0.0, 1.0], 4.0)
    relative = light_sources.rows_from(rows, origin)
    p = np.array([0.5, -1.25, 2.0])
    for k in (0, 1, 2, 5, 6, 7):
        assert relative[k] @ np.append(p, 1.0) == pytest.approx(rows[k] @ np.append(origin + p, 1.0), abs=1e-9)
    assert np.array_equal(relative[[3, 4, 8, 9]], rows[[3, 4, 8, 9]])   # the extent and sizes stay
    assert np.abs(relative[:3, 3]).max() < 10.0   # small constants: float32 keeps the pixel's place


def test_a_sun_is_a_highlight_and_a_softbox_stays_in_the_atlas(sdnative):
    """Source.highlight: a sun (1.2 degrees wide) is shaded on its own, a softbox (16 degrees) is not;
    without_highlights takes the sun's texels from the remainder and keeps the softbox's, and
    nothing else changes. The sun lies off the x-z plane, so a mirrored azimuth would miss it."""
    height, width = 256, 512
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = np.pi * (width - 2 * np.arange(width) - 1) / width
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    elevation, azimuth = math.radians(30.0), math.radians(50.0)
    sun = np.array([math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                    math.sin(elevation)])
    box = np.array([-math.cos(math.radians(20.0)), 0.0, math.sin(math.radians(20.0))])
    rgb = np.full((height, width, 3), 0.5, np.float32)
    rgb[d @ sun > math.cos(math.radians(0.6))] = 5000.0
    rgb[d @ box > math.cos(math.radians(8.0))] = 40.0
    env = sdnative.environment_from_pixels(rgb)
    split = env.light_sources(light_sources.SPLIT_ORDER)
    sources = sorted((light_sources.Source.from_split(s) for s in split["sources"]), key=lambda s: s.major_radius)
    assert len(sources) == 2
    found_sun, softbox = sources
    assert found_sun.highlight and not softbox.highlight
    assert np.asarray(found_sun.direction) @ sun > math.cos(math.radians(1.0))
    whole, remainder = np.asarray(env.pixels()), np.asarray(split["remainder"].pixels())
    shown = light_sources.without_highlights(whole, remainder, sources)
    near_sun = d @ sun > math.cos(math.radians(3.0))
    assert np.array_equal(shown[near_sun], remainder[near_sun])
    assert shown[near_sun].max() < 0.01 * whole[near_sun].max()   # the sun is gone from the atlas
    assert np.array_equal(shown[~near_sun], whole[~near_sun])      # the softbox and the sky stay
    directions, irradiance = light_sources.shading_rows(sources, np.eye(3), 1.0)
    assert list(irradiance[:, 3]) == [1.0, 0.0]
    # the sun's points hold the light the atlas lost; the softbox has none (it stays in the atlas)
    found_sun, softbox = light_sources.with_highlight_points(sources, whole, remainder)
    assert softbox == sources[1] and not softbox.points
    assert np.array(found_sun.points)[:, 4:].sum(axis=0) == pytest.approx([1.0, 1.0, 1.0])


def test_a_highlight_keeps_its_own_texels_shape_and_colours(sdnative):
    """with_highlight_points: a sun with a white core and a red rim becomes points that hold all of
    its light per channel about its direction, the core's whiter than the rim's; a one-texel sun is
    one point at the texel, widened to a bilinear texel's peak (h_theta h_phi / (4 pi))."""
    height, width = 512, 1024
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = np.pi * (width - 2 * np.arange(width) - 1) / width
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    sun = np.array([math.cos(math.radians(30.0)), 0.0, math.sin(math.radians(30.0))])
    rgb = np.full((height, width, 3), 0.5, np.float32)
    rgb[d @ sun > math.cos(math.radians(0.9))] = (3000.0, 1000.0, 500.0)     # the rim
    rgb[d @ sun > math.cos(math.radians(0.4))] = (8000.0, 8000.0, 8000.0)    # the core
    env = sdnative.environment_from_pixels(rgb)
    split = env.light_sources(light_sources.SPLIT_ORDER)
    sources = [light_sources.Source.from_split(s) for s in split["sources"]]
    (source,) = light_sources.with_highlight_points(sources, env.pixels(), split["remainder"].pixels())
    points = np.array(source.points)
    assert points[:, 4:].sum(axis=0) == pytest.approx([1.0, 1.0, 1.0])
    mean = (points[:, 4:5] * points[:, :3]).sum(axis=0)
    assert mean / np.linalg.norm(mean) @ np.asarray(source.direction) > math.cos(math.radians(0.05))
    near = points[:, :3] @ sun > math.cos(math.radians(0.4))
    assert near.any() and (~near & (points[:, 4] > 0.0)).any()
    core, rim = points[near], points[~near & (points[:, 4] > 0.0)]
    assert core[:, 6].sum() / core[:, 4].sum() > 2.0 * rim[:, 6].sum() / rim[:, 4].sum()   # bluer, as the map

    one = np.full((height, width, 3), 0.5, np.float32)
    row, column = 120, 200
    one[row, column] = 1.0e6
    env = sdnative.environment_from_pixels(one)
    split = env.light_sources(light_sources.SPLIT_ORDER)
    sources = [light_sources.Source.from_split(s) for s in split["sources"]]
    (source,) = light_sources.with_highlight_points(sources, env.pixels(), split["remainder"].pixels())
    (x, y, z, widening, *share), *rest = sorted(source.points, key=lambda q: -q[4])
    assert share == pytest.approx([1.0, 1.0, 1.0]) and not any(q[4] for q in rest)
    assert np.array([x, y, z]) @ d[row, column] == pytest.approx(1.0, abs=1e-9)
    h_theta, h_phi = math.pi / height, 2.0 * math.pi / width * math.sin(theta[row])
    assert widening == pytest.approx(h_theta * h_phi / (4.0 * math.pi))


def test_highlight_rows_turn_the_points_into_the_bake_space():
    gr = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])   # 90 degrees about x
    point = (0.0, 0.6, 0.8, 2e-5, 0.25, 0.5, 1.0)
    found = light_sources.Source((0.0, 0.6, 0.8), (1.0, 0.0, 0.0), 0.01, 0.004, (1.0, 1.0, 1.0),
                                 points=(point,) + ((0.0,) * 7,) * (light_sources.HIGHLIGHT_POINTS - 1))
    bare = light_sources.Source((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), 0.01, 0.004, (1.0, 1.0, 1.0))
    rows = light_sources.highlight_rows([found, bare], gr)
    assert rows.shape == (4 * light_sources.HIGHLIGHT_POINTS, 4)
    assert rows[0] == pytest.approx([*(gr.T @ [0.0, 0.6, 0.8]), 2e-5])
    assert rows[1] == pytest.approx([0.25, 0.5, 1.0, 0.0])
    assert not rows[2:2 * light_sources.HIGHLIGHT_POINTS].any()
    # a source given without its texels: its centre, all of its light, an ellipse's peak
    k = 2 * light_sources.HIGHLIGHT_POINTS
    assert rows[k] == pytest.approx([*(gr.T @ [0.0, 0.0, 1.0]), 0.25 * 0.01 * 0.004])
    assert rows[k + 1] == pytest.approx([1.0, 1.0, 1.0, 0.0])
    assert not rows[k + 2:].any()
