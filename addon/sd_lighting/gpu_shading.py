"""The GPU side of the live shading: shader variants, and the per-object data they read.

One GLSL program (shaders/sd_shading_lib.glsl, _vert.glsl, _frag.glsl) is specialised with
defines to what an object's bake uses (method, lobe, orders, per-vertex data layout), so an object
pays only for the effects it has. Variants are compiled on first use and cached.

What a draw reads:
- vertex attributes `pos` and `nrm` (the baked mesh's positions and the `sd_normal` it was baked
  with), both in the object's local frame; per-pixel variants also `corners` (the triangle's
  three vertex indices, as floats: exact below 2^24 vertices) and `bary` (the corner's
  barycentric coordinates);
- per-vertex data in the RGBA32F texture `sd_data`: vertex p's texels are
  [p * stride, (p + 1) * stride), row-major over the texture, read with texelFetch by
  gl_VertexID (the index of an indexed batch) - the bake's FLOAT_COLOR attributes in order;
- the uniform block `sd` (struct SdFrameData, std140): matrices, eye, exposure, the rotated
  environment coefficients L(g R x) as vec4s, the lobe's Funk-Hecke factors and, for eq. (12),
  the lobe design (x, y, z, lambda) - rebuilt every frame;
- for PRT (10), the real Gaunt coefficients as texels (a, b, c, G) in `sd_gaunt`;
- with the light-texture option (MSD 12 and 13 only), the band-limited environment L~ (unrotated)
  as an equirect RGBA32F texture `sd_light_texture`, looked up at g R x (`light_rotation` in the
  block) instead of summing (s+1)^2 SH terms per direction.
"""

import os
from dataclasses import dataclass

import numpy as np

from . import attributes, methods, native

_HERE = os.path.dirname(os.path.abspath(__file__))
SHADER_FILES = ("sd_shading_lib.glsl", "sd_shading_vert.glsl", "sd_shading_frag.glsl")
TEXTURE_WIDTH_LOG2 = 12
TEXTURE_WIDTH = 1 << TEXTURE_WIDTH_LOG2   # every data texture has this width (rows: as needed)

_shaders = {}        # Variant -> GPUShader
_gaunt_textures = {}  # (s, s') -> (GPUTexture, count)
_lobe_designs = {}   # (lobe, exponent, degree) -> float32 [D, 4]
_light_textures = {}  # (source key, strength, s, width, height) -> GPUTexture
LIGHT_TEXTURE_METHODS = ("msd_lobe", "msd_visibility")   # the methods that evaluate L~ at directions


def light_texture_size(order):
    """Width and height of the band-limited environment texture for order s: bilinear
    interpolation of L~_s between texel centres is then within about 5e-4 of max |L~| (measured:
    4.3e-4 at s = 4, 4.8e-4 at s = 8, 4.6e-4 at s = 12 on forest.exr)."""
    width = max(256, 64 * (order + 1))
    return width, width // 2


def shader_directory():
    """shaders/ inside the add-on (the zip), else the repository's shaders/."""
    for directory in (os.path.join(_HERE, "shaders"), os.path.join(_HERE, "..", "..", "shaders")):
        if all(os.path.isfile(os.path.join(directory, f)) for f in SHADER_FILES):
            return os.path.normpath(directory)
    raise FileNotFoundError("the add-on's GLSL files (%s) are missing" % ", ".join(SHADER_FILES))


def _read_shader(name):
    with open(os.path.join(shader_directory(), name), encoding="utf-8") as f:
        return f.read()


def clear_cache():
    _shaders.clear()
    _gaunt_textures.clear()
    _lobe_designs.clear()
    _light_textures.clear()


def _glsl_floats(values):
    return ", ".join("%.9e" % v for v in values)


