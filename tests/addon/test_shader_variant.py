"""Shader variants: defines, samplers and the uniform block (std140) against the GLSL."""

import dataclasses
import itertools
import re

import numpy as np
import pytest

from sd_lighting import methods
from sd_lighting.bake import lightmap
from sd_lighting.live import band_limited_map
from sd_lighting.live.shader_variant import BlockField, Variant


def all_variants():
    for method in methods.METHODS:
        for lobes, per_pixel, target, texture, albedo in itertools.product(
                ("lambert", "layer", "phong", "metal", "both"), (False, True), (False, True), (False, True),
                (False, True)):
            if texture and not method.band_limited_texture:
                continue
            both = lobes == "both"
            if lobes not in ("lambert", "layer") and method.lambert_only:
                continue
            weights = lobes in ("layer", "metal", "both")
            for texels, prefiltered, sources in itertools.product(
                    (False, True) if per_pixel and lightmap.applies(method) else (False,),
                    (True,) if lobes == "layer" else (False, True) if weights else (False,),
                    (0, 2) if not target else (0,)):
                if sources and lobes not in ("lambert", "layer") and not (prefiltered and albedo):
                    continue   # a glossy lobe takes the sources where the prefiltered atlas lights it
                # a glossy lobe or a specular layer lit by the prefiltered atlas traces its visibility
                rays = 16 if lobes != "lambert" and prefiltered and albedo and not target else 0
                yield Variant(method, lobes not in ("lambert", "layer"), 4, 2, 0 if method.data is None else 3,
                              18 if method.lobe_design else 0, 77 if method.gaunt_table else 0,
                              per_pixel, target,
                              band_limited_map.texture_size(4) if texture else (),
                              material_count=2 if albedo else 0, material_slots=albedo,
                              albedo_texture=albedo, lobe_weights=weights,
                              diffuse_lobe=both,
                              diffuse_design_size=12 if both and method.lobe_design else 0,
                              lightmap=(64, 32) if texels else (), prefiltered=(1024, 7) if prefiltered else (),
                              sources=sources, reflection_rays=rays)


def test_defines_of_a_known_variant(sdnative):
    variant = Variant(methods.get("prt_gaunt"), True, 4, 2, data_stride=3, gaunt_count=77,
                      per_pixel=True)
    defines = variant.defines(sdnative.sh_recurrence_constants)
    assert defines.pop("SD_SH_DIAGONAL").split(", ")[:3] == [
        "1.000000000e+00", "1.732050808e+00", "1.936491673e+00"]
    a = defines.pop("SD_SH_A").split(", ")        # at l (l + 1) / 2 + m
    assert (a[1], a[3], a[4]) == ("1.732050808e+00", "1.936491673e+00", "2.236067977e+00")
    assert defines.pop("SD_SH_B").split(", ")[3] == "1.118033989e+00"   # b_20
    assert defines == {
        "SD_METHOD_PRT_GAUNT": "1", "SD_LIGHT_COUNT": "25", "SD_VIS_ORDER": "2",
        "SD_VIS_COUNT": "9", "SD_LOBE_VEC4S": "2", "SD_DATA_STRIDE": "3",
        "SD_TEXTURE_WIDTH_LOG2": "12", "SD_BASIS_ORDER": "6", "SD_BASIS_COUNT": "49",
        "SD_SH_TABLE_SIZE": "28", "SD_GLOSSY": "1", "SD_GAUNT_COUNT": "77", "SD_PER_PIXEL": "1"}
    assert variant.samplers() == [(0, "sd_data"), (1, "sd_gaunt")]


def test_texture_space_variant_reads_the_lightmap_uv_per_pixel(sdnative):
    variant = Variant(methods.get("prt_diffuse"), False, 2, 0, data_stride=3, per_pixel=True,
                      lightmap=(512, 256))
    defines = variant.defines(sdnative.sh_recurrence_constants)
    assert (defines["SD_LIGHTMAP"], defines["SD_LIGHTMAP_WIDTH"], defines["SD_LIGHTMAP_HEIGHT"]) == ("1", "512", "256")
    assert variant.vertex_inputs() == [("vec3", "pos"), ("vec3", "nrm"), ("vec2", "lightmap_uv")]
    assert ("smooth", "vec2", "sd_lightmap_uv") in variant.interface()
    assert not any(name in ("sd_bary", "sd_corners") for _, _, name in variant.interface())
    with pytest.raises(ValueError, match="per pixel"):
        Variant(methods.get("prt_diffuse"), False, 2, 0, data_stride=3, lightmap=(512, 256))


