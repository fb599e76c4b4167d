"""The binding contract of environment maps (loading and its errors, array layouts, the methods'
arguments and results), with one real computation per function; the math of projection,
textures, error measures, designs and sampling is tested in tests/cpp/environment.

Image files are written here with a tiny PFM writer since the test interpreter has no image
library; Blender's studio-light HDRIs are used when installed (skipped with a message otherwise).
"""
import math
import os
import re

import numpy as np
import pytest

import sdnative
from sd_test_utils import EXACT, random_rotation, sh_count, sh_index

BLENDER_WORLDS = "/usr/share/blender/datafiles/studiolights/world"
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])

needs_blender = pytest.mark.skipif(
    not os.path.exists(os.path.join(BLENDER_WORLDS, "sunset.exr")),
    reason=f"Blender's studio lights are not installed in {BLENDER_WORLDS}",
)
# The add-on's builds read no image files (Blender reads them: issue 31); the test module does.
needs_image_files = pytest.mark.skipif(not hasattr(sdnative, "load_environment"),
                                       reason="a build of the add-on's: no image files")


# ---- references independent of the library ----

def pixel_directions(width, height):
    """Pixel centres, rows top-first: theta = pi (j+0.5)/H, phi = pi - 2 pi (i+0.5)/W."""
    theta = np.pi * (np.arange(height) + 0.5) / height
    phi = np.pi - 2.0 * np.pi * (np.arange(width) + 0.5) / width
    t, p = np.meshgrid(theta, phi, indexing="ij")
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


def cube_directions(n):
    """OpenGL face table on Blender's axes, inverted by hand: faces +X, -X, +Y, -Y, +Z, -Z."""
    s = 2.0 * (np.arange(n) + 0.5) / n - 1.0
    tc, sc = np.meshgrid(s, s, indexing="ij")  # rows (t) first
    one = np.ones_like(sc)
    faces = [
        (one, -tc, -sc), (-one, -tc, sc), (sc, one, tc),
        (sc, -one, -tc), (sc, -tc, one), (-sc, -tc, -one),
    ]
    d = np.stack([np.stack(f, axis=-1) for f in faces])
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def band_limited_function(sd, rng, order):
    """A random positive RGB function with coefficients c of shape ((order+1)^2, 3)."""
    c = np.zeros((sh_count(order), 3))
    for l in range(1, order + 1):
        for m in range(-l, l + 1):
            c[sh_index(l, m)] = rng.normal(size=3) / (l + 1.0)
    bound = sum(np.abs(c[sh_index(l, m)]) * math.sqrt(2 * l + 1) for l in range(1, order + 1) for m in range(-l, l + 1))
    c[0] = 0.5 + bound  # |y_lm| <= sqrt(2l+1): positive everywhere, nothing clamped

    def f(dirs):
        flat = dirs.reshape(-1, 3)
        return (sd.sh_basis(order, flat) @ c).reshape(dirs.shape[:-1] + (3,))

    return f, c


def write_pfm(path, rgb):
    """Portable float map: rows are stored bottom-to-top; rgb is (H, W, 3) rows top-first."""
    h, w, _ = rgb.shape
    with open(path, "wb") as out:
        out.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        out.write(np.ascontiguousarray(rgb[::-1], dtype="<f4").tobytes())


def sun_map(width, height, sun=(0.6, 0.0, 0.8), radius_deg=6.0):
    d = pixel_directions(width, height)
    sky = 0.2 + 0.1 * d[..., 2]
    rgb = np.stack([sky, sky, 1.5 * sky], axis=-1)
    inside = d @ np.asarray(sun) / np.linalg.norm(sun) > math.cos(math.radians(radius_deg))
    rgb[inside] = [500.0, 400.0, 300.0]
    return rgb


