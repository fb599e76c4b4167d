"""Environment maps through sdnative: loading, orientation, SH projection and rotation,
band-limited textures, energies and error measures, designs of a channel, sampling.

Tolerances: EXACT (1e-12) for what the library computes exactly; quadrature (midpoint rule) and
Monte Carlo tolerances are derived where they are used. Image files are written here with tiny
writers (PFM for floats, PNG for 8-bit) since the test interpreter has no image library; Blender's
studio-light HDRIs are used when installed (skipped with a message otherwise).
"""
import math
import os
import re
import struct
import zlib

import numpy as np
import pytest

from sd_test_utils import EXACT, random_rotation, sh_count, sh_index, sphere_product_rule

BLENDER_WORLDS = "/usr/share/blender/datafiles/studiolights/world"
BLENDER_HDRIS = ["city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset"]
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])

needs_blender = pytest.mark.skipif(
    not os.path.exists(os.path.join(BLENDER_WORLDS, "sunset.exr")),
    reason=f"Blender's studio lights are not installed in {BLENDER_WORLDS}",
)


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


def write_png(path, pixels):
    """8-bit PNG of a uint8 array (H, W, C), C = 1 (grey), 2 (grey + alpha), 3 (RGB) or 4 (RGBA)."""
    h, w, c = pixels.shape
    color_type = {1: 0, 2: 4, 3: 2, 4: 6}[c]
    raw = b"".join(b"\x00" + pixels[y].astype(np.uint8).tobytes() for y in range(h))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    with open(path, "wb") as out:
        out.write(b"\x89PNG\r\n\x1a\n")
        out.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, color_type, 0, 0, 0)))
        out.write(chunk(b"IDAT", zlib.compress(raw)))
        out.write(chunk(b"IEND", b""))


