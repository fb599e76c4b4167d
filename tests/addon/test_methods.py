"""The method table against sdnative (bake_transfer, shade) and the GLSL."""

import re

import numpy as np
import pytest

from sd_lighting import methods
from sd_lighting.store import bake_data


def uv_sphere(rings=6, segments=10):
    """A closed unit sphere (GROUND, below it, shadows its underside)."""
    vertices = [(0.0, 0.0, 1.0)]
    for i in range(1, rings):
        theta = np.pi * i / rings
        for j in range(segments):
            phi = 2 * np.pi * j / segments
            vertices.append((np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)))
    vertices.append((0.0, 0.0, -1.0))
    ring = lambda i, j: 1 + i * segments + j % segments  # noqa: E731
    triangles = [(0, ring(0, j), ring(0, j + 1)) for j in range(segments)]
    for i in range(rings - 2):
        for j in range(segments):
            triangles += [(ring(i, j), ring(i + 1, j), ring(i, j + 1)),
                          (ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1))]
    triangles += [(ring(rings - 2, j), len(vertices) - 1, ring(rings - 2, j + 1)) for j in range(segments)]
    vertices = np.array(vertices)
    return vertices, vertices.copy(), np.array(triangles, dtype=np.int32)


GROUND = (np.array([[-3, -3, -1.1], [3, -3, -1.1], [3, 3, -1.1], [-3, 3, -1.1]], dtype=np.float64),
          np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32))


def test_ids_labels_and_enum():
    ids = [m.id for m in methods.METHODS]
    assert len(set(ids)) == len(ids) == 7
    assert len({m.label for m in methods.METHODS}) == len({m.short_label for m in methods.METHODS}) == 7
    assert all(methods.get(m.equal_to).equal_to is None for m in methods.METHODS if m.equal_to)
    assert {m.baked_kind for m in methods.METHODS} == {a.name for a in bake_data.ARRAYS}
    assert [item[0] for item in methods.enum_items()] == ids
    assert methods.get("prt_diffuse").lambert_only
    assert [m.id for m in methods.METHODS if m.lambert_only] == ["prt_diffuse"]
    with pytest.raises(KeyError):
        methods.get("prt_nonexistent")


def test_orders_the_shader_is_specialised_on():
    s, sv = 4, 2
    basis = {m.id: (m.basis_order(s, sv, False), m.basis_order(s, sv, True)) for m in methods.METHODS}
    assert basis == {"msd_visibility": (4, -1), "msd_lobe": (4, 2), "prt_gaunt": (6, 6),
                     "prt_matrix": (2, 2), "prt_diffuse": (-1, -1), "ambient_occlusion": (4, 4),
                     "unshadowed": (4, 4)}
    lobe = {m.id: m.lobe_order(s, sv) for m in methods.METHODS}
    assert lobe == {"msd_visibility": 2, "msd_lobe": 0, "prt_gaunt": 6, "prt_matrix": 2,
                    "prt_diffuse": 0, "ambient_occlusion": 4, "unshadowed": 4}


def test_every_method_has_its_glsl_branch_and_no_other(glsl_source):
    in_glsl = set(re.findall(r"SD_METHOD_([A-Z_]*[A-Z])", glsl_source))
    assert in_glsl == {m.id.upper() for m in methods.METHODS}


def as_stored(array, result, s, sv):
    """A bake result's array as the mesh stores it (float32; store/attributes.py), read back."""
    if array.packing == "design":
        offsets, nodes, weights = (result[key] for key in array.keys)
        return dict(zip(array.keys, (np.asarray(offsets), np.float32(nodes).astype(np.float64),
                                     np.float32(weights).astype(np.float64))))
    return array.from_groups(array.groups(result), s, sv)


@pytest.mark.parametrize("method", methods.METHODS, ids=lambda m: m.id)
def test_bake_store_and_shade_with_the_tables_inputs(method, sdnative):
    """The table's bake request gives what its shade inputs need; stored (float32) and read back, sdnative.shade gives what it gives for the bake's arrays rounded to float32."""
    s, sv = 3, 2
    vertices, normals, triangles = uv_sphere()
    result = dict(sdnative.bake_transfer(vertices, normals, triangles, rays=128, seed=1,
                                         occluder_vertices=GROUND[0], occluder_triangles=GROUND[1],
                                         **method.bake_arguments(s, sv)))
    stored = {"visibility_order": sv}
    if method.data is not None:
        stored.update(as_stored(method.data, result, s, sv))
    inputs = {key: stored[key] for key in method.shade_inputs}
    light = np.random.default_rng(2).uniform(0.1, 1.0, size=((s + 1) ** 2, 3))
    views = normals @ np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    lobe = {"lobe": "lambert"} if method.lambert_only else {"lobe": "phong", "exponent": 8.0}
    shaded = sdnative.shade(method.id, light, normals, views=views, **lobe, **inputs)
    assert shaded.shape == (len(vertices), 3) and np.isfinite(shaded).all()

    rounded = {key: (np.asarray(result[key], dtype=np.float32).astype(np.float64)
                     if key in result and key != "design_offsets" else stored[key])
               for key in method.shade_inputs}
    direct = sdnative.shade(method.id, light, normals, views=views, **lobe, **rounded)
    assert np.allclose(shaded, direct, rtol=1e-12, atol=1e-12)
    for key in (method.data.keys if method.data else ()):
        without = {k: v for k, v in inputs.items() if k != key}
        with pytest.raises(ValueError):
            sdnative.shade(method.id, light, normals, views=views, **lobe, **without)


def test_shadowed_methods_differ_from_unshadowed(sdnative):
    """The bake request really carries the visibility: a ground below darkens the sphere's
    underside in every method that reads V."""
    s, sv = 2, 2
    vertices, normals, triangles = uv_sphere()
    light = np.zeros(((s + 1) ** 2, 3))
    light[0] = 1.0
    unshadowed = sdnative.shade("unshadowed", light, normals)
    for method in methods.METHODS:
        if method.data is None:
            continue
        result = dict(sdnative.bake_transfer(vertices, normals, triangles, rays=256, seed=1,
                                             occluder_vertices=GROUND[0],
                                             occluder_triangles=GROUND[1],
                                             **method.bake_arguments(s, sv)))
        inputs = {"visibility_order": sv}
        inputs.update(as_stored(method.data, result, s, sv))
        shaded = sdnative.shade(method.id, light, normals,
                                **{key: inputs[key] for key in method.shade_inputs})
        bottom = normals[:, 2] < -0.9
        assert shaded[bottom].mean() < 0.8 * unshadowed[bottom].mean(), method.id
