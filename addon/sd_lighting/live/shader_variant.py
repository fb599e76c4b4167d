"""Shader variants: what the one GLSL program (shaders/sd_shading_*.glsl) is specialised on for an
object's bake - its #defines, samplers and uniform block - so an object pays only for its effects.

The uniform block `sd` (struct SdFrameData, std140) is described once, by `Variant.frame_fields`:
the GLSL struct text and the packing of a frame's values are both generated from that list. Its
fields are vec4s, mat4s and arrays of them only: in std140 those have base alignment 16 and sizes
that are multiples of 16, so the block is the fields' floats back to back, matrices column-major.
"""

from dataclasses import dataclass

import numpy as np

from .. import methods, native
from ..scene.light_sources import HIGHLIGHT_POINTS, SHADOW_MAP_SIZE, SOURCE_ROWS
from ..scene.lobes import DIELECTRIC_SHAPE_IOR
from ..store.bake_data import TEXTURE_WIDTH_LOG2


# (slot, name) of the shader's samplers
DATA_SAMPLER = (0, "sd_data")                               # per-vertex texels
GAUNT_SAMPLER = (1, "sd_gaunt")                             # (a, b, c, G) of eq. (10)
BAND_LIMITED_TEXTURE_SAMPLER = (2, "sd_band_limited_texture")  # L~ on cube faces (band_limited_map.py)
ALBEDO_TEXTURE_SAMPLER = (3, "sd_albedo_texture")           # the material's image texture
LIGHTMAP_INDEX_SAMPLER = (4, "sd_lightmap_index")           # each lightmap texel's data row, or -1
PREFILTERED_SAMPLER = (5, "sd_prefiltered")                 # the environment prefiltered per roughness
BRDF_TABLE_SAMPLER = (6, "sd_environment_brdf_table")       # the GGX lobe's tables over n.v, roughness
BRDF_TABLE_SIZE = 32   # each table's side (sdnative.environment_brdf_table, glossy_bend_table)
SHADOW_MAP_SAMPLER = (7, "sd_shadow_map")                   # the sources' shadow maps, side by side
RAY_BVH_SAMPLER = (8, "sd_ray_bvh")                         # the scene's triangles (live/ray_bvh.py)
# The glossy light is sampled by GLOSSY_TAPS directions of its lobe instead of one prefiltered
# lookup (sd_sampled_glossy_light) where the view grazes, n.v below SAMPLED_N_DOT_V (wholly from
# 0.1 below it down), and on a metal from SAMPLED_ROUGHNESS on (over the 0.1 below): where the
# lobe stretches away from the round lobe one lookup reads (msd-notes, "Glossy light", measures both).
SAMPLED_ROUGHNESS = 0.3
SAMPLED_N_DOT_V = 0.6
GLOSSY_TAPS = 128
# The traced visibility of a glossy lobe or a Lambert lobe's specular layer (reflection_rays;
# sd_traced_visibility): rays per pixel by default, and the counts the scene's reflection_ray_count
# offers (each its own program, so a few), drawn as the taps are; below SINGLE_RAY_ROUGHNESS one,
# along the lobe's axis (a lobe under a degree or two wide). Fewer leave a rough lobe's partial
# visibility coarser: a grain over 4 x 4 pixels, whose rays interleave (msd-notes, "Reflection rays").
REFLECTION_RAYS = 32
RAY_COUNTS = (8, 16, 32, 64)
SINGLE_RAY_ROUGHNESS = 0.1



def glsl_floats(values):
    """A GLSL initializer list of float literals (explicit exponents: Metal-safe)."""
    return ", ".join("%.9e" % v for v in values)