def sh_recurrence_defines(order):
    """The constants of the SH recurrences (spherical_harmonics.cpp) up to `order`, computed in
    float64, as GLSL float lists: SD_SH_DIAGONAL (Q_mm), SD_SH_A and SD_SH_B (a_lm, b_lm at
    l (l + 1) / 2 + m; a_{m+1,m} = sqrt(2m+3), b_{m+1,m} = 0)."""
    import math
    diagonal = [1.0]
    for m in range(1, order + 1):
        diagonal.append(math.sqrt(3.0) if m == 1 else diagonal[-1] * math.sqrt((2.0 * m + 1.0) / (2.0 * m)))
    size = (order + 1) * (order + 2) // 2
    a, b = [0.0] * size, [0.0] * size
    for l in range(order + 1):
        for m in range(l):
            k = l * (l + 1) // 2 + m
            if l == m + 1:
                a[k] = math.sqrt(2.0 * m + 3.0)
            else:
                a[k] = math.sqrt((2.0 * l - 1.0) * (2.0 * l + 1.0) / ((l - m) * (l + m)))
                b[k] = math.sqrt((2.0 * l + 1.0) * (l + m - 1.0) * (l - m - 1.0) /
                                 ((l - m) * (l + m) * (2.0 * l - 3.0)))
    return {"SD_SH_DIAGONAL": _glsl_floats(diagonal), "SD_SH_A": _glsl_floats(a),
            "SD_SH_B": _glsl_floats(b), "SD_SH_TABLE_SIZE": str(size)}


@dataclass(frozen=True)
class Variant:
    """Everything the shader is specialised on."""
    method: str
    glossy: bool
    light_order: int
    visibility_order: int
    data_stride: int = 0
    lobe_design_size: int = 0
    gaunt_count: int = 0
    per_pixel: bool = False
    vertex_target: bool = False
    light_texture: tuple = ()   # (width, height) of the environment texture (MSD 12, 13), or ()

    @property
    def basis_order(self):
        s, sv = self.light_order, self.visibility_order
        return {"unshadowed": s, "ambient_occlusion": s, "prt_diffuse": -1, "prt_matrix": sv,
                "prt_gaunt": s + sv, "msd_lobe": sv if self.light_texture else max(s, sv),
                "msd_visibility": -1 if self.light_texture else s}[self.method]

    @property
    def lobe_order(self):
        """Highest l whose Funk-Hecke factor the shader reads."""
        s, sv = self.light_order, self.visibility_order
        return {"unshadowed": s, "ambient_occlusion": s, "prt_diffuse": 0, "prt_matrix": sv,
                "prt_gaunt": s + sv, "msd_lobe": 0, "msd_visibility": sv}[self.method]

    @property
    def lobe_vec4s(self):
        return self.lobe_order // 4 + 1

    def defines(self):
        s, sv = self.light_order, self.visibility_order
        d = {"SD_METHOD_" + self.method.upper(): "1",
             "SD_LIGHT_COUNT": str((s + 1) ** 2),
             "SD_VIS_ORDER": str(sv),
             "SD_VIS_COUNT": str((sv + 1) ** 2),
             "SD_LOBE_VEC4S": str(self.lobe_vec4s),
             "SD_DATA_STRIDE": str(self.data_stride),
             "SD_TEXTURE_WIDTH_LOG2": str(TEXTURE_WIDTH_LOG2)}
        if self.basis_order >= 0:
            d["SD_BASIS_ORDER"] = str(self.basis_order)
            d["SD_BASIS_COUNT"] = str((self.basis_order + 1) ** 2)
            d.update(sh_recurrence_defines(self.basis_order))
        if self.glossy:
            d["SD_GLOSSY"] = "1"
        if self.method == "msd_lobe":
            d["SD_LOBE_DESIGN_SIZE"] = str(self.lobe_design_size)
        if self.method == "msd_visibility":
            d["SD_DESIGN_TEXELS"] = str(self.data_stride)
        if self.method == "prt_gaunt":
            d["SD_GAUNT_COUNT"] = str(self.gaunt_count)
        if self.per_pixel:
            d["SD_PER_PIXEL"] = "1"
        if self.vertex_target:
            d["SD_VERTEX_TARGET"] = "1"
        if self.light_texture:
            d["SD_LIGHT_TEXTURE"] = "1"
            d["SD_LIGHT_TEXTURE_WIDTH"] = str(self.light_texture[0])
            d["SD_LIGHT_TEXTURE_HEIGHT"] = str(self.light_texture[1])
        return d

    def frame_struct(self):
        lines = ["struct SdFrameData {",
                 "  mat4 model;",
                 "  mat4 view_projection;",
                 "  mat4 world_to_local;",
                 "  vec4 camera;",
                 "  vec4 params;",
                 "  vec4 light[%d];" % ((self.light_order + 1) ** 2),
                 "  vec4 lobe[%d];" % self.lobe_vec4s]
        if self.light_texture:
            lines.append("  mat4 light_rotation;")
        if self.method == "msd_lobe":
            lines.append("  vec4 design[%d];" % self.lobe_design_size)
        lines.append("};")
        return "\n".join(lines) + "\n"