def test_band_limited_texture_variant(sdnative):
    variant = Variant(methods.get("msd_visibility"), False, 8, 2, data_stride=20,
                      band_limited_texture=band_limited_map.texture_size(8))
    defines = variant.defines(sdnative.sh_recurrence_constants)
    assert "SD_BASIS_ORDER" not in defines           # L~ from the texture: no SH basis at all
    cells = band_limited_map.side(8) + 1
    assert defines["SD_BAND_LIMITED_CELLS"] == str(cells) and "SD_EQUIRECT_MAP" not in defines
    assert variant.samplers() == [(0, "sd_data"), (2, "sd_band_limited_texture")]
    assert band_limited_map.texture_size(8) == (2 * cells, 6 * cells)


def test_every_define_and_field_is_one_the_glsl_uses_and_vice_versa(glsl_source, sdnative):
    source = glsl_source
    produced, fields, samplers, equirect_maps = set(), set(), set(), set()
    for variant in all_variants():
        defines = variant.defines(sdnative.sh_recurrence_constants)
        produced |= set(defines)
        equirect_maps |= {defines.get("SD_EQUIRECT_MAP"), defines.get("SD_PREFILTERED_MAP")}
        fields |= {f.name for f in variant.frame_fields()}
        samplers |= {name for _, name in variant.samplers()}
    defined_in_glsl = set(re.findall(r"#\s*define\s+(SD_[A-Z0-9_]+)", source))
    used = set(re.findall(r"\b(SD_[A-Z0-9_]*[A-Z0-9])\b", source)) - defined_in_glsl
    assert used == produced | {"SD_EQUIRECT_MAP"}    # that one the background shader's
    assert set(re.findall(r"\bsd\.([a-z_]+)", source)) == fields
    glsl_samplers = set(re.findall(r"(?:texelFetch|texture)\((sd_[a-z_]+)", source))
    # sd_equirect.glsl reads the maps they name
    assert "texelFetch(SD_EQUIRECT_MAP" in source and "texelFetch(SD_PREFILTERED_MAP" in source
    assert glsl_samplers | (equirect_maps - {None}) == samplers


def test_albedo_variants_read_only_what_the_materials_need(sdnative):
    unshadowed = methods.get("unshadowed")
    white = Variant(unshadowed, False, 1, 0)
    flat = Variant(unshadowed, False, 1, 0, material_count=1)
    textured = Variant(unshadowed, False, 1, 0, material_count=3, material_slots=True,
                       albedo_texture=True)
    assert not any(name.startswith("SD_ALBEDO") for name in white.defines(sdnative.sh_recurrence_constants))
    assert "albedo" not in [f.name for f in white.frame_fields()]
    defines = flat.defines(sdnative.sh_recurrence_constants)
    assert defines["SD_ALBEDO"] == "1"
    assert "SD_MATERIAL_SLOTS" not in defines and "SD_ALBEDO_TEXTURE" not in defines
    assert [n for _, n in flat.vertex_inputs()] == ["pos", "nrm"]
    assert ("flat", "vec4", "sd_albedo") in flat.interface()
    assert [n for _, n in textured.vertex_inputs()] == ["pos", "nrm", "material_slot", "uv"]
    assert textured.samplers() == [(3, "sd_albedo_texture")]
    assert [f for f in textured.frame_fields() if f.name == "albedo"][0].length == 3


def test_a_lambert_lobe_besides_the_phong_one(sdnative):
    """Two lobes: the Lambert lobe's factors and design follow the Phong lobe's in the block, the
    vertex stage passes its B and n.v on, and each slot has its lobe weights; the vertex target
    reads no weights."""
    msd_lobe = methods.get("msd_lobe")
    one = Variant(msd_lobe, True, 4, 2, 3, lobe_design_size=18, material_count=2, material_slots=True)
    two = dataclasses.replace(one, lobe_weights=True, diffuse_lobe=True, diffuse_design_size=12)
    defines = two.defines(sdnative.sh_recurrence_constants)
    assert defines["SD_DIFFUSE_LOBE"] == "1" and defines["SD_DIFFUSE_DESIGN_SIZE"] == "12"
    assert defines["SD_LOBE_WEIGHTS"] == "1"
    assert not {"SD_DIFFUSE_LOBE", "SD_LOBE_WEIGHTS"} & set(one.defines(sdnative.sh_recurrence_constants))
    rows = {f.name: f.rows for f in two.frame_fields()}
    assert rows["lobe"] == 2 * {f.name: f.rows for f in one.frame_fields()}["lobe"]
    assert rows["design"] == 30 and rows["lobe_weights"] == 2
    assert "lobe_weights" not in [f.name for f in one.frame_fields()]
    assert [m for _, _, m in two.interface()] == ["sd_color", "sd_diffuse_color", "sd_n_dot_v",
                                                  "sd_albedo", "sd_lobe_weights"]
    per_pixel = dataclasses.replace(two, per_pixel=True)
    assert [m for _, _, m in per_pixel.interface()] == ["sd_origin_offset", "sd_normal", "sd_bary",
                                                        "sd_corners", "sd_albedo", "sd_lobe_weights"]
    target = dataclasses.replace(two, material_count=0, material_slots=False, vertex_target=True)
    assert "SD_LOBE_WEIGHTS" not in target.defines(sdnative.sh_recurrence_constants)
    assert [m for _, _, m in target.interface()] == ["sd_color", "sd_diffuse_color"]
    with pytest.raises(ValueError):
        Variant(msd_lobe, False, 4, 2, 3, lobe_weights=True)
    with pytest.raises(ValueError):
        Variant(msd_lobe, True, 4, 2, 3, diffuse_lobe=True)


