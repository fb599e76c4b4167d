"""Roughness -> Phong sigma, and how a Principled BSDF splits between the Lambert and Phong
lobes (the shader's colours from the weights: test_material_colour against Cycles)."""

import numpy as np
import pytest

from sd_lighting.scene import lobes

F0 = 0.04   # IOR 1.5


@pytest.mark.parametrize("roughness, sigma", [(0.5, 7.5), (0.3, 61.228395), (0.2, 312.0),
                                              (0.7, 1.5824656), (0.9, 1.0), (0.05, 1000.0),
                                              (0.0, 1000.0)])
def test_exponent_from_roughness(roughness, sigma):
    assert lobes.exponent_from_roughness(roughness) == pytest.approx(sigma, rel=1e-4)


@pytest.mark.parametrize("kwargs, f0", [({}, 0.04), ({"ior": 1.5, "ior_level": 0.5}, 0.04),
                                        ({"ior": 1.5, "ior_level": 1.0}, 0.08),
                                        ({"ior": 1.5, "ior_level": 0.0}, 0.0),
                                        ({"ior": 2.0, "ior_level": 0.5}, 1.0 / 9.0),
                                        ({"specular": 0.5}, 0.04), ({"specular": 1.0}, 0.08),
                                        ({"ior": 1e6, "ior_level": 1.0}, 1.0)])
def test_dielectric_reflectance(kwargs, f0):
    assert lobes.dielectric_reflectance(**kwargs) == pytest.approx(f0, rel=1e-3)


def test_dielectrics_without_a_specular_layer_are_lambert_alone():
    assert lobes.lobes_from_principled(0.5, 0.0, 0.0) == (lobes.Lobes(), "no specular layer (F0 = 0) -> Lambert")
    assert lobes.principled_weights(0.9, 0.0, 0.0) == lobes.DIFFUSE_ONLY


def test_metals_are_phong_alone():
    found, why = lobes.lobes_from_principled(0.3, 1.0, F0)
    assert found == lobes.Lobes("phong", pytest.approx(61.228395, rel=1e-6), False, True)
    assert lobes.principled_weights(0.3, 1.0, F0) == (1.0, F0, 0.3, lobes.LAYER_OVER)
    assert why == "metallic 1.00, roughness 0.30 -> Phong sigma 61.2"


def test_smooth_dielectrics_have_both_lobes():
    found, why = lobes.lobes_from_principled(0.3, 0.0, F0)
    assert found.lobe == "phong" and found.diffuse and found.weighted
    assert found.label == "Lambert + Phong sigma 61.2"
    assert why == "roughness 0.30 -> Lambert + Phong sigma 61.2"
    assert lobes.principled_weights(0.3, 0.0, F0) == (0.0, F0, 0.3, lobes.LAYER_OVER)
    assert lobes.principled_weights(0.3, 0.0, F0, layer_over=False)[3] == lobes.LAYER_ADDED


def test_partly_metallic_surfaces_have_both_lobes():
    assert lobes.principled_weights(0.8, 0.5, F0) == (0.5, F0, 0.8, lobes.LAYER_OVER)
    assert lobes.lobes_from_principled(0.8, 0.5, F0)[0] == lobes.Lobes("phong", 1.0, True, True)
    assert lobes.principled_weights(0.3, 1.7, F0)[0] == 1.0      # inputs clamped to [0, 1]


def test_a_single_scattering_distribution_negates_the_layer_code():
    # GGX (3.x's default) scatters once; Multiscatter GGX (4.0's) keeps the light it bounces
    assert lobes.principled_weights(0.3, 1.0, F0, multiscatter=False) == (1.0, F0, 0.3, -lobes.LAYER_OVER)
    assert lobes.principled_weights(0.3, 0.0, F0, False, False)[3] == -lobes.LAYER_ADDED
    assert lobes.principled_weights(0.9, 0.0, 0.0, multiscatter=False) == lobes.DIFFUSE_ONLY
    assert lobes.rough_layer(lobes.principled_weights(0.5, 0.0, F0, multiscatter=False))
    grey = (0.5, 0.5, 0.5)
    for layer_over in (True, False):
        assert lobes.reflected(grey, lobes.principled_weights(0.3, 0.0, F0, layer_over, False)) == \
            pytest.approx(lobes.reflected(grey, lobes.principled_weights(0.3, 0.0, F0, layer_over)))


def test_reflected_light_per_lobe():
    grey = (0.5, 0.5, 0.5)
    assert lobes.reflected(grey, lobes.DIFFUSE_ONLY) == pytest.approx((0.0, 0.5))
    assert lobes.reflected(grey, lobes.principled_weights(0.3, 0.0, F0)) == pytest.approx((F0, 0.96 * 0.5))
    assert lobes.reflected(grey, lobes.principled_weights(0.3, 0.0, F0, layer_over=False)) == \
        pytest.approx((F0, 0.5))
    assert lobes.reflected(grey, lobes.principled_weights(0.3, 1.0, F0)) == pytest.approx((0.5, 0.0))
    assert lobes.reflected((1.0, 0.0, 0.0), lobes.DIFFUSE_ONLY)[1] == pytest.approx(0.2126)