def brute_sh(sd, env, lmax, points=10):
    """L_lm = sum over texels of L times the integral of y_lm over the texel (a Gauss-Legendre
    product rule in theta and phi on each texel of an equirect map)."""
    height, width = env.height, env.width
    x, w = np.polynomial.legendre.leggauss(points)
    x, w = (x + 1) / 2, w / 2
    j, i, qt, qp = np.meshgrid(np.arange(height), np.arange(width), np.arange(points), np.arange(points),
                               indexing="ij")
    theta = np.pi * (j + x[qt]) / height
    phi = np.pi - 2 * np.pi * (i + x[qp]) / width
    dirs = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    area = w[qt] * w[qp] * np.sin(theta) * (np.pi / height) * (2 * np.pi / width) / (4 * np.pi)
    rgb = env.pixels()[j, i].astype(np.float64)
    return sd.sh_basis(lmax, dirs.reshape(-1, 3)).T @ (rgb * area[..., None]).reshape(-1, 3)


# ---- pixels, files, layouts ----

def test_top_row_looks_up(sd):
    rgb = np.zeros((33, 64, 3))
    rgb[0, :, 0] = 1.0
    env = sd.environment_from_pixels(rgb)
    assert env.radiance([0.0, 0.0, 1.0])[0] == 1.0
    assert env.radiance([0.0, 0.0, -1.0])[0] == 0.0
    assert env.radiance(np.array([[0.0, 0.0, 2.0], [1.0, 0.0, -1.0]])).shape == (2, 3)


def test_texels_and_layouts(sd):
    env = sd.environment_from_pixels(np.ones((31, 48, 3)))
    dirs, dmu, rgb = env.texels()
    assert dirs.shape == (31 * 48, 3) and dmu.shape == (31 * 48,) and rgb.shape == (31 * 48, 3)
    assert (env.layout, env.width, env.height, env.texel_count) == ("equirect", 48, 31, 31 * 48)
    np.testing.assert_allclose(dirs.reshape(31, 48, 3), pixel_directions(48, 31), atol=1e-14)
    assert abs(dmu.sum() - 1.0) < EXACT
    assert env.mass.shape == (4,) and env.norm_squared.shape == (4,)
    np.testing.assert_allclose(env.mass, [1.0] * 4, atol=EXACT)
    cube = sd.environment_from_cube_pixels(np.ones((6, 16, 16, 3)))
    cdirs, cdmu, _ = cube.texels()
    assert (cube.layout, cube.width, cube.texel_count) == ("cube", 16, 6 * 256)
    assert cube.pixels().shape == (6, 16, 16, 3)
    np.testing.assert_allclose(cdirs.reshape(6, 16, 16, 3), cube_directions(16), atol=1e-14)


def test_pixels_accept_rgba_and_clamp_negatives(sd):
    rgba = np.ones((4, 8, 4), dtype=np.float32)
    rgba[..., 3] = 0.0  # alpha ignored
    rgba[0, 0, 0] = -0.004
    rgba[1, 2, 1:3] = -1.0
    env = sd.environment_from_pixels(rgba)
    assert env.clamped_negative_pixels == 2
    px = env.pixels()
    assert px.shape == (4, 8, 3) and px.dtype == np.float32
    assert px.min() == 0.0 and px[0, 0, 0] == 0.0 and px[0, 1, 0] == 1.0


@pytest.mark.parametrize("bad,match", [
    (np.zeros((0, 0, 3)), "empty"),
    (np.zeros((4, 8)), "shape"),
    (np.zeros((4, 8, 2)), "shape"),
])
def test_bad_pixel_arrays(sd, bad, match):
    with pytest.raises(ValueError, match=match):
        sd.environment_from_pixels(bad)


def test_nan_and_inf_pixels_raise(sd):
    rgb = np.ones((4, 8, 3))
    rgb[2, 5, 1] = np.nan
    with pytest.raises(ValueError, match=r"x=5, y=2.*NaN"):
        sd.environment_from_pixels(rgb)
    rgb[2, 5, 1] = np.inf
    with pytest.raises(ValueError, match="infinite"):
        sd.environment_from_pixels(rgb)


