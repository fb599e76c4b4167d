"""sdnative.shade: the formulas agree where the math says they must, and bad input is refused."""
import numpy as np
import pytest

from sd_test_utils import random_directions, random_rotation, sh_count


def random_inputs(rng, n=200, s=4, s_v=2):
    light = rng.normal(size=(sh_count(s), 3))
    light[0] = 5.0
    visibility = 0.3 * rng.normal(size=(n, sh_count(s_v)))
    visibility[:, 0] = 0.7
    return light, random_directions(rng, n), random_directions(rng, n), visibility


@pytest.mark.parametrize("lobe,exponent", [("lambert", 1.0), ("phong", 8.0), ("phong", 32.0)])
def test_msd_theorem_2_1_equals_gaunt_prt(sd, rng, lobe, exponent):
    light, normals, views, visibility = random_inputs(rng)
    g = random_rotation(rng)
    common = dict(light=light, normals=normals, views=views, rotation=g, lobe=lobe, exponent=exponent,
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


def test_unshadowed_lambert_of_a_constant_sky_is_its_radiance(sd, rng):
    light = np.zeros((sh_count(2), 3))
    light[0] = [1.0, 2.0, 3.0]
    out = sd.shade("unshadowed", light=light, normals=random_directions(rng, 10))
    np.testing.assert_allclose(out, np.tile([1.0, 2.0, 3.0], (10, 1)), atol=1e-14)


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