def shader_program(variant):
    """The compiled GPUShader of a variant (cached)."""
    return _compile(variant)[0]


def _compile(variant):
    compiled = _shaders.get(variant)
    if compiled is not None:
        return compiled
    import gpu
    info = gpu.types.GPUShaderCreateInfo()
    for name, value in variant.defines().items():
        info.define(name, value)
    info.typedef_source(variant.frame_struct())
    info.uniform_buf(0, "SdFrameData", "sd")
    if variant.data_stride > 0:
        info.sampler(0, 'FLOAT_2D', "sd_data")
    if variant.method == "prt_gaunt":
        info.sampler(1, 'FLOAT_2D', "sd_gaunt")
    if variant.light_texture:
        info.sampler(2, 'FLOAT_2D', "sd_light_texture")
    info.vertex_in(0, 'VEC3', "pos")
    info.vertex_in(1, 'VEC3', "nrm")
    interface = gpu.types.GPUStageInterfaceInfo("sd_interface")
    if variant.per_pixel:
        info.vertex_in(2, 'VEC3', "corners")
        info.vertex_in(3, 'VEC3', "bary")
        interface.smooth('VEC3', "sd_world_position")
        interface.smooth('VEC3', "sd_normal")
        interface.smooth('VEC3', "sd_bary")
        interface.flat('VEC3', "sd_corners")
    else:
        interface.smooth('VEC3', "sd_color")
    info.vertex_out(interface)
    info.fragment_out(0, 'VEC4', "fragColor")
    lib, vert, frag = (_read_shader(name) for name in SHADER_FILES)
    info.vertex_source(lib + "\n" + vert)
    info.fragment_source(lib + "\n" + frag)
    program = gpu.shader.create_from_info(info)
    _shaders[variant] = (program, interface, info)  # keep the create-infos alive with the shader
    return _shaders[variant]


def float_texture(texels):
    """An RGBA32F texture holding float32 [M, 4] texels row-major, TEXTURE_WIDTH wide."""
    import gpu
    texels = np.ascontiguousarray(texels, dtype=np.float32).reshape(-1, 4)
    count = max(len(texels), 1)
    width = TEXTURE_WIDTH
    height = (count + width - 1) // width
    limit = gpu.capabilities.max_texture_size_get()
    if height > limit:
        raise ValueError("per-vertex data too large for one texture (%d texels)" % count)
    padded = np.zeros((width * height, 4), dtype=np.float32)
    padded[:len(texels)] = texels
    buffer = gpu.types.Buffer('FLOAT', padded.size, padded.ravel())
    return gpu.types.GPUTexture((width, height), format='RGBA32F', data=buffer)


def environment_texture(source, order):
    """The band-limited environment L~ of order s (unrotated, strength applied) as an RGBA32F
    equirect texture of light_texture_size(s), Blender's orientation, rows bottom-first as GPU
    textures hold them (v = 0 at the south pole) (cached per source and order)."""
    from . import environment
    width, height = light_texture_size(order)
    key = (source.key, float(source.strength), int(order), width, height)
    texture = _light_textures.get(key)
    if texture is None:
        import gpu
        coefficients = environment.light_coefficients(source, order)
        image = np.asarray(native.get().band_limited_texture(coefficients, width, height),
                           dtype=np.float32).reshape(height, width, 3)
        texels = np.zeros((height, width, 4), dtype=np.float32)
        texels[..., :3] = image[::-1]     # sdnative's rows are top-first
        texels[..., 3] = 1.0
        buffer = gpu.types.Buffer('FLOAT', texels.size, texels.ravel())
        texture = gpu.types.GPUTexture((width, height), format='RGBA32F', data=buffer)
        _light_textures[key] = texture
    return texture