@needs_image_files
def test_unreadable_files_raise_oserror_with_path(sd, tmp_path):
    missing = str(tmp_path / "missing.exr")
    empty = tmp_path / "empty.exr"
    empty.write_bytes(b"")
    garbage = tmp_path / "garbage.hdr"
    garbage.write_text("not an image")
    for path in (missing, str(empty), str(garbage)):
        with pytest.raises(OSError, match=re.escape(path)):
            sd.load_environment(path)
    with pytest.raises(OSError):
        sd.load_cube_environment([missing] * 6)
    with pytest.raises(ValueError, match="6 paths"):
        sd.load_cube_environment([missing] * 5)


@needs_image_files
def test_float_file_round_trip_and_nan_file(sd, tmp_path, rng):
    rgb = rng.uniform(0.0, 40.0, size=(16, 32, 3)).astype(np.float32)
    rgb[0, 3, 0] = -0.5
    path = str(tmp_path / "map.pfm")
    write_pfm(path, rgb)
    env = sd.load_environment(path)
    assert (env.width, env.height) == (32, 16)
    assert env.clamped_negative_pixels == 1
    np.testing.assert_array_equal(env.pixels(), np.maximum(rgb, 0.0))  # rows top-first, linear
    rgb[3, 4, 2] = np.nan
    bad = str(tmp_path / "nan.pfm")
    write_pfm(bad, rgb)
    with pytest.raises(ValueError, match="nan\\.pfm.*NaN"):
        sd.load_environment(bad)


@needs_blender
@needs_image_files
def test_blender_exr_loads(sd):
    env = sd.load_environment(os.path.join(BLENDER_WORLDS, "forest.exr"))
    assert (env.layout, env.width, env.height) == ("equirect", 1024, 512)
    assert np.all(np.isfinite(env.mass)) and np.all(env.mass > 0.0)


@needs_image_files
def test_cube_map_from_files_matches_pixels(sd, tmp_path, rng):
    pixels = rng.uniform(0.0, 4.0, size=(6, 24, 24, 3)).astype(np.float32)
    paths = []
    for face in range(6):
        paths.append(str(tmp_path / f"face{face}.pfm"))
        write_pfm(paths[-1], pixels[face])
    cube = sd.load_cube_environment(paths)
    np.testing.assert_array_equal(cube.pixels(), pixels)
    write_pfm(paths[2], pixels[2][:12, :12])
    with pytest.raises(ValueError, match="one size"):
        sd.load_cube_environment(paths)


# ---- projection and rotation ----

def test_projection_integrates_texels_as_areas(sd, rng):
    env = sd.environment_from_pixels(rng.uniform(0, 5, size=(27, 50, 3)))
    coeffs = env.sh(4)
    assert coeffs.shape == (sh_count(4), 3) and coeffs.dtype == np.float64
    expected = brute_sh(sd, env, 4)
    # The texel rules' bound: 1e-5 of max |y_lm| = 3 times the mass.
    np.testing.assert_allclose(coeffs, expected, rtol=0, atol=1e-5 * 3 * env.mass[:3].max())
    # A constant map of 2 x 1 texels is the constant, not two point lights.
    two = sd.environment_from_pixels(np.full((1, 2, 3), 3.0))
    np.testing.assert_allclose(two.sh(4)[0], 3.0, rtol=EXACT)
    assert np.abs(two.sh(4)[1:]).max() < 1e-5 * 9 * 3.0
    assert np.array_equal(env.sh(8, threads=1), env.sh(8, threads=2))
    with pytest.raises(ValueError, match="lmax"):
        env.sh(sd.MAX_PROJECTION_ORDER + 1)