@dataclass(frozen=True)
class BlockField:
    """One member of the uniform block: a mat4, a vec4 or an array of `length` vec4s."""
    name: str
    glsl_type: str
    length: int = 0     # 0: not an array

    def __post_init__(self):
        if self.glsl_type not in ("vec4", "mat4") or (self.glsl_type == "mat4" and self.length):
            raise ValueError("the block holds vec4s, vec4 arrays and mat4s only (std140 without "
                             "padding)")

    @property
    def rows(self):
        """vec4s (a mat4: its four columns) the field spans."""
        return 4 if self.glsl_type == "mat4" else max(self.length, 1)

    def declaration(self):
        return "  %s %s%s;" % (self.glsl_type, self.name, "[%d]" % self.length if self.length else "")

    def pack(self, value):
        """The field's float64 [rows, 4] from a value: a mat4 from a row-major 4x4 (or a 3x3
        rotation, embedded in the identity), written column-major; a vec4 (array) from rows of
        1-4 components, zero padded."""
        value = np.asarray(value, dtype=np.float64)
        if self.glsl_type == "mat4":
            matrix = np.eye(4)
            if value.shape not in ((3, 3), (4, 4)):
                raise ValueError("%s: a 3x3 or 4x4 matrix, got shape %s" % (self.name, value.shape))
            matrix[:value.shape[0], :value.shape[1]] = value
            return matrix.T.copy()
        rows = value.reshape(max(self.length, 1), -1)
        if rows.shape[1] > 4:
            raise ValueError("%s: rows of at most 4 components, got %d" % (self.name, rows.shape[1]))
        out = np.zeros((len(rows), 4))
        out[:, :rows.shape[1]] = rows
        return out