def test_rough_dielectrics_are_lambert_with_their_specular_layer():
    # Blender's default material (roughness 0.5, F0 0.04): baked as Lambert, its layer lit live
    found, why = lobes.lobes_from_principled(0.5, 0.0, F0)
    assert found == lobes.Lobes("lambert", 1.0, False, True) and found.layer
    assert (why, found.label) == ("rough dielectric -> Lambert + specular layer", "Lambert + specular layer")
    assert lobes.principled_weights(1.0, 0.0, F0) == (0.0, F0, 1.0, lobes.LAYER_OVER)
    assert not lobes.Lobes().layer and not lobes.lobes_from_principled(0.3, 0.0, F0)[0].layer


def test_the_layer_roughness_threshold_is_half():
    assert lobes.lobes_from_principled(0.49, 0.0, F0)[0].lobe == "phong"
    assert lobes.lobes_from_principled(0.5, 0.0, F0)[0].layer
    assert lobes.lobes_from_principled(0.5, 0.01, F0)[0].lobe == "phong"
    assert lobes.rough_layer(lobes.principled_weights(0.5, 0.0, F0))
    assert not any(lobes.rough_layer(lobes.principled_weights(*inputs))
                   for inputs in ((0.49, 0.0, F0), (0.5, 0.01, F0), (0.9, 0.0, 0.0)))


def test_a_bake_record_names_its_lobes():
    assert lobes.Lobes.of_bake({"lobe": "lambert", "exponent": 1.0}) == lobes.Lobes()
    both = lobes.Lobes.of_bake({"lobe": "phong", "exponent": 8.0, "diffuse_lobe": 1, "lobe_weights": 1})
    assert both == lobes.Lobes("phong", 8.0, True, True)
    assert both.shaded() == [("phong", 8.0), ("lambert", 1.0)]
    assert lobes.Lobes("phong", 8.0).shaded() == [("phong", 8.0)]


def test_horizon_factors_are_the_half_space_step():
    # h_l = 1/2 integral_0^1 P_l, by the trapezoid rule on the Legendre polynomials
    import numpy as np
    from numpy.polynomial import legendre
    t = np.linspace(0.0, 1.0, 20001)
    for l, h in enumerate(lobes.horizon_factors(9)):
        values = legendre.legval(t, np.eye(10)[l])
        assert h == pytest.approx(0.5 * np.sum((values[1:] + values[:-1]) / 2) * (t[1] - t[0]), abs=1e-8)


@pytest.mark.parametrize("exponent, angle", [(8.0, 0.0), (8.0, 1.2), (30.0, 1.45), (1.0, 0.7)])
def test_horizon_share_of_a_lobe_by_funk_hecke(sdnative, exponent, angle):
    """sum_l (2l+1) h_l w_l P_l(a.n) is the share of a Phong lobe around a above the plane of n:
    against a quadrature of the lobe over the sphere."""
    import numpy as np
    from numpy.polynomial import legendre
    order = 40
    w = np.asarray(sdnative.zonal_coefficients("phong", exponent, order))
    series = legendre.legval(np.cos(angle), (2 * np.arange(order + 1) + 1) * lobes.horizon_factors(order) * w)
    # the lobe (2 sigma + 2) max(0, a.x)^sigma over dmu = dx / 4 pi, a tilted by `angle` from n = z
    theta = (np.arange(800) + 0.5) * np.pi / 800
    phi = (np.arange(1600) + 0.5) * 2 * np.pi / 1600
    st, ph = np.meshgrid(theta, phi, indexing="ij")
    x = np.stack([np.sin(st) * np.cos(ph), np.sin(st) * np.sin(ph), np.cos(st)], axis=-1)
    a = np.array([np.sin(angle), 0.0, np.cos(angle)])
    lobe = (2 * exponent + 2) * np.maximum(x @ a, 0.0) ** exponent
    weights = np.sin(st) * (np.pi / 800) * (2 * np.pi / 1600) / (4 * np.pi)
    share = np.sum(lobe * weights * (x[..., 2] > 0.0)) / np.sum(lobe * weights)
    assert series == pytest.approx(share, abs=5e-3)


def test_average_albedo_is_the_cosine_weighted_mean_over_n_dot_v():
    size = 32
    mu = (np.arange(size) + 0.5) / size
    table = np.zeros((3, size, 2))
    table[0] = 0.5                                # A + B = 1: all the light at every angle
    table[1, :, 0] = mu                           # A + B = mu: 2 int mu^2 = 2/3
    table[2, :, 1] = 0.25                         # B alone counts as A does: a constant 0.25
    assert lobes.average_albedo(table) == pytest.approx([1.0, 2.0 / 3.0, 0.25], abs=2e-4)