def test_rotated_environment_sh(sd, rng):
    g = random_rotation(rng)
    f, c = band_limited_function(sd, rng, 4)
    rotated = sd.rotated_environment_sh(c, g)
    assert rotated.shape == c.shape and rotated.dtype == np.float64
    # Definition: the coefficients of x -> L(g x).
    x = rng.normal(size=(50, 3))
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    np.testing.assert_allclose(sd.sh_basis(4, x) @ rotated, f(x @ g.T), rtol=0, atol=EXACT * c[0].max())
    np.testing.assert_allclose(rotated, sd.rotate_sh(c, g.T), rtol=0, atol=EXACT * c[0].max())
    assert sd.rotated_environment_sh(c[:, 0], g).shape == (sh_count(4),)
    with pytest.raises(ValueError):
        sd.rotated_environment_sh(c, 2.0 * g)
    with pytest.raises(ValueError, match="square"):
        sd.rotated_environment_sh(np.ones((10, 3)), g)


# ---- band-limited textures, energies, errors ----

def test_band_limited_texture(sd):
    env = sd.environment_from_pixels(sun_map(256, 128))
    img = env.band_limited(8, 64, 32)
    assert img.shape == (32, 64, 3) and img.dtype == np.float32
    expected = sd.sh_basis(8, pixel_directions(64, 32).reshape(-1, 3)) @ env.sh(8)
    np.testing.assert_allclose(img.reshape(-1, 3), expected, rtol=1e-5, atol=1e-5 * np.abs(expected).max())
    image, report = env.band_limited(8, 128, 64, report=True)
    assert set(report) == {"min", "max", "negative_texels", "negative_fraction", "negative_solid_angle"}
    assert report["min"][0] == pytest.approx(float(image[..., 0].min()), rel=1e-6)
    assert report["negative_texels"] == int(np.any(image < 0, axis=2).sum())
    for window in ("hanning", "lanczos"):
        assert env.band_limited(8, 16, 8, window=window).shape == (8, 16, 3)
    with pytest.raises(ValueError, match="window"):
        env.band_limited(8, 64, 32, window="boxcar")
    with pytest.raises(ValueError, match="lmax"):
        env.band_limited(sd.MAX_ENERGY_ORDER + 1, 64, 32)


def test_band_limited_texture_of_rotated_coefficients(sd, rng):
    g = random_rotation(rng)
    f, c = band_limited_function(sd, rng, 5)
    tex = sd.band_limited_texture(sd.rotated_environment_sh(c, g), 48, 24)
    assert tex.shape == (24, 48, 3) and tex.dtype == np.float32
    np.testing.assert_allclose(tex, f(pixel_directions(48, 24) @ g.T), rtol=1e-6, atol=1e-6 * c[0].max())
    with pytest.raises(ValueError, match="square"):
        sd.band_limited_texture(np.ones((10, 3)), 8, 4)


def test_ringing_window(sd):
    env = sd.environment_from_pixels(sun_map(128, 64, radius_deg=3.0))
    keys = {"window", "sloan_lambda", "factors", "error", "unwindowed_error", "l2_error",
            "unwindowed_l2_error", "min_over_max", "unwindowed_min_over_max"}
    chosen = env.ringing_window("phong", 61.0, 8)
    assert set(chosen) == keys
    assert chosen["window"] in ("none", "hanning", "lanczos", "sloan")
    assert chosen["factors"].shape == (9,) and chosen["factors"][0] == 1.0
    assert chosen["error"] <= chosen["unwindowed_error"]
    hanning = env.ringing_window("phong", 61.0, 8, window="hanning")
    l = np.arange(9)
    np.testing.assert_allclose(hanning["factors"], 0.5 * (1 + np.cos(np.pi * l / 9)), rtol=0, atol=EXACT)
    sloan = env.ringing_window("phong", 61.0, 8, window="sloan")
    np.testing.assert_allclose(sloan["factors"], 1 / (1 + sloan["sloan_lambda"] * (l * (l + 1)) ** 2),
                               rtol=0, atol=EXACT)
    # The measure of given factors: the chosen window's own, and that of none.
    again = env.displayed_error("phong", 61.0, 8, hanning["factors"])
    assert set(again) == keys - {"window", "sloan_lambda"}
    assert again["error"] == hanning["error"]
    assert env.displayed_error("phong", 61.0, 8, np.ones(9))["error"] == chosen["unwindowed_error"]
    # Sloan's window in the texture is that of the windowed coefficients.
    texture = env.band_limited(8, 32, 16, window="sloan", sloan_lambda=sloan["sloan_lambda"])
    by_hand = sd.band_limited_texture(env.sh(8) * np.repeat(sloan["factors"], 2 * l + 1)[:, None], 32, 16)
    np.testing.assert_allclose(texture, by_hand, rtol=1e-5, atol=1e-5 * np.abs(by_hand).max())
    with pytest.raises(ValueError, match="window"):
        env.ringing_window("phong", 61.0, 8, window="boxcar")
    with pytest.raises(ValueError):
        env.ringing_window("phong", 61.0, sd.MAX_SHADING_ORDER + 1)
    with pytest.raises(ValueError, match="factors"):
        env.displayed_error("phong", 61.0, 8, np.ones(8))
    with pytest.raises(ValueError, match="sloan_lambda"):
        env.band_limited(8, 32, 16, window="sloan", sloan_lambda=-1.0)