@dataclass(frozen=True)
class Variant:
    """Everything the shader is specialised on."""
    method: methods.Method
    glossy: bool                  # lobe 0 is Phong (else Lambert)
    light_order: int
    visibility_order: int
    data_stride: int = 0          # texels per vertex in the data texture (0: none)
    lobe_design_size: int = 0     # nodes of the lobe design (methods with lobe_design)
    gaunt_count: int = 0          # real Gaunt coefficients (methods with gaunt_table)
    per_pixel: bool = False
    vertex_target: bool = False   # tests: vertex p drawn as pixel p of a float target
    band_limited_texture: tuple = ()   # (width, height) of L~'s cell texture, or () for the SH sum
    material_count: int = 0       # albedos in the block, one per material slot (0: white, none)
    material_slots: bool = False  # the vertices carry their slot (objects with several)
    albedo_texture: bool = False  # a slot's albedo is an image texture, read through `uv`
    lobe_weights: bool = False    # the slots' Principled weights colour the Phong lobe 0 (glossy),
                                  # or add the specular layers of a Lambert lobe 0 (prefiltered)
    diffuse_lobe: bool = False    # a Lambert lobe 1 besides it (lobe_weights)
    diffuse_design_size: int = 0  # nodes of lobe 1's design (methods with lobe_design)
    lightmap: tuple = ()          # (width, height) of texture-space data (per pixel), or ()
    prefiltered: tuple = ()       # (width0, levels) of the prefiltered atlas lobe 0's light is
                                  # looked up in (drawn with weights), or () for its SH result
    sources: int = 0              # the map's bright sources lighting the lobes on their own,
                                  # shadowed per pixel (scene/light_sources.py); L is the rest
    reflection_rays: int = 0      # rays per pixel tracing the glossy lobe's or the specular
                                  # layer's visibility (live/ray_bvh.py), or 0

    def __post_init__(self):
        if (self.lobe_weights and not (self.glossy or self.prefiltered)) or \
                (self.diffuse_lobe and not (self.lobe_weights and self.glossy)):
            raise ValueError("lobe weights go with a Phong lobe 0 or with the prefiltered light of a "
                             "Lambert lobe's specular layers; a Lambert lobe 1 with a weighted Phong lobe 0")
        if self.prefiltered and not self.lobe_weights:
            raise ValueError("the prefiltered glossy light needs the slots' lobe weights (roughness)")
        if self.lightmap and not self.per_pixel:
            raise ValueError("texture-space data are read per pixel")
        if self.sources and (self.vertex_target or (self.glossy and not self.prefiltered_lookup)):
            raise ValueError("the bright sources light a Lambert lobe 0, or a glossy one lit by the "
                             "prefiltered atlas, in a drawn image")
        if self.reflection_rays < 0:
            raise ValueError("reflection rays per pixel must be 0 (none) or more")
        if self.reflection_rays and not self.prefiltered_lookup:
            raise ValueError("reflection rays trace a glossy lobe, or a Lambert lobe's specular layer, "
                             "lit by the prefiltered atlas")

    @property
    def weighted(self):
        """Whether the drawn colour reads the slots' lobe weights (not the vertex target's)."""
        return self.lobe_weights and self.material_count > 0

    @property
    def prefiltered_lookup(self):
        """Whether lobe 0's light is looked up in the prefiltered atlas (where weights are drawn)."""
        return bool(self.prefiltered) and self.weighted

    @property
    def lambert_layer(self):
        """Whether lobe 0 is Lambert and the slots' specular layers are lit by the prefiltered
        light, shadowed by its visibility ratio (scene/lobes.Lobes.layer)."""
        return self.prefiltered_lookup and not self.glossy

    @property
    def open_order(self):
        """The order of lobe 0's unshadowed sum its visibility ratio divides by (prefiltered_lookup)."""
        return self.method.open_order(self.light_order, self.visibility_order)

    @property
    def horizon_order(self):
        """The order of the horizon factor of the visibility ratio: what the method's B has of
        the surface's own hemisphere (methods with V~, M or a design of V: s', whatever s is - in a
        uniform world their B under V = [n.x > 0] is the lobe truncated at s' over the hemisphere;
        the others see no horizon: order 0, factor 1)."""
        return self.visibility_order if self.method.uses_visibility_order else 0

    @property
    def shaded_lobes(self):
        """Lobes whose B the shader evaluates: lobe 0 and the Lambert lobe 1."""
        return 2 if self.diffuse_lobe else 1

    @property
    def lobe_count(self):
        """Rows of factors in the block: the shaded lobes', and the horizon factors with the
        prefiltered lookup (row shaded_lobes)."""
        return self.shaded_lobes + (1 if self.prefiltered_lookup else 0)

    @property
    def basis_order(self):
        order = self.method.basis_order(self.light_order, self.visibility_order, bool(self.band_limited_texture))
        return max(order, self.open_order) if self.prefiltered_lookup else order

    @property
    def lobe_order(self):
        """Highest l whose Funk-Hecke factor the shader reads."""
        order = self.method.lobe_order(self.light_order, self.visibility_order)
        return max(order, self.open_order, self.horizon_order) if self.prefiltered_lookup else order

    @property
    def lobe_vec4s(self):
        return self.lobe_order // 4 + 1

    def defines(self, sh_recurrence_constants):
        """The #defines (name -> text). sh_recurrence_constants(order) gives the SH recurrences'
        float64 tables {"diagonal", "a", "b"} (sdnative.sh_recurrence_constants)."""
        s, sv = self.light_order, self.visibility_order
        d = {"SD_METHOD_" + self.method.id.upper(): "1",
             "SD_LIGHT_COUNT": str((s + 1) ** 2),
             "SD_VIS_ORDER": str(sv),
             "SD_VIS_COUNT": str((sv + 1) ** 2),
             "SD_LOBE_VEC4S": str(self.lobe_vec4s),
             "SD_DATA_STRIDE": str(self.data_stride),
             "SD_TEXTURE_WIDTH_LOG2": str(TEXTURE_WIDTH_LOG2)}
        if self.basis_order >= 0:
            tables = sh_recurrence_constants(self.basis_order)
            d["SD_BASIS_ORDER"] = str(self.basis_order)
            d["SD_BASIS_COUNT"] = str((self.basis_order + 1) ** 2)
            d["SD_SH_DIAGONAL"] = glsl_floats(tables["diagonal"])
            d["SD_SH_A"] = glsl_floats(tables["a"])
            d["SD_SH_B"] = glsl_floats(tables["b"])
            d["SD_SH_TABLE_SIZE"] = str(len(tables["a"]))
        if self.glossy:
            d["SD_GLOSSY"] = "1"
        if self.diffuse_lobe:
            d["SD_DIFFUSE_LOBE"] = "1"
        if self.method.lobe_design:
            d["SD_LOBE_DESIGN_SIZE"] = str(self.lobe_design_size)
            if self.diffuse_lobe:
                d["SD_DIFFUSE_DESIGN_SIZE"] = str(self.diffuse_design_size)
        if self.method.gaunt_table:
            d["SD_GAUNT_COUNT"] = str(self.gaunt_count)
        if self.per_pixel:
            d["SD_PER_PIXEL"] = "1"
        if self.lightmap:
            d["SD_LIGHTMAP"] = "1"
            d["SD_LIGHTMAP_WIDTH"] = str(self.lightmap[0])
            d["SD_LIGHTMAP_HEIGHT"] = str(self.lightmap[1])
        if self.vertex_target:
            d["SD_VERTEX_TARGET"] = "1"
        if self.band_limited_texture:
            d["SD_BAND_LIMITED_TEXTURE"] = "1"
            d["SD_BAND_LIMITED_CELLS"] = str(self.band_limited_texture[0] // 2)
        if self.material_count:
            d["SD_ALBEDO"] = "1"
            if self.material_slots:
                d["SD_MATERIAL_SLOTS"] = "1"
            if self.albedo_texture:
                d["SD_ALBEDO_TEXTURE"] = "1"
            if self.weighted:
                d["SD_LOBE_WEIGHTS"] = "1"
                d["SD_BRDF_TABLE_SIZE"] = str(BRDF_TABLE_SIZE)
                d["SD_DIELECTRIC_IOR"] = "%.6g" % DIELECTRIC_SHAPE_IOR
        if self.prefiltered_lookup:
            d["SD_PREFILTERED"] = "1"
            d["SD_PREFILTERED_MAP"] = PREFILTERED_SAMPLER[1]
            d["SD_PREFILTERED_WIDTH"] = str(self.prefiltered[0])
            d["SD_PREFILTERED_LEVELS"] = str(self.prefiltered[1])
            d["SD_SAMPLED_ROUGHNESS"] = "%.3f" % SAMPLED_ROUGHNESS
            d["SD_SAMPLED_N_DOT_V"] = "%.3f" % SAMPLED_N_DOT_V
            d["SD_GLOSSY_TAPS"] = str(GLOSSY_TAPS)
            d["SD_OPEN_ORDER"] = str(self.open_order)
            d["SD_HORIZON_LOBE"] = str(self.shaded_lobes)
            d["SD_HORIZON_ORDER"] = str(self.horizon_order)
            if self.lambert_layer:
                d["SD_LAMBERT_LAYER"] = "1"
        if self.sources:
            d["SD_SOURCES"] = str(self.sources)
            d["SD_SOURCE_ROWS"] = str(SOURCE_ROWS)
            d["SD_SHADOW_MAP_SIZE"] = str(SHADOW_MAP_SIZE)
            d["SD_HIGHLIGHT_POINTS"] = str(HIGHLIGHT_POINTS)
        if self.reflection_rays:
            d["SD_REFLECTION_RAYS"] = str(self.reflection_rays)
            d["SD_SINGLE_RAY_ROUGHNESS"] = "%.3f" % SINGLE_RAY_ROUGHNESS
            # the walk's stack: the native builder's depth bound (ray_bvh.h)
            d["SD_RAY_BVH_MAX_DEPTH"] = str(native.get().RAY_BVH_MAX_DEPTH)
        return d

    def vertex_inputs(self):
        """The vertex attributes, in location order: (GLSL type, name)."""
        inputs = [("vec3", "pos"), ("vec3", "nrm")]
        if self.lightmap:
            inputs.append(("vec2", "lightmap_uv"))
        elif self.per_pixel:
            inputs += [("vec3", "corners"), ("vec3", "bary")]
        if self.material_count and self.material_slots:
            inputs.append(("float", "material_slot"))
        if self.material_count and self.albedo_texture:
            inputs.append(("vec2", "uv"))
        return inputs

    def interface(self):
        """What the vertex stage passes on, in location order: (qualifier, GLSL type, name)."""
        if self.lightmap:
            out = [("smooth", "vec3", "sd_origin_offset"), ("smooth", "vec3", "sd_normal"),
                   ("smooth", "vec2", "sd_lightmap_uv")]
        elif self.per_pixel:
            out = [("smooth", "vec3", "sd_origin_offset"), ("smooth", "vec3", "sd_normal"),
                   ("smooth", "vec3", "sd_bary"), ("flat", "vec3", "sd_corners")]
        elif self.prefiltered_lookup:
            out = [("smooth", "vec3", "sd_origin_offset"), ("smooth", "vec3", "sd_normal"),
                   ("smooth", "float", "sd_visibility")]
            if self.diffuse_lobe or self.lambert_layer:
                out.append(("smooth", "vec3", "sd_diffuse_color"))
        else:
            out = [("smooth", "vec3", "sd_color")]
            if self.diffuse_lobe:
                out.append(("smooth", "vec3", "sd_diffuse_color"))
            if self.weighted:
                out.append(("smooth", "float", "sd_n_dot_v"))
            if self.sources:   # the sources are shaded per pixel: where the pixel is, its normal
                out += [("smooth", "vec3", "sd_origin_offset"), ("smooth", "vec3", "sd_normal")]
        if self.material_count:
            # a triangle's corners share their slot (bake/corners.py splits vertices between slots)
            out.append(("flat", "vec4", "sd_albedo"))
            if self.weighted:
                out.append(("flat", "vec4", "sd_lobe_weights"))
            if self.albedo_texture:
                out.append(("smooth", "vec2", "sd_uv"))
        return out

    def samplers(self):
        """(slot, name) of the samplers the variant reads."""
        out = []
        if self.data_stride > 0:
            out.append(DATA_SAMPLER)
        if self.method.gaunt_table:
            out.append(GAUNT_SAMPLER)
        if self.band_limited_texture:
            out.append(BAND_LIMITED_TEXTURE_SAMPLER)
        if self.material_count and self.albedo_texture:
            out.append(ALBEDO_TEXTURE_SAMPLER)
        if self.lightmap:
            out.append(LIGHTMAP_INDEX_SAMPLER)
        if self.weighted:
            out.append(BRDF_TABLE_SAMPLER)
        if self.prefiltered_lookup:
            out.append(PREFILTERED_SAMPLER)
        if self.sources:
            out.append(SHADOW_MAP_SAMPLER)
        if self.reflection_rays:
            out.append(RAY_BVH_SAMPLER)
        return out

    def frame_fields(self):
        """The uniform block's members, in order."""
        fields = [BlockField("model", "mat4"),             # object to world
                  BlockField("view_projection", "mat4"),   # world to clip
                  BlockField("world_to_local", "mat4"),    # the object's rotation, inverted
                  BlockField("camera", "vec4"),            # eye - object origin (w = 1), or direction to it (w = 0)
                  BlockField("params", "vec4"),            # 2^exposure, target width, height, depth bias
                  BlockField("light", "vec4", (self.light_order + 1) ** 2),  # L(g R x), rgb
                  # Funk-Hecke factors, lobe 0's then lobe 1's, then the horizon factors
                  BlockField("lobe", "vec4", self.lobe_vec4s * self.lobe_count)]
        if self.band_limited_texture or self.prefiltered_lookup:
            fields.append(BlockField("local_to_environment", "mat4"))  # g R: the textures are unrotated
        if self.band_limited_texture:
            fields.append(BlockField("band_limited_scale", "vec4"))    # L~ per code of its texture
        if self.prefiltered_lookup:
            fields.append(BlockField("prefiltered_scale", "vec4"))     # the environment's strength
        if self.method.lobe_design:
            # x, y, z, lambda; lobe 0's nodes, then lobe 1's
            fields.append(BlockField("design", "vec4", self.lobe_design_size + self.diffuse_design_size))
        if self.material_count:
            # per slot: linear rgb, and 1 where the albedo is the image texture instead
            fields.append(BlockField("albedo", "vec4", self.material_count))
            if self.weighted:   # per slot: scene/lobes.principled_weights
                fields.append(BlockField("lobe_weights", "vec4", self.material_count))
        if self.sources:   # scene/light_sources.shading_rows, shadow_rows
            fields += [BlockField("source_direction", "vec4", self.sources),
                       BlockField("source_irradiance", "vec4", self.sources),
                       BlockField("source_shadow", "vec4", SOURCE_ROWS * self.sources)]
            if self.prefiltered_lookup:   # light_sources.highlight_rows
                fields.append(BlockField("source_points", "vec4", 2 * HIGHLIGHT_POINTS * self.sources))
        if self.reflection_rays:   # live/ray_bvh.block_rows
            fields += [BlockField("ray_bvh", "vec4"), BlockField("ray_offset", "vec4")]
        return fields

    def frame_struct(self):
        """The block's GLSL declaration."""
        lines = ["struct SdFrameData {"] + [f.declaration() for f in self.frame_fields()] + ["};"]
        return "\n".join(lines) + "\n"

    def frame_block(self, values):
        """The block's bytes (float32) from {field name: value} (see BlockField.pack)."""
        fields = self.frame_fields()
        missing = [f.name for f in fields if f.name not in values]
        extra = set(values) - {f.name for f in fields}
        if missing or extra:
            raise ValueError("frame block: missing %s, unknown %s" % (missing, sorted(extra)))
        return np.concatenate([f.pack(values[f.name]).ravel() for f in fields]).astype(np.float32)