def gaunt_texture(light_order, visibility_order):
    """Texels (a, b, c, G) of every non-zero real Gaunt coefficient for eq. (10) (cached)."""
    key = (light_order, visibility_order)
    if key not in _gaunt_textures:
        indices, values = native.get().gaunt_coefficients(light_order, visibility_order,
                                                           light_order + visibility_order)
        texels = np.empty((len(values), 4), dtype=np.float32)
        texels[:, :3] = indices
        texels[:, 3] = values
        _gaunt_textures[key] = (float_texture(texels), len(values))
    return _gaunt_textures[key]


def lobe_design(lobe, exponent, degree):
    """The lobe's design of the degree (sdnative.zonal_design, as the CPU evaluator uses): [D, 4]."""
    key = (lobe, float(exponent), int(degree))
    if key not in _lobe_designs:
        nodes, weights = native.get().zonal_design(lobe, float(exponent), int(degree))
        design = np.empty((len(weights), 4), dtype=np.float32)
        design[:, :3] = nodes
        design[:, 3] = weights
        _lobe_designs[key] = design
    return _lobe_designs[key]


def make_batch(primitive, content, indices=None):
    """A GPUBatch of float attributes (name -> float32 [N, k], k <= 4) with the vertex format built
    here: gpu_extras' batch_for_shader asks the shader for its attributes, which Blender 3.4
    reports wrongly for some programs (names and types out of order). Only F32 x 1-4 with fetch
    mode FLOAT: 4.5 deprecates formats that are not 4-byte aligned, wider than 4 components or
    INT_TO_FLOAT, and 5.0 rejects the last two."""
    import gpu
    vertex_format = gpu.types.GPUVertFormat()
    arrays = {}
    for name, values in content.items():
        values = np.ascontiguousarray(values, dtype=np.float32)
        values = values.reshape(len(values), -1)
        if not 1 <= values.shape[1] <= 4:
            raise ValueError("vertex attribute %s has %d components (1-4 allowed)" % (name, values.shape[1]))
        arrays[name] = values
        vertex_format.attr_add(id=name, comp_type='F32', len=values.shape[1], fetch_mode='FLOAT')
    count = len(next(iter(arrays.values())))
    vertex_buffer = gpu.types.GPUVertBuf(vertex_format, count)
    for name, values in arrays.items():
        vertex_buffer.attr_fill(name, values)
    if indices is None:
        return gpu.types.GPUBatch(type=primitive, buf=vertex_buffer)
    index_buffer = gpu.types.GPUIndexBuf(type=primitive, seq=np.ascontiguousarray(indices, dtype=np.int32))
    return gpu.types.GPUBatch(type=primitive, buf=vertex_buffer, elem=index_buffer)