def test_every_input_and_interface_member_is_one_the_glsl_reads(glsl_source):
    # The vertex inputs and the stage interface are declared from the variant (gpu_shading and the
    # strict-GLSL test alike): each name must be one the GLSL reads, and per pixel adds the
    # triangle's corners and barycentric coordinates.
    for per_pixel in (False, True):
        variant = Variant(methods.get("prt_diffuse"), False, 2, 0, 3, per_pixel=per_pixel)
        names = [name for _, name in variant.vertex_inputs()] + [name for _, _, name in variant.interface()]
        for name in names:
            assert re.search(r"\b%s\b" % name, glsl_source), name
    assert [n for _, n in Variant(methods.get("unshadowed"), False, 1, 0).vertex_inputs()] == ["pos", "nrm"]
    per_pixel = Variant(methods.get("unshadowed"), False, 1, 0, per_pixel=True)
    assert [n for _, n in per_pixel.vertex_inputs()] == ["pos", "nrm", "corners", "bary"]
    assert ("flat", "vec3", "sd_corners") in per_pixel.interface()


STD140 = {"float": (4, 4), "vec2": (8, 8), "vec3": (16, 12), "vec4": (16, 16), "mat4": (16, 64)}


def std140_offsets(struct_text):
    """Offsets and total size of a GLSL struct by the std140 rules (arrays: element stride rounded
    up to 16; the struct's size rounded up to 16)."""
    offsets, offset = {}, 0
    for glsl_type, name, length in re.findall(r"^\s*(\w+)\s+(\w+)(?:\[(\d+)\])?;", struct_text, re.M):
        align, size = STD140[glsl_type]
        if length:
            align = max(align, 16)
            size = int(length) * (size + (-size) % 16)
        offset += (-offset) % align
        offsets[name] = offset
        offset += size
    return offsets, offset + (-offset) % 16


@pytest.mark.parametrize("variant", list(all_variants()), ids=lambda v: "%s%s%s%s" % (
    v.method.id, "-texture" if v.band_limited_texture else "", "-glossy" if v.glossy else "",
    "-diffuse" if v.diffuse_lobe else ""))
def test_struct_text_and_packing_agree_by_std140(variant):
    offsets, size = std140_offsets(variant.frame_struct())
    rng = np.random.default_rng(0)
    values = {}
    for field in variant.frame_fields():
        values[field.name] = rng.normal(size=(4, 4) if field.glsl_type == "mat4" else (field.rows, 4))
    block = variant.frame_block(values)
    assert block.dtype == np.float32 and 4 * block.size == size
    for field in variant.frame_fields():
        start = offsets[field.name] // 4
        if field.glsl_type == "mat4":       # column-major: column c, row r at 4 c + r
            assert np.array_equal(block[start:start + 16].reshape(4, 4).T,
                                  values[field.name].astype(np.float32))
        else:
            assert np.array_equal(block[start:start + 4 * field.rows],
                                  values[field.name].astype(np.float32).ravel())


def test_packing_pads_rows_and_embeds_rotations():
    field = BlockField("light", "vec4", 2)
    assert field.pack([[1, 2, 3], [4, 5, 6]]).tolist() == [[1, 2, 3, 0], [4, 5, 6, 0]]
    rotation = BlockField("local_to_environment", "mat4").pack(np.arange(9.0).reshape(3, 3))
    assert rotation[:, 3].tolist() == [0, 0, 0, 1] and rotation[0, :3].tolist() == [0, 3, 6]
    with pytest.raises(ValueError):
        BlockField("lights", "mat4", 2)
    with pytest.raises(ValueError):
        BlockField("normal", "vec3")