def test_band_energies_and_error_measures(sd):
    env = sd.environment_from_pixels(sun_map(128, 64, radius_deg=3.0))
    e = env.band_energies(16)
    assert e.shape == (17, 4) and e.dtype == np.float64
    c = env.sh(16)
    np.testing.assert_allclose(e[2, :3], (c[4:9] ** 2).sum(axis=0), rtol=1e-12)
    assert env.low_frequency_error(0, "luminance") == pytest.approx(
        math.sqrt(1.0 - env.mass[3] ** 2 / env.norm_squared[3]), abs=EXACT)
    assert env.low_frequency_error(4, 0) == env.low_frequency_error(4, "r")
    errors = [env.lobe_filtered_error("phong", 8.0, s) for s in range(17)]
    s = env.smallest_order("phong", 8.0, 0.05, 16)
    assert isinstance(s, int) and errors[s] <= 0.05 and (s == 0 or errors[s - 1] > 0.05)
    assert env.smallest_order("phong", 32.0, 1e-9) is None  # max_order = 16
    with pytest.raises(ValueError, match="channel"):
        env.low_frequency_error(4, "alpha")


def test_channel_design(sd):
    env = sd.environment_from_pixels(sun_map(256, 128, sun=(0.3, -0.4, 0.866), radius_deg=10.0))
    copy = env.area_averaged(64, 32)
    dirs, dmu, rgb = copy.texels()
    values = rgb @ LUMINANCE
    nodes, weights = env.channel_design("luminance", 6)
    assert nodes.shape[1] == 3 and len(nodes) <= 49 and np.all(weights > 0)
    mass = float(np.sum(values * dmu))
    moments = sd.sh_basis(6, nodes).T @ weights
    target = sd.sh_basis(6, dirs).T @ (values * dmu)
    assert np.linalg.norm(moments - target) <= sd.DESIGN_TOLERANCE * mass * 1.0001
    assert weights.sum() == pytest.approx(mass, rel=1e-9)
    with pytest.raises(ValueError, match="channel"):
        env.channel_design("alpha", 4)
    black_green = np.zeros((32, 64, 3))
    black_green[..., 0] = 1.0
    with pytest.raises(ValueError, match="black"):
        sd.environment_from_pixels(black_green).channel_design(1, 4)


# ---- sampling ----

def test_sampler(sd, rng):
    env = sd.environment_from_pixels(sun_map(64, 32, radius_deg=8.0))
    sampler = sd.EnvironmentSampler(env)
    dirs, pdf = sampler.sample(rng.uniform(size=(20000, 2)))
    assert dirs.shape == (20000, 3) and pdf.shape == (20000,)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=EXACT)
    np.testing.assert_allclose(sampler.pdf(dirs), pdf, rtol=1e-9)
    x = env.radiance(dirs)[:, 0] / pdf  # an unbiased estimate of integral L dmu
    assert abs(x.mean() - env.mass[0]) < 5 * x.std() / math.sqrt(len(x))
    with pytest.raises(ValueError, match="shape"):
        sampler.sample(np.zeros((4, 3)))


