"""The binding contract of sdnative.shade (rotation, per-vertex arrays, bad input) with one real
computation; every formula's math is tested in tests/cpp/shading."""
import numpy as np
import pytest

from sd_test_utils import random_directions, random_rotation, sh_count


def random_inputs(rng, n=200, s=4, s_v=2):
    light = rng.normal(size=(sh_count(s), 3))
    light[0] = 5.0
    visibility = 0.3 * rng.normal(size=(n, sh_count(s_v)))
    visibility[:, 0] = 0.7
    return light, random_directions(rng, n), random_directions(rng, n), visibility


def test_msd_theorem_2_1_equals_gaunt_prt(sd, rng):
    light, normals, views, visibility = random_inputs(rng)
    g = random_rotation(rng)
    common = dict(light=light, normals=normals, views=views, rotation=g, lobe="phong", exponent=8.0,
                  visibility=visibility)
    msd = sd.shade("msd_lobe", **common)
    prt = sd.shade("prt_gaunt", **common)
    np.testing.assert_allclose(msd, prt, rtol=0, atol=1e-9 * np.abs(prt).max())


def test_rotation_turns_the_environment(sd, rng):
    """B(n, g) for the environment turned by g equals B(g n) unturned: L(g x) seen around n."""
    light, normals, _, _ = random_inputs(rng, n=50)
    g = random_rotation(rng)
    turned = sd.shade("unshadowed", light=light, normals=normals, rotation=g)
    direct = sd.shade("unshadowed", light=light, normals=normals @ g.T)
    np.testing.assert_allclose(turned, direct, atol=1e-12 * np.abs(direct).max())


def test_ambient_occlusion_scales_unshadowed(sd, rng):
    light, normals, _, _ = random_inputs(rng, n=20)
    ao = rng.uniform(size=20)
    base = sd.shade("unshadowed", light=light, normals=normals)
    np.testing.assert_allclose(sd.shade("ambient_occlusion", light=light, normals=normals, ambient_occlusion=ao),
                               base * ao[:, None], atol=1e-14)


def test_bad_input_is_refused(sd, rng):
    light, normals, views, visibility = random_inputs(rng, n=5)
    with pytest.raises(ValueError, match="unknown method"):
        sd.shade("raytrace", light=light, normals=normals)
    with pytest.raises(ValueError, match="views"):
        sd.shade("unshadowed", light=light, normals=normals, lobe="phong", exponent=8.0)
    with pytest.raises(ValueError, match="perfect square"):
        sd.shade("unshadowed", light=light[:-1], normals=normals)
    with pytest.raises(ValueError, match="visibility"):
        sd.shade("prt_gaunt", light=light, normals=normals)
    with pytest.raises(ValueError, match="shape"):
        sd.shade("prt_gaunt", light=light, normals=normals, visibility=visibility[:3])
    bad = normals.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match="normals"):
        sd.shade("unshadowed", light=light, normals=bad)
    with pytest.raises(ValueError, match="transfer"):
        sd.shade("prt_diffuse", light=light, normals=normals)
    with pytest.raises(ValueError):
        sd.shade("unshadowed", light=light, normals=normals, rotation=2.0 * np.eye(3))
    with pytest.raises(ValueError, match="visibility_order"):
        sd.shade("msd_visibility", light=light, normals=normals, design_offsets=np.zeros(6, dtype=np.int64),
                 design_nodes=np.zeros((0, 3)), design_weights=np.zeros(0))