def test_frame_block_wants_exactly_the_fields():
    variant = Variant(methods.get("unshadowed"), False, 1, 0)
    values = {"model": np.eye(4), "view_projection": np.eye(4), "world_to_local": np.eye(3),
              "camera": (0, 0, 1, 1), "params": (1, 1, 1, 0), "light": np.ones((4, 3)),
              "lobe": np.zeros(4)}
    assert variant.frame_block(values).size == 3 * 16 + 2 * 4 + 4 * 4 + 4
    with pytest.raises(ValueError):
        variant.frame_block(dict(values, design=np.zeros((1, 4))))
    del values["lobe"]
    with pytest.raises(ValueError):
        variant.frame_block(values)


def test_prefiltered_lookup_reads_the_horizon_factors_to_s_prime(sdnative):
    """The visibility ratio's horizon factor has the order of V (s'), whatever s is: a uniform
    world (s = 0) under V = [n.x > 0] gives the lobe truncated at s' over the hemisphere."""
    variant = Variant(methods.get("msd_visibility"), True, 0, 3, data_stride=8, material_count=1,
                      lobe_weights=True, prefiltered=(1024, 7))
    assert variant.prefiltered_lookup and variant.open_order == 0 and variant.horizon_order == 3
    assert variant.lobe_order >= 3 and variant.lobe_count == 2
    defines = variant.defines(sdnative.sh_recurrence_constants)
    assert defines["SD_HORIZON_ORDER"] == "3" and defines["SD_HORIZON_LOBE"] == "1"
    assert "prefiltered_scale" in [f.name for f in variant.frame_fields()]
    unshadowed = Variant(methods.get("unshadowed"), True, 4, 0, material_count=1, lobe_weights=True,
                         prefiltered=(1024, 7))
    assert unshadowed.horizon_order == 0
    assert not dataclasses.replace(variant, material_count=0).prefiltered_lookup   # the vertex target


def test_reflection_rays_variant_casts_the_scenes_count(sdnative):
    """The traced glossy visibility casts the variant's rays per pixel (the scene's Rays), only on
    a glossy lobe or a Lambert lobe's specular layer lit by the prefiltered atlas."""
    variant = Variant(methods.get("unshadowed"), True, 4, 0, material_count=1, lobe_weights=True,
                      prefiltered=(1024, 7), reflection_rays=12)
    defines = variant.defines(sdnative.sh_recurrence_constants)
    assert defines["SD_REFLECTION_RAYS"] == "12"
    assert "SD_REFLECTION_RAYS" not in dataclasses.replace(variant, reflection_rays=0).defines(
        sdnative.sh_recurrence_constants)
    with pytest.raises(ValueError, match="rays per pixel"):
        dataclasses.replace(variant, reflection_rays=-1)
    with pytest.raises(ValueError, match="reflection rays trace"):
        dataclasses.replace(variant, prefiltered=(), lobe_weights=False, material_count=0)
    layer = Variant(methods.get("prt_diffuse"), False, 4, 0, data_stride=7, material_count=1,
                    lobe_weights=True, prefiltered=(1024, 7), reflection_rays=12)
    assert layer.lambert_layer and layer.defines(sdnative.sh_recurrence_constants)["SD_REFLECTION_RAYS"] == "12"


def test_lambert_layer_variant_passes_lobe_0_on_as_the_diffuse(sdnative):
    """A rough dielectric's Lambert lobe with its specular layers (scene/lobes.Lobes.layer)."""
    variant = Variant(methods.get("prt_diffuse"), False, 4, 0, data_stride=7, material_count=1,
                      lobe_weights=True, prefiltered=(1024, 7))
    assert variant.lambert_layer and variant.prefiltered_lookup and variant.lobe_count == 2
    assert variant.defines(sdnative.sh_recurrence_constants)["SD_LAMBERT_LAYER"] == "1"
    assert ("smooth", "vec3", "sd_diffuse_color") in variant.interface()
    per_pixel = dataclasses.replace(variant, per_pixel=True)
    assert per_pixel.defines(sdnative.sh_recurrence_constants)["SD_LAMBERT_LAYER"] == "1"
    assert ("smooth", "vec3", "sd_diffuse_color") not in per_pixel.interface()   # B per pixel
    assert not dataclasses.replace(variant, material_count=0).lambert_layer   # the vertex target: B
    with pytest.raises(ValueError, match="prefiltered light"):
        Variant(methods.get("prt_diffuse"), False, 4, 0, data_stride=7, material_count=1, lobe_weights=True)
    with pytest.raises(ValueError, match="Lambert lobe 1"):
        Variant(methods.get("prt_matrix"), False, 4, 2, data_stride=7, material_count=1, lobe_weights=True,
                diffuse_lobe=True, prefiltered=(1024, 7))