def test_environment_brdf_and_its_table():
    a, b = sdnative.environment_brdf(0.5, 0.4, 512)
    table = sdnative.environment_brdf_table(8, 512)
    dielectric = sdnative.environment_brdf_table(8, 512, ior=1.5)
    assert table.shape == dielectric.shape == (8, 8, 2) and table.dtype == np.float64
    assert 0.0 < b < a and a + b <= 1.0
    # The Fresnel shape moves light between A and B, never the lobe's albedo A + B.
    np.testing.assert_allclose(table.sum(axis=2), dielectric.sum(axis=2), atol=1e-6)
    # IOR 1.5's Fresnel rises earlier than Schlick's (from n.v 0.3 up; nearer grazing it is lower).
    assert (dielectric[:, 2:, 1] > table[:, 2:, 1]).all() and dielectric[0, 0, 1] < table[0, 0, 1]
    with pytest.raises(ValueError, match="ior must be 0"):
        sdnative.environment_brdf(0.5, 0.4, 512, ior=0.9)


def test_glossy_bend_and_its_table():
    table = sdnative.glossy_bend_table(8, 256)
    assert table.shape == (8, 8) and table.dtype == np.float64
    assert table[5, 3] == pytest.approx(sdnative.glossy_bend(3.5 / 8, 5 / 7, 256), rel=1e-6)
    # a mirror reads the mirrored view, the roughest lobe about the normal; a rough lobe seen at
    # grazing leans towards the normal
    assert (table[0] > 0.999).all() and sdnative.glossy_bend(1.0, 0.5) == 1.0
    assert table[-1].max() < 0.05
    assert 0.0 < table[5, 0] < table[4, 0] < table[4, -1] < 1.0
    # a dielectric's Fresnel weighs the grazing light, nearer the mirrored view: it bends less
    dielectric = sdnative.glossy_bend_table(8, 256, ior=1.5)
    assert (dielectric[3:, :4] > table[3:, :4]).all() and dielectric[0, 0] > 0.999
    with pytest.raises(ValueError, match="ior must be 0"):
        sdnative.glossy_bend(0.5, 0.5, ior=0.5)
    with pytest.raises(ValueError, match="n_dot_v must be in"):
        sdnative.glossy_bend(0.0, 0.5)
    with pytest.raises(ValueError, match="size must be in"):
        sdnative.glossy_bend_table(300)


def test_light_sources_split_a_sun_off_and_give_back_the_remainder():
    # a 2-degree sun at the zenith's side on a grey sky, through the binding
    height, width = 128, 256
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = np.pi * (width - 2 * np.arange(width) - 1) / width
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    sun = np.array([0.6, 0.0, 0.8])
    rgb = np.full((height, width, 3), 0.5)
    rgb[d @ sun > np.cos(np.radians(3.0))] = (500.0, 400.0, 300.0)
    env = sdnative.environment_from_pixels(rgb.astype(np.float32))
    split = env.light_sources(8, 4)
    assert len(split["sources"]) == 1 and split["threshold"] > 0.5
    source = split["sources"][0]
    assert np.degrees(np.arccos(np.dot(source["direction"], sun))) < 1.0
    assert set(source) == {"direction", "major_axis", "major_radius", "minor_radius", "extent", "solid_angle",
                           "power", "texels"}
    remainder = split["remainder"]
    for c in range(3):
        assert remainder.mass[c] + source["power"][c] == pytest.approx(env.mass[c], rel=1e-9)
    assert split["error_after"] < 0.1 * split["error_before"]
    assert env.light_sources()["threshold"] == split["threshold"]   # the defaults: s = 8, four sources
    with pytest.raises(ValueError, match="cube"):
        sdnative.environment_from_cube_pixels(np.ones((6, 8, 8, 3), np.float32)).light_sources()
    with pytest.raises(ValueError, match="max_sources"):
        env.light_sources(8, 0)