def test_baked_arrays_feed_every_method(sd, rng):
    """The arrays of bake_transfer go into shade as they are: MSD (13) equals PRT (8)-(9) on them, and
    every method returns (N, 3) float64."""
    dirs = random_directions(rng, 12)
    vertices, normals = 2.0 * dirs, dirs  # probes on a sphere, no triangles: V = 1
    triangles = np.zeros((0, 3), dtype=np.int64)
    bake = sd.bake_transfer(vertices, normals, triangles, 256, visibility_order=2, product_orders=(4, 2),
                            transfer_order=4, design_orders=(4, 2))
    light, _, views, _ = random_inputs(rng, n=12)
    common = dict(light=light, normals=normals, views=views, lobe="phong", exponent=8.0)
    msd = sd.shade("msd_visibility", visibility_order=2, design_offsets=bake["design_offsets"],
                   design_nodes=bake["design_nodes"], design_weights=bake["design_weights"], **common)
    prt = sd.shade("prt_matrix", product_matrices=bake["product_matrices"], **common)
    assert msd.shape == (12, 3) and msd.dtype == np.float64
    np.testing.assert_allclose(msd, prt, rtol=0, atol=1e-9 * np.abs(prt).max())
    diffuse = sd.shade("prt_diffuse", light=light, normals=normals, transfer=bake["transfer"])
    assert diffuse.shape == (12, 3) and np.all(np.isfinite(diffuse))


def test_reference_of_a_constant_sky_is_its_radiance(sd):
    sky = sd.environment_from_pixels(np.tile([1.0, 2.0, 3.0], (8, 16, 1)))
    normals = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    radiance, error = sd.reference(sky, np.zeros((2, 3)), normals, np.zeros((0, 3), dtype=int), samples=256)
    assert radiance.shape == (2, 3) and error.shape == (2, 3) and radiance.dtype == np.float64
    # Unoccluded and normalised lobes: B is the sky's radiance, within four standard errors.
    assert np.all(error > 0.0)
    assert np.all(np.abs(radiance - [1.0, 2.0, 3.0]) < 4.0 * error)
    with pytest.raises(ValueError, match="views"):
        sd.reference(sky, np.zeros((2, 3)), normals, np.zeros((0, 3), dtype=int), lobe="phong", exponent=8.0)


def test_reference_with_a_horizon_cuts_the_lobe_at_the_tangent_plane(sd):
    """horizon=True: V is 0 below each vertex's tangent plane - the prefiltered glossy light's open lobe."""
    sky = sd.environment_from_pixels(np.tile([1.0, 2.0, 3.0], (8, 16, 1)))
    normals = np.array([[0.0, 0.0, 1.0]])
    args = (sky, np.zeros((1, 3)), normals, np.zeros((0, 3), dtype=int))
    lambert = [sd.reference(*args, samples=256, horizon=h)[0] for h in (False, True)]
    assert np.array_equal(lambert[0], lambert[1])   # a cosine lobe has nothing below the plane
    # a Phong lobe whose axis lies in the plane (the view at grazing): half of it is above
    grazing = dict(views=np.array([[1.0, 0.0, 0.0]]), lobe="phong", exponent=8.0, samples=4096)
    whole, _ = sd.reference(*args, **grazing)
    half, error = sd.reference(*args, horizon=True, **grazing)
    assert np.all(np.abs(whole - [1.0, 2.0, 3.0]) < 1e-9 + 4.0 * error)
    assert np.all(np.abs(half - [0.5, 1.0, 1.5]) < 4.0 * error)


def test_reference_of_no_vertex_is_empty(sd):
    sky = sd.environment_from_pixels(np.tile([1.0, 2.0, 3.0], (8, 16, 1)))
    radiance, error = sd.reference(sky, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3), dtype=int))
    assert radiance.shape == error.shape == (0, 3)


def test_reference_refuses_a_matrix_that_is_no_rotation(sd):
    # Found by tests/fuzz/fuzz_reference: the reference took any matrix (NaN or silently wrong).
    sky = sd.environment_from_pixels(np.ones((4, 8, 3)))
    args = (sky, np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.zeros((0, 3), dtype=int))
    for matrix, match in [(np.full((3, 3), 0.72), "orthogonal"), (np.diag([1.0, 1.0, -1.0]), "reflection"),
                          (2.0 * np.eye(3), "orthogonal")]:
        with pytest.raises(ValueError, match=match):
            sd.reference(*args, rotation=matrix, samples=16)
    radiance, _ = sd.reference(*args, rotation=np.eye(3, dtype=np.float32), samples=16)
    assert np.all(np.isfinite(radiance))