def srgb_to_linear(c):
    c = np.asarray(c, dtype=float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def sun_map(width, height, sun=(0.6, 0.0, 0.8), radius_deg=6.0):
    d = pixel_directions(width, height)
    sky = 0.2 + 0.1 * d[..., 2]
    rgb = np.stack([sky, sky, 1.5 * sky], axis=-1)
    inside = d @ np.asarray(sun) / np.linalg.norm(sun) > math.cos(math.radians(radius_deg))
    rgb[inside] = [500.0, 400.0, 300.0]
    return rgb


def band1_direction(coeffs, channel=0):
    v = np.array([coeffs[sh_index(1, 1), channel], coeffs[sh_index(1, -1), channel], coeffs[sh_index(1, 0), channel]])
    return v / np.linalg.norm(v)


def brute_sh(sd, env, lmax):
    dirs, dmu, rgb = env.texels()
    return sd.sh_basis(lmax, dirs).T @ (rgb * dmu[:, None])


# ---- orientation, geometry, loading ----

@pytest.mark.parametrize("width,height,i,j,expected", [
    (65, 33, 32, 16, (1.0, 0.0, 0.0)),   # horizontal centre -> +X
    (66, 33, 16, 16, (0.0, 1.0, 0.0)),   # column W/4 (phi = pi/2 exactly for W = 66, i = 16) -> +Y
    (66, 33, 49, 16, (0.0, -1.0, 0.0)),  # column 3W/4 -> -Y
])
def test_single_bright_pixel_orientation(sd, width, height, i, j, expected):
    rgb = np.zeros((height, width, 3))
    rgb[j, i] = 100.0
    env = sd.environment_from_pixels(rgb)
    np.testing.assert_allclose(band1_direction(env.sh(1)), expected, atol=1e-12)
    np.testing.assert_allclose(env.radiance(np.asarray(expected)), [100.0] * 3, rtol=0, atol=0)


def test_top_row_looks_up(sd):
    rgb = np.zeros((33, 64, 3))
    rgb[0, :, 0] = 1.0
    env = sd.environment_from_pixels(rgb)
    np.testing.assert_allclose(band1_direction(env.sh(1)), [0.0, 0.0, 1.0], atol=1e-12)
    assert env.radiance([0.0, 0.0, 1.0])[0] == 1.0
    assert env.radiance([0.0, 0.0, -1.0])[0] == 0.0


def test_lookup_follows_cycles_formula(sd, rng):
    width, height = 40, 24
    values = np.arange(width * height, dtype=float).reshape(height, width)
    env = sd.environment_from_pixels(np.repeat(values[:, :, None], 3, axis=2))
    d = rng.normal(size=(3000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    u = 0.5 - np.arctan2(d[:, 1], d[:, 0]) / (2 * np.pi)
    v = 1.0 - np.arccos(d[:, 2]) / np.pi  # v = 0 at the bottom row
    i = np.minimum((u * width).astype(int), width - 1)
    row = height - 1 - np.minimum((v * height).astype(int), height - 1)
    np.testing.assert_array_equal(env.radiance(d)[:, 0], values[row, i])


def test_texels_and_solid_angles(sd):
    env = sd.environment_from_pixels(np.ones((31, 48, 3)))
    dirs, dmu, rgb = env.texels()
    assert dirs.shape == (31 * 48, 3) and dmu.shape == (31 * 48,) and rgb.shape == (31 * 48, 3)
    np.testing.assert_allclose(dirs.reshape(31, 48, 3), pixel_directions(48, 31), atol=1e-14)
    assert abs(dmu.sum() - 1.0) < EXACT
    theta = np.pi * np.arange(32) / 31
    expected = (2 * np.pi / 48) * (np.cos(theta[:-1]) - np.cos(theta[1:])) / (4 * np.pi)
    np.testing.assert_allclose(dmu.reshape(31, 48), np.repeat(expected[:, None], 48, axis=1), rtol=1e-13)
    np.testing.assert_allclose(env.mass, [1.0] * 4, atol=EXACT)
    cube = sd.environment_from_cube_pixels(np.ones((6, 16, 16, 3)))
    cdirs, cdmu, _ = cube.texels()
    assert cube.layout == "cube" and cube.width == 16 and cube.texel_count == 6 * 256
    assert abs(cdmu.sum() - 1.0) < EXACT
    np.testing.assert_allclose(cdirs.reshape(6, 16, 16, 3), cube_directions(16), atol=1e-14)
    # Face centres look along +X, -X, +Y, -Y, +Z, -Z.
    probe = sd.environment_from_cube_pixels(np.arange(6, dtype=float)[:, None, None, None] * np.ones((6, 9, 9, 3)))
    np.testing.assert_array_equal(probe.radiance(np.vstack([np.eye(3)[k] * s for k in range(3) for s in (1, -1)]))[:, 0],
                                  np.arange(6))


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


def test_eight_bit_png_is_srgb_decoded(sd, tmp_path):
    rgb = np.full((4, 8, 3), 188, dtype=np.uint8)
    rgb[0, 0] = [10, 255, 0]
    path = str(tmp_path / "srgb.png")
    write_png(path, rgb)
    px = sd.load_environment(path).pixels()
    half = float(srgb_to_linear(188 / 255))
    assert abs(half - 0.5) < 0.004
    np.testing.assert_allclose(px[1:], half, rtol=1e-6)
    np.testing.assert_allclose(px[0, 0], srgb_to_linear(np.array([10, 255, 0]) / 255), rtol=1e-6, atol=1e-7)
    grey = np.full((4, 8, 2), 188, dtype=np.uint8)
    grey[..., 1] = np.arange(32, dtype=np.uint8).reshape(4, 8)  # alpha: ignored
    write_png(str(tmp_path / "grey.png"), grey)
    np.testing.assert_allclose(sd.load_environment(str(tmp_path / "grey.png")).pixels(), half, rtol=1e-6)


def test_cube_map_from_files_matches_pixels(sd, tmp_path, rng):
    f, c = band_limited_function(sd, rng, 3)
    pixels = f(cube_directions(24)).astype(np.float32)
    paths = []
    for face in range(6):
        paths.append(str(tmp_path / f"face{face}.pfm"))
        write_pfm(paths[-1], pixels[face])
    cube = sd.load_cube_environment(paths)
    np.testing.assert_array_equal(cube.pixels(), pixels)
    np.testing.assert_allclose(cube.sh(3), c, atol=2e-3 * np.abs(c).max())
    write_pfm(paths[2], pixels[2][:12, :12])
    with pytest.raises(ValueError, match="one size"):
        sd.load_cube_environment(paths)


# ---- projection and rotation ----

def test_projection_is_the_texel_sum(sd, rng):
    env = sd.environment_from_pixels(rng.uniform(0, 5, size=(27, 50, 3)))
    cube = sd.environment_from_cube_pixels(rng.uniform(0, 5, size=(6, 7, 7, 3)))
    for e in (env, cube):
        for lmax in (0, 4, 16):
            expected = brute_sh(sd, e, lmax)
            np.testing.assert_allclose(e.sh(lmax), expected, rtol=0, atol=EXACT * np.abs(expected).max())
    assert np.array_equal(env.sh(8, threads=1), env.sh(8, threads=2))
    with pytest.raises(ValueError, match="lmax"):
        env.sh(17)


def test_recovers_band_limited_coefficients(sd, rng):
    f, c = band_limited_function(sd, rng, 6)
    errors = []
    for width, height in ((128, 64), (512, 256)):
        env = sd.environment_from_pixels(f(pixel_directions(width, height)))
        errors.append(np.abs(env.sh(6) - c).max() / np.abs(c).max())
    assert errors[1] < 3e-4
    assert 8.0 < errors[0] / errors[1] < 32.0  # midpoint rule in theta: error ~ 1/H^2


def test_cube_and_equirect_agree(sd, rng):
    f, c = band_limited_function(sd, rng, 5)
    a = sd.environment_from_pixels(f(pixel_directions(512, 256))).sh(5)
    b = sd.environment_from_cube_pixels(f(cube_directions(96))).sh(5)
    np.testing.assert_allclose(a, c, atol=3e-4 * np.abs(c).max())
    np.testing.assert_allclose(b, c, atol=3e-4 * np.abs(c).max())


def test_rotated_environment_sh(sd, rng):
    g = random_rotation(rng)
    f, c = band_limited_function(sd, rng, 4)
    rotated = sd.rotated_environment_sh(c, g)
    assert rotated.shape == c.shape
    # Definition: the coefficients of x -> L(g x).
    x = rng.normal(size=(50, 3))
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    np.testing.assert_allclose(sd.sh_basis(4, x) @ rotated, f(x @ g.T), rtol=0, atol=EXACT * c[0].max())
    np.testing.assert_allclose(rotated, sd.rotate_sh(c, g.T), rtol=0, atol=EXACT * c[0].max())
    # Against the projection of the turned map.
    turned = sd.environment_from_pixels(f(pixel_directions(512, 256) @ g.T)).sh(4)
    plain = sd.environment_from_pixels(f(pixel_directions(512, 256))).sh(4)
    np.testing.assert_allclose(sd.rotated_environment_sh(plain, g), turned, atol=5e-4 * np.abs(c).max())
    with pytest.raises(ValueError):
        sd.rotated_environment_sh(c, 2.0 * g)
    with pytest.raises(ValueError, match="square"):
        sd.rotated_environment_sh(np.ones((10, 3)), g)


# ---- band-limited textures, energies, errors ----

def test_band_limited_texture(sd):
    env = sd.environment_from_pixels(sun_map(256, 128))
    img = env.band_limited(8, 64, 32)
    assert img.shape == (32, 64, 3) and img.dtype == np.float32
    coeffs = env.sh(8)
    expected = sd.sh_basis(8, pixel_directions(64, 32).reshape(-1, 3)) @ coeffs
    np.testing.assert_allclose(img.reshape(-1, 3), expected, rtol=1e-5, atol=1e-5 * np.abs(expected).max())
    image, report = env.band_limited(8, 128, 64, report=True)
    assert set(report) == {"min", "max", "negative_texels", "negative_fraction", "negative_solid_angle"}
    assert report["min"][0] == pytest.approx(float(image[..., 0].min()), rel=1e-6)
    assert report["negative_texels"] == int(np.any(image < 0, axis=2).sum())
    assert report["negative_fraction"] == pytest.approx(report["negative_texels"] / (128 * 64), abs=EXACT)
    windowed = [env.band_limited(8, 128, 64, window=w, report=True)[1] for w in ("hanning", "lanczos")]
    assert report["min"][0] < 0.0
    for r in windowed:
        assert r["min"][0] > report["min"][0]
        assert r["negative_texels"] < report["negative_texels"]
    with pytest.raises(ValueError, match="window"):
        env.band_limited(8, 64, 32, window="boxcar")
    with pytest.raises(ValueError, match="lmax"):
        env.band_limited(65, 64, 32)


def test_band_limited_texture_of_rotated_coefficients(sd, rng):
    g = random_rotation(rng)
    f, c = band_limited_function(sd, rng, 5)
    tex = sd.band_limited_texture(sd.rotated_environment_sh(c, g), 48, 24)
    assert tex.shape == (24, 48, 3) and tex.dtype == np.float32
    np.testing.assert_allclose(tex, f(pixel_directions(48, 24) @ g.T), rtol=1e-6, atol=1e-6 * c[0].max())
    with pytest.raises(ValueError, match="square"):
        sd.band_limited_texture(np.ones((10, 3)), 8, 4)


def test_band_energies_and_parseval(sd):
    env = sd.environment_from_pixels(sun_map(256, 128, sun=(0.0, 0.6, 0.8)))
    e = env.band_energies(16)
    assert e.shape == (17, 4)
    c = env.sh(16)
    y = c @ LUMINANCE
    for l in range(17):
        block = slice(l * l, (l + 1) * (l + 1))
        np.testing.assert_allclose(e[l, :3], (c[block] ** 2).sum(axis=0), rtol=1e-12)
        assert e[l, 3] == pytest.approx(float((y[block] ** 2).sum()), rel=1e-12)
    np.testing.assert_allclose(e[0], env.mass ** 2, rtol=1e-12)
    dirs, dmu, rgb = env.texels()
    for s in (2, 4, 8):
        approx = sd.sh_basis(s, dirs) @ env.sh(s)
        direct = math.sqrt(np.sum((rgb[:, 0] - approx[:, 0]) ** 2 * dmu) / np.sum(rgb[:, 0] ** 2 * dmu))
        assert env.low_frequency_error(s, 0) == pytest.approx(direct, abs=1e-3)
    eps = [env.low_frequency_error(s) for s in range(65)]
    assert all(a >= b for a, b in zip(eps, eps[1:]))
    assert env.low_frequency_error(0, "luminance") == pytest.approx(
        math.sqrt(1.0 - env.mass[3] ** 2 / env.norm_squared[3]), abs=EXACT)


def test_lobe_filtered_error_and_smallest_order(sd):
    env = sd.environment_from_pixels(sun_map(128, 64, radius_deg=3.0))
    for lobe, sigma in (("lambert", 0.0), ("phong", 8.0), ("phong", 32.0)):
        errors = [env.lobe_filtered_error(lobe, sigma, s) for s in range(65)]
        assert all(a >= b for a, b in zip(errors, errors[1:]))
        assert errors[-1] == 0.0
        s = env.smallest_order(lobe, sigma, 0.05, 64)
        assert errors[s] <= 0.05 and (s == 0 or errors[s - 1] > 0.05)
    assert env.smallest_order("phong", 32.0, 1e-9) is None  # max_order = 16
    # Against the definition: relative RMS over axes of B - B~_s, B by brute force over the texels.
    axes, weights = sphere_product_rule(48, 96, phi_offset=0.5)
    dirs, dmu, rgb = env.texels()
    lum = rgb @ LUMINANCE * dmu
    for sigma, s in ((8.0, 4), (32.0, 6)):
        b = ((2 * sigma + 2) * np.maximum(axes @ dirs.T, 0.0) ** sigma) @ lum
        w = sd.zonal_coefficients("phong", sigma, s)
        ls = np.repeat(w, 2 * np.arange(s + 1) + 1)
        truncated = sd.sh_basis(s, axes) @ (ls * (env.sh(s) @ LUMINANCE))
        brute = math.sqrt(np.sum(weights * (b - truncated) ** 2) / np.sum(weights * b * b))
        assert env.lobe_filtered_error("phong", sigma, s) == pytest.approx(brute, rel=5e-3)


def test_channel_design(sd):
    env = sd.environment_from_pixels(sun_map(256, 128, sun=(0.3, -0.4, 0.866), radius_deg=10.0))
    copy = env.area_averaged(64, 32)
    dirs, dmu, rgb = copy.texels()
    for channel, values in ((0, rgb[:, 0]), ("luminance", rgb @ LUMINANCE)):
        nodes, weights = env.channel_design(channel, 6)
        assert nodes.shape[1] == 3 and len(nodes) <= 49 and np.all(weights > 0)
        target = sd.sh_basis(6, dirs).T @ (values * dmu)
        mass = float(np.sum(values * dmu))
        moments = sd.sh_basis(6, nodes).T @ weights
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
    # Density integrates to 1: sub-cells uniform in phi and cos(theta) nested in the texels.
    sub = 3
    z_edges = np.cos(np.pi * np.arange(32 * sub + 1) / (32 * sub))
    z = 0.5 * (z_edges[:-1] + z_edges[1:])
    phi = np.pi - 2 * np.pi * (np.arange(64 * sub) + 0.5) / (64 * sub)
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    r = np.sqrt(1 - zz ** 2)
    d = np.stack([r * np.cos(pp), r * np.sin(pp), zz], -1).reshape(-1, 3)
    cell = np.repeat((z_edges[:-1] - z_edges[1:]) / (2 * 64 * sub), 64 * sub)
    assert float(np.sum(sampler.pdf(d) * cell)) == pytest.approx(1.0, abs=EXACT)
    # Unbiased estimates of integral 1 dmu and integral L dmu.
    dirs, pdf = sampler.sample(rng.uniform(size=(200000, 2)))
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=EXACT)
    np.testing.assert_allclose(sampler.pdf(dirs), pdf, rtol=1e-9)
    for f, expected in ((np.ones(len(dirs)), 1.0), (env.radiance(dirs)[:, 0], env.mass[0])):
        x = f / pdf
        assert abs(x.mean() - expected) < 5 * x.std() / math.sqrt(len(x))
    with pytest.raises(ValueError, match="shape"):
        sampler.sample(np.zeros((4, 3)))


# ---- Blender's HDRIs ----

@needs_blender
@pytest.mark.parametrize("name", ["sunrise", "studio", "sunset"])
def test_blender_lambert_order8_against_brute_force(sd, name):
    """Unshadowed Lambert at s = 8 against the direct sum over the HDRI's pixels for 512 normals
    (product rule): the relative RMS over normals equals lobe_filtered_error and is below 1.5 %
    (0.1-1.4 % on Blender's maps; per normal, where B is small, the error is a larger fraction of B
    but stays below 10 % of the mean irradiance)."""
    env = sd.load_environment(os.path.join(BLENDER_WORLDS, name + ".exr"))
    normals, weights = sphere_product_rule(16, 32, phi_offset=0.5)
    dirs, dmu, rgb = env.texels()
    weighted = rgb * dmu[:, None]
    direct = np.concatenate([4.0 * np.maximum(chunk @ dirs.T, 0.0) @ weighted for chunk in np.array_split(normals, 16)])
    w = np.repeat(sd.zonal_coefficients("lambert", 0.0, 8), 2 * np.arange(9) + 1)
    approx = sd.sh_basis(8, normals) @ (w[:, None] * env.sh(8))
    assert np.all(np.abs(approx - direct) < 0.10 * env.mass[:3])
    e = (approx - direct) @ LUMINANCE
    rms = math.sqrt(np.sum(weights * e ** 2) / np.sum(weights * (direct @ LUMINANCE) ** 2))
    assert rms == pytest.approx(env.lobe_filtered_error("lambert", 0.0, 8), rel=0.05)
    assert rms < 0.015


@needs_blender
def test_blender_error_measures(sd):
    values = []
    for name in BLENDER_HDRIS:
        env = sd.load_environment(os.path.join(BLENDER_WORLDS, name + ".exr"))
        assert (env.width, env.height) == (1024, 512)
        values.append([env.lobe_filtered_error("lambert", 0.0, 4), env.lobe_filtered_error("phong", 8.0, 4),
                       env.lobe_filtered_error("phong", 32.0, 4), env.low_frequency_error(8)])
        s = env.smallest_order("lambert", 0.0, 0.01, 16)  # 1 % RMS: s = 4..12 on these maps
        assert s is not None and env.lobe_filtered_error("lambert", 0.0, s) <= 0.01 < env.lobe_filtered_error(
            "lambert", 0.0, s - 1)
    v = np.array(values)
    # msd-notes quote 0.2-3 %, 6-20 %, 22-63 % and 0.6-1.0; measured here 0.34-3.3 %, 4.8-19.9 %,
    # 18-63 % and 0.62-1.0 (sunset is below the quoted lower ends).
    assert 0.001 < v[:, 0].min() and v[:, 0].max() < 0.04
    assert 0.03 < v[:, 1].min() and v[:, 1].max() < 0.25
    assert 0.11 < v[:, 2].min() and v[:, 2].max() < 0.70
    assert 0.55 < v[:, 3].min() and v[:, 3].max() <= 1.0
    assert np.all(v[:, 0] < v[:, 1]) and np.all(v[:, 1] < v[:, 2])