class ObjectData:
    """GPU data of one baked mesh: batch, per-vertex texture, shader variant, lobe constants."""

    def __init__(self, mesh, per_pixel=False, vertex_target=False, light_texture=False):
        bake = dict(mesh["sd_bake"])
        self.bake = bake
        self.method = methods.get(bake["method"])
        self.lobe = bake["lobe"]
        self.exponent = float(bake["exponent"])
        self.light_order = int(bake["light_order"])
        self.visibility_order = int(bake["visibility_order"])
        self.vertex_count = len(mesh.vertices)
        s, sv = self.light_order, self.visibility_order

        texels = None
        if self.method.id != "unshadowed":
            texels = attributes.gpu_texels(mesh, self.method.needs)
        stride = texels.shape[1] if texels is not None else 0
        self.data_texture = float_texture(texels.reshape(-1, 4)) if stride else None
        self.gaunt_texture, gaunt_count = (None, 0)
        if self.method.id == "prt_gaunt":
            self.gaunt_texture, gaunt_count = gaunt_texture(s, sv)
        self.design = None
        if self.method.id == "msd_lobe":
            self.design = lobe_design(self.lobe, self.exponent, s + sv)
        self.uses_light_texture = bool(light_texture) and self.method.id in LIGHT_TEXTURE_METHODS
        self.variant = Variant(self.method.id, self.lobe == "phong", s, sv, stride,
                               len(self.design) if self.design is not None else 0, gaunt_count,
                               per_pixel, vertex_target,
                               light_texture_size(s) if self.uses_light_texture else ())
        self.shader = shader_program(self.variant)
        factors = native.get().zonal_coefficients(self.lobe, self.exponent, self.variant.lobe_order)
        self.lobe_factors = np.zeros(4 * self.variant.lobe_vec4s, dtype=np.float32)
        self.lobe_factors[:len(factors)] = factors

        positions = attributes.read_positions(mesh)
        normals = attributes.read_normals(mesh)
        if vertex_target:
            content = {"pos": positions, "nrm": normals}
            if per_pixel:
                index = np.arange(self.vertex_count, dtype=np.float32)
                content["corners"] = np.repeat(index[:, None], 3, axis=1)
                content["bary"] = np.tile(np.array([[1.0, 0.0, 0.0]], dtype=np.float32),
                                          (self.vertex_count, 1))
            self.batch = make_batch('POINTS', content)
        else:
            triangles = attributes.read_triangles(mesh)
            if per_pixel:
                corners = triangles.reshape(-1)
                content = {"pos": positions[corners], "nrm": normals[corners],
                           "corners": np.repeat(triangles.astype(np.float32), 3, axis=0),
                           "bary": np.tile(np.eye(3, dtype=np.float32), (len(triangles), 1))}
                self.batch = make_batch('TRIS', content)
            else:
                self.batch = make_batch('TRIS', {"pos": positions, "nrm": normals}, indices=triangles)
        self.ubo = None

    def frame_block(self, model, view_projection, camera, light, exposure_scale, target=(1, 1),
                    depth_bias=0.0, light_rotation=None):
        """The uniform block's bytes for one draw.

        model: 4x4 object-to-world; view_projection: 4x4 world-to-clip; camera: (x, y, z, w) with
        w = 1 for an eye position, w = 0 for a direction towards an orthographic viewer; light:
        [(s+1)^2, 3] coefficients of x -> L(g R x) (already rotated); light_rotation: g R, for
        the light-texture variants (the texture holds the unrotated L~, looked up at g R x)."""
        model = np.asarray(model, dtype=np.float64)
        rotation = rotation_part(model)
        world_to_local = np.eye(4)
        world_to_local[:3, :3] = rotation.T
        parts = [
            model.T.ravel(),
            np.asarray(view_projection, dtype=np.float64).T.ravel(),
            world_to_local.T.ravel(),
            np.asarray(camera, dtype=np.float64),
            np.array([exposure_scale, target[0], target[1], depth_bias]),
        ]
        light4 = np.zeros((len(light), 4))
        light4[:, :3] = light
        parts += [light4.ravel(), self.lobe_factors]
        if self.variant.light_texture:
            rotation4 = np.eye(4)
            if light_rotation is not None:
                rotation4[:3, :3] = light_rotation
            parts.append(rotation4.T.ravel())
        if self.design is not None:
            parts.append(self.design.ravel())
        return np.concatenate(parts).astype(np.float32)

    def draw(self, block, light_texture=None):
        import gpu
        buffer = gpu.types.Buffer('FLOAT', block.size, block)
        if self.ubo is None:
            self.ubo = gpu.types.GPUUniformBuf(buffer)
        else:
            self.ubo.update(buffer)
        self.shader.bind()
        self.shader.uniform_block("sd", self.ubo)
        if self.data_texture is not None:
            self.shader.uniform_sampler("sd_data", self.data_texture)
        if self.gaunt_texture is not None:
            self.shader.uniform_sampler("sd_gaunt", self.gaunt_texture)
        if self.variant.light_texture:
            self.shader.uniform_sampler("sd_light_texture", light_texture)
        self.batch.draw(self.shader)


def rotation_part(matrix):
    """The rotation of a 4x4 affine matrix (polar decomposition of its 3x3 part)."""
    u, _, vt = np.linalg.svd(np.asarray(matrix, dtype=np.float64)[:3, :3])
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] = -u[:, -1]
        r = u @ vt
    return r

