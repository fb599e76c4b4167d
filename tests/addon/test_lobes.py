"""Roughness -> Phong sigma and the Lambert/Phong decision of a Principled BSDF."""

import pytest

from sd_lighting.utils import lobes


@pytest.mark.parametrize("roughness, sigma", [(0.5, 7.5), (0.3, 61.228395), (0.2, 312.0),
                                              (0.7, 1.5824656), (0.9, 1.0), (0.05, 1000.0),
                                              (0.0, 1000.0)])
def test_exponent_from_roughness(roughness, sigma):
    assert lobes.exponent_from_roughness(roughness) == pytest.approx(sigma, rel=1e-4)


def test_rough_dielectrics_are_lambert():
    assert lobes.lobe_from_principled(0.5, 0.0)[0] == ("lambert", 1.0)
    assert lobes.lobe_from_principled(0.9, 0.49)[0] == ("lambert", 1.0)


def test_smooth_or_metallic_is_phong():
    (name, sigma), why = lobes.lobe_from_principled(0.3, 0.0)
    assert name == "phong" and sigma == pytest.approx(61.228395, rel=1e-6)
    assert why == "roughness 0.30 -> Phong sigma 61.2"
    assert lobes.lobe_from_principled(0.8, 0.5)[0] == ("phong", 1.0)


def test_the_thresholds_are_half():
    assert lobes.lobe_from_principled(0.49, 0.0)[0][0] == "phong"
    assert lobes.lobe_from_principled(0.5, 0.5)[0][0] == "phong"
