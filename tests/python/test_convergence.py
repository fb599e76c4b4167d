"""Every method against the reference (eq. 1 by Monte Carlo) on a real HDRI and a shadowed scene.

A ground plane with a box standing over its centre, lit by a Blender-shipped HDRI: the methods
that carry visibility (PRT (2), (8)-(9), (10), MSD (12), (13)) converge to the reference as s, s'
and the rays grow; the ones that do not (unshadowed, ambient occlusion) stay far off, which is why
the scene calls for visibility. On the same real data, MSD equals PRT exactly: (12) = (10) and
(13) = (8)-(9).
"""
import os

import numpy as np
import pytest

HDRI = "/usr/share/blender/datafiles/studiolights/world/sunset.exr"
LEVELS = [(2, 1, 256), (4, 2, 1024), (6, 3, 2048)]  # (s, s', rays)


def plane_under_a_box(n=8):
    xs = np.linspace(-1.0, 1.0, n)
    x, y = np.meshgrid(xs, xs)
    vertices = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)
    triangles = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            triangles += [[a, a + 1, a + n + 1], [a, a + n + 1, a + n]]
    corners = np.array([[x, y, z] for x in (-0.4, 0.4) for y in (-0.4, 0.4) for z in (0.1, 0.9)])
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return vertices, np.tile([0.0, 0.0, 1.0], (n * n, 1)), np.array(triangles), corners, faces


def relative_rms(estimate, reference):
    return float(np.sqrt(((estimate - reference) ** 2).mean() / (reference ** 2).mean()))


@pytest.fixture(scope="module")
def scene(sd):
    if not os.path.exists(HDRI):
        pytest.fail(f"{HDRI} is missing: install Debian's blender package (scripts/install_dependencies.sh)")
    environment = sd.load_environment(HDRI)
    vertices, normals, triangles, occluder_vertices, occluder_triangles = plane_under_a_box()
    eye = np.array([3.0, -2.0, 2.5])
    views = eye - vertices
    views /= np.linalg.norm(views, axis=1, keepdims=True)
    return dict(environment=environment, vertices=vertices, normals=normals, triangles=triangles, views=views,
                occluder_vertices=occluder_vertices, occluder_triangles=occluder_triangles)


def all_methods(sd, scene, lobe, exponent, s, s_v, rays):
    bake = sd.bake_transfer(scene["vertices"], scene["normals"], scene["triangles"], rays, seed=1,
                            visibility_order=s_v, product_orders=(s, s_v), transfer_order=s, design_orders=(s, s_v),
                            occluder_vertices=scene["occluder_vertices"],
                            occluder_triangles=scene["occluder_triangles"])
    common = dict(light=scene["environment"].sh(s), normals=scene["normals"], views=scene["views"], lobe=lobe,
                  exponent=exponent)
    out = {
        "unshadowed": sd.shade("unshadowed", **common),
        "ambient_occlusion": sd.shade("ambient_occlusion", ambient_occlusion=bake["ambient_occlusion"], **common),
        "prt_matrix": sd.shade("prt_matrix", product_matrices=bake["product_matrices"], **common),
        "prt_gaunt": sd.shade("prt_gaunt", visibility=bake["visibility"], **common),
        "msd_lobe": sd.shade("msd_lobe", visibility=bake["visibility"], **common),
        "msd_visibility": sd.shade("msd_visibility", visibility_order=s_v, design_offsets=bake["design_offsets"],
                                   design_nodes=bake["design_nodes"], design_weights=bake["design_weights"],
                                   **common),
    }
    if lobe == "lambert":
        out["prt_diffuse"] = sd.shade("prt_diffuse", transfer=bake["transfer"], **common)
    return out


@pytest.mark.parametrize("lobe,exponent,final_error", [("lambert", 1.0, 0.05), ("phong", 8.0, 0.2)])
def test_methods_with_visibility_converge_to_the_reference(sd, scene, lobe, exponent, final_error):
    reference, standard_error = sd.reference(
        scene["environment"], scene["vertices"], scene["normals"], scene["triangles"], views=scene["views"],
        lobe=lobe, exponent=exponent, samples=8192, occluder_vertices=scene["occluder_vertices"],
        occluder_triangles=scene["occluder_triangles"])
    assert relative_rms(reference + standard_error, reference) < 0.02, "the reference itself is not converged"
    errors = []
    for s, s_v, rays in LEVELS:
        out = all_methods(sd, scene, lobe, exponent, s, s_v, rays)
        # MSD is PRT computed another way: equal on real data, not only on random data.
        for msd, prt in (("msd_lobe", "prt_gaunt"), ("msd_visibility", "prt_matrix")):
            np.testing.assert_allclose(out[msd], out[prt], rtol=0, atol=1e-9 * np.abs(out[prt]).max())
        errors.append({name: relative_rms(value, reference) for name, value in out.items()})
    print(lobe, errors)
    for name in errors[0]:
        first, last = errors[0][name], errors[-1][name]
        if name in ("unshadowed", "ambient_occlusion"):
            assert last > 0.3, f"{name} should miss the box's shadow (error {last:.3f})"
        else:
            assert last < first, f"{name} does not converge: {first:.4f} -> {last:.4f}"
            assert last < final_error, f"{name} ends {last:.4f} from the reference"
