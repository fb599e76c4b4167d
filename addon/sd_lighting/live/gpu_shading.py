"""The GPU side of the live shading: compiled shader variants (live/shader_variant.py), and the
per-object data they read.

What a draw reads:
- vertex attributes `pos` (the baked mesh's positions, in the object's local space) and `nrm`
  (the `sd_normal` it was baked with, in its bake space: bake/geometry.py); per-pixel variants also
  `corners` (the triangle's three vertex indices, as floats: exact below 2^24 vertices) and
  `bary` (the corner's barycentric coordinates);
- per-vertex data in the RGBA32F texture `sd_data`: vertex p's texels are
  [p * stride, (p + 1) * stride), row-major over the texture, read with texelFetch by
  gl_VertexID (the index of an indexed batch) - the method's stored array (store/bake_data.py;
  a design's texel is a header, its nodes follow every vertex's header);
- texture-space data (a bake with a lightmap, bake/lightmap.py): the same texels, one entry per
  stored lightmap texel (the texels' mesh's attributes), found through the R32F index map
  `sd_lightmap_index` and read per pixel at the vertex attribute `lightmap_uv` (the baked mesh's
  UV map "SD Lightmap") instead of `corners` and `bary`;
- the uniform block `sd` (Variant.frame_fields), rebuilt every frame; for MSD (12) it holds the
  lobes' designs (live/lobe_designs.py: the Gauss product rule until the small design, built in a
  worker thread, is there; then the variant is swapped);
- for PRT (10), the real Gaunt coefficients as texels (a, b, c, G) in `sd_gaunt`;
- with the band-limited texture option (methods that can read it), the band-limited environment
  L~ (unrotated) on cube faces, by bilinear cell (live/band_limited_map.py), in the RGBA32F texture
  `sd_band_limited_texture`, looked up at g R x instead of summing (s+1)^2 SH terms per direction;
- the albedo B is multiplied by (materials.py), read from the object's materials at every draw:
  one colour per material slot in the block, a vertex attribute `material_slot` where the bake
  kept several, and the image texture `sd_albedo_texture` with the vertex attribute `uv`; for
  lobes from Principled BSDFs, each slot's lobe weights (scene/lobes.py). An object with neither
  weights nor a colour other than white gets a variant without any of it.
Variants are compiled on first use and cached.
"""

import dataclasses
import os

import numpy as np

from .. import compat, methods, native
from ..bake import lightmap
from ..scene import environment, light_sources, lobes, materials, transforms
from ..store import attributes, baked
from ..store.bake_data import LIGHTMAP, LIGHTMAP_UV, TEXTURE_WIDTH
from . import band_limited_map
from . import lobe_designs as lobe_design_cache
from .shader_variant import (ALBEDO_TEXTURE_SAMPLER, BRDF_TABLE_SAMPLER, BRDF_TABLE_SIZE, DATA_SAMPLER, GAUNT_SAMPLER,
                             LIGHTMAP_INDEX_SAMPLER, REFLECTION_RAYS, SHADOW_MAP_SAMPLER, Variant)

_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))   # sd_lighting/
EQUIRECT_FILE = "sd_equirect.glsl"
# (library, vertex, fragment): the fragment stage alone shades the bright sources
SHADER_FILES = ("sd_shading_lib.glsl", "sd_shading_vert.glsl",
                ("sd_source_shadows.glsl", "sd_ray_bvh.glsl", "sd_shading_frag.glsl"))
BACKGROUND_FILES = ("sd_background_vert.glsl", "sd_background_frag.glsl")
CASTER_FILES = ("sd_caster_vert.glsl", "sd_caster_frag.glsl")
ALL_FILES = tuple(name for stage in (EQUIRECT_FILE,) + SHADER_FILES + BACKGROUND_FILES + CASTER_FILES
                  for name in ((stage,) if isinstance(stage, str) else stage))
BACKGROUND_SAMPLER = "sd_environment"

_shaders = {}                 # Variant -> (GPUShader, interface, create-info)
_gaunt_textures = {}          # (s, s') -> (GPUTexture, count)
_lobe_designs = None          # LobeDesigns, made on first use
_band_limited_textures = {}   # (source key, coefficients bytes, width, height) -> (GPUTexture, scale)
_BASIS_BLOCK = 16384          # directions per SH basis evaluated at once for that texture
_prefiltered_textures = {}    # (source key, remainder) -> GPUTexture
_brdf_table = []              # the GPUTexture of environment_brdf_table and glossy_bend_table, once made
_background = {}              # "shader": (GPUShader, interface, info, batch); source key -> GPUTexture


def shader_directory():
    """shaders/ inside the add-on (the zip), else the repository's shaders/."""
    for directory in (os.path.join(_PACKAGE, "shaders"), os.path.join(_PACKAGE, "..", "..", "shaders")):
        if all(os.path.isfile(os.path.join(directory, f)) for f in ALL_FILES):
            return os.path.normpath(directory)
    raise FileNotFoundError("the add-on's GLSL files (%s) are missing" % ", ".join(ALL_FILES))


def _read_shader(name):
    with open(os.path.join(shader_directory(), name), encoding="utf-8") as f:
        return f.read()


def stage_sources(files):
    """(vertex, fragment) source of a program of `files` (library, vertex, fragment; or vertex,
    fragment; a stage may be a tuple of files, read in order), each after sd_equirect.glsl, as
    create-infos take them (after their declarations)."""
    *library, vert, frag = ("\n".join(_read_shader(name) for name in ((f,) if isinstance(f, str) else f))
                            for f in (EQUIRECT_FILE,) + tuple(files))
    prefix = "\n".join(library) + "\n"
    return prefix + vert, prefix + frag


def clear_cache():
    global _lobe_designs
    _shaders.clear()
    _gaunt_textures.clear()
    if _lobe_designs is not None:
        _lobe_designs.close()
        _lobe_designs = None
    _band_limited_textures.clear()
    _prefiltered_textures.clear()
    _brdf_table.clear()
    _background.clear()


def shader_program(variant):
    """The compiled GPUShader of a variant (cached)."""
    return _compile(variant)[0]


def _compile(variant):
    compiled = _shaders.get(variant)
    if compiled is not None:
        return compiled
    import gpu
    info = gpu.types.GPUShaderCreateInfo()
    for name, value in variant.defines(native.get().sh_recurrence_constants).items():
        info.define(name, value)
    info.typedef_source(variant.frame_struct())
    info.uniform_buf(0, "SdFrameData", "sd")
    for slot, name in variant.samplers():
        info.sampler(slot, 'FLOAT_2D', name)
    for location, (glsl_type, name) in enumerate(variant.vertex_inputs()):
        info.vertex_in(location, glsl_type.upper(), name)
    interface = gpu.types.GPUStageInterfaceInfo("sd_interface")
    for qualifier, glsl_type, name in variant.interface():
        getattr(interface, qualifier)(glsl_type.upper(), name)
    program = create(info, interface, SHADER_FILES)
    _shaders[variant] = (program, interface, info)  # keep the create-infos alive with the shader
    return _shaders[variant]


def create(info, interface, files):
    """Compiles a create-info given its declarations, with the stage interface, one fragment
    output fragColor and the sources of `files` (stage_sources)."""
    import gpu
    info.vertex_out(interface)
    info.fragment_out(0, 'VEC4', "fragColor")
    vert, frag = stage_sources(files)
    info.vertex_source(vert)
    info.fragment_source(frag)
    return gpu.shader.create_from_info(info)


def bind(program):
    """Binds one of this module's programs for a draw. Blender skips a bind when the context's
    last bound shader is at the same address (GPU_shader_bind compares pointers, and unbinding is
    a no-op in release builds), and a program compiled after clear_cache freed the others can get
    a freed one's address: on OpenGL the draw then ran whatever program GL had in use - after a
    file reload, test_default_scene's Ground drew with its own white variant's program (bpy 5.0.1;
    blender_tests/test_shader_rebind.py). A built-in shader lives as long as Blender, so binding
    one first makes the comparison fail."""
    compat.uniform_color_shader().bind()
    program.bind()


def _texture(width, height, texels, format='RGBA32F'):
    import gpu
    texels = np.ascontiguousarray(texels, dtype=np.float32).ravel()
    buffer = gpu.types.Buffer('FLOAT', texels.size, texels)
    return gpu.types.GPUTexture((width, height), format=format, data=buffer)


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
    return _texture(width, height, padded)


def band_limited_texture(source, light):
    """The band-limited environment L~ of the unrotated coefficients `light` ([(s+1)^2, 3]: the
    source's, strength and ringing window applied, drawing.shading_light) as (the RGBA32F cell
    texture of live/band_limited_map.py, its scale: the block's band_limited_scale), cached per
    source and coefficients."""
    light = np.ascontiguousarray(light, dtype=np.float64)
    order = int(round(np.sqrt(light.shape[0]))) - 1
    width, height = band_limited_map.texture_size(order)
    key = (source.key, light.tobytes(), width, height)
    cached = _band_limited_textures.get(key)
    if cached is None:
        n = band_limited_map.side(order)
        directions = band_limited_map.texel_directions(n).reshape(-1, 3)
        # in blocks: the basis of every texel at once would be (n + 2)^2 6 (s + 1)^2 floats (1.9 GB
        # at s = 16), on the thread that draws
        faces = np.concatenate([native.get().sh_basis(order, directions[start:start + _BASIS_BLOCK]) @ light
                                for start in range(0, len(directions), _BASIS_BLOCK)])
        texels, scale = band_limited_map.cell_texels(faces.reshape(6, n + 2, n + 2, 3))
        cached = _band_limited_textures[key] = (_texture(width, height, texels), scale)
    return cached


def takes_sources(record, vertex_target, prefiltered):
    """Whether the map's bright sources light the data of a bake (its store/record.BakeRecord) on
    their own, the rest of the map in its SH light: drawn, unless the automatic mode found they do
    not pay (record.sources False), with a Lambert lobe 0, or with a glossy one whose light is looked
    up in the prefiltered atlas (prefiltered: it is, for these data; the atlas is then the
    remainder's, and the shader adds each source's highlight, shadowed). A glossy lobe lit through
    SH alone keeps the whole map (its highlight of a source would need the lobe's SH to hold it)."""
    lobes = record.lobes
    return not vertex_target and record.sources is not False and \
        (lobes.lobe == "lambert" or (lobes.weighted and prefiltered))


def prefiltered_layout():
    """(width0, levels) of the prefiltered atlas (sdnative's PREFILTER_WIDTH, PREFILTER_LEVELS)."""
    return native.get().PREFILTER_WIDTH, native.get().PREFILTER_LEVELS


def prefiltered_texture(source, wait, remainder=False):
    """The environment of `source` prefiltered by the GGX lobe per roughness level, without its
    strength (scene/environment.prefiltered_atlas; the block's `prefiltered_scale` applies it), as
    the RGBA32F atlas texture the shader's sd_prefiltered_light reads (cached per source);
    remainder: of the map without the bright sources that light the data on their own; wait=False:
    None while it is computed."""
    remainder = bool(remainder and environment.has_highlights(source, wait))   # else the same atlas
    key = (source.key, remainder)
    texture = _prefiltered_textures.get(key)
    if texture is None:
        atlas = environment.prefiltered_atlas(source, *prefiltered_layout(), wait, remainder=remainder)
        if atlas is None:
            return None
        height, width, _ = atlas.shape
        texels = np.ones((height, width, 4), dtype=np.float32)
        texels[..., :3] = atlas
        texture = _prefiltered_textures[key] = _texture(width, height, texels)
    return texture


def brdf_table_texture():
    """The GGX lobe's tables over n.v and roughness as the RGBA32F texture the shader's
    sd_brdf_table reads (made once), one above the other: the split-sum terms (A, B) of Schlick's
    Fresnel (sdnative.environment_brdf_table), each roughness row's E_avg (lobes.average_albedo)
    and B of the dielectric Fresnel of lobes.DIELECTRIC_SHAPE_IOR; then where the prefiltered
    light is read (sdnative.glossy_bend_table): for a metal, and for the dielectric layer of
    lobes.DIELECTRIC_SHAPE_IOR."""
    if not _brdf_table:
        sd = native.get()
        table = np.asarray(sd.environment_brdf_table(BRDF_TABLE_SIZE))
        texels = np.zeros((2, BRDF_TABLE_SIZE, BRDF_TABLE_SIZE, 4), dtype=np.float32)
        texels[0, ..., :2] = table
        texels[0, ..., 2] = lobes.average_albedo(table)[:, None]
        texels[0, ..., 3] = np.asarray(sd.environment_brdf_table(BRDF_TABLE_SIZE, ior=lobes.DIELECTRIC_SHAPE_IOR))[..., 1]
        texels[1, ..., 0] = np.asarray(sd.glossy_bend_table(BRDF_TABLE_SIZE))
        texels[1, ..., 1] = np.asarray(sd.glossy_bend_table(BRDF_TABLE_SIZE, ior=lobes.DIELECTRIC_SHAPE_IOR))
        _brdf_table.append(_texture(BRDF_TABLE_SIZE, 2 * BRDF_TABLE_SIZE, texels))
    return _brdf_table[0]


def _background_shader():
    """(GPUShader, batch of its screen-covering triangle) of the world background (compiled once)."""
    compiled = _background.get("shader")
    if compiled is None:
        import gpu
        info = gpu.types.GPUShaderCreateInfo()
        info.define("SD_EQUIRECT_MAP", BACKGROUND_SAMPLER)
        info.push_constant('MAT4', "sd_inverse_view_projection")
        info.push_constant('MAT4', "sd_to_environment")
        info.push_constant('FLOAT', "sd_scale")
        info.sampler(0, 'FLOAT_2D', BACKGROUND_SAMPLER)
        info.vertex_in(0, 'VEC2', "pos")
        interface = gpu.types.GPUStageInterfaceInfo("sd_background_interface")
        interface.smooth('VEC2', "sd_ndc")
        shader = create(info, interface, BACKGROUND_FILES)
        batch = compat.make_batch('TRIS', {"pos": np.array([[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]])})
        compiled = _background["shader"] = (shader, interface, info, batch)   # infos kept alive
    return compiled[0], compiled[3]


def draw_background(source, view, to_environment, scale):
    """Draws the environment of `source` (environment.Source) behind everything drawn so far:
    in each pixel L(g d), d its ray (view: view.View), g = to_environment, times `scale` (the
    exposure), at the far plane - with the depth test LESS_EQUAL it fills only what is empty."""
    import gpu
    from mathutils import Matrix
    shader, batch = _background_shader()
    texture = _background.get(source.key)
    if texture is None:
        texels = environment.background_texels(source)
        height, width, _ = texels.shape
        rgba = np.ones((height, width, 4), dtype=np.float32)
        rgba[..., :3] = texels
        texture = _background[source.key] = _texture(width, height, rgba)
    rotation = np.eye(4)
    rotation[:3, :3] = to_environment
    bind(shader)
    shader.uniform_float("sd_inverse_view_projection", Matrix(np.linalg.inv(view.view_projection).tolist()))
    shader.uniform_float("sd_to_environment", Matrix(rotation.tolist()))
    shader.uniform_float("sd_scale", float(scale))
    shader.uniform_sampler(BACKGROUND_SAMPLER, texture)
    gpu.state.depth_mask_set(False)
    batch.draw(shader)


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


def lobe_designs():
    """The session's lobe designs (live/lobe_designs.py), cached in the user's cache folder."""
    global _lobe_designs
    if _lobe_designs is None:
        _lobe_designs = lobe_design_cache.LobeDesigns(native.get(), lobe_design_cache.default_directory())
    return _lobe_designs


def lobe_design(lobe, exponent, degree):
    """The lobe's design of the degree for eq. (12): a lobe_designs.Design, final or the Gauss
    rule standing in while the final one builds; never waits for a build."""
    return lobe_designs().get(lobe, exponent, degree)


def lobe_design_status():
    """Lines for the panel: the lobe designs being built or whose build failed."""
    if _lobe_designs is None:
        return []
    lines = []
    for key in _lobe_designs.pending():
        lines.append("Building the lobe design of %s, degree %d (Gauss rule meanwhile)"
                     % (lobes.label(key.lobe, key.exponent), key.degree))
    for key, why in _lobe_designs.failures().items():
        lines.append("Lobe design of %s, degree %d failed: %s"
                     % (lobes.label(key.lobe, key.exponent), key.degree, why))
    return lines


class ObjectData:
    """GPU data of one baked mesh: batches, per-vertex texture, shader variant, lobe constants."""

    def __init__(self, mesh, per_pixel=False, vertex_target=False, band_limited_texture=False, prefiltered=False):
        record = baked.mesh_record(mesh)
        self.method = methods.get(record.method)
        self.record = record
        self.lobes = record.lobes
        self.lobe, self.exponent = self.lobes.lobe, self.lobes.exponent
        self.light_order, self.visibility_order = record.light_order, record.visibility_order
        self.vertex_count = len(mesh.vertices)
        s, sv = self.light_order, self.visibility_order

        # Texture-space data, where the bake has them (the vertex target reads the vertices')
        texels_mesh = None if vertex_target else mesh.get(LIGHTMAP)
        if texels_mesh is None or LIGHTMAP_UV not in mesh.uv_layers or self.method.data is None:
            texels_mesh = None
        self.lightmap = (record.lightmap,) * 2 if texels_mesh is not None else ()
        per_pixel = per_pixel or bool(self.lightmap)
        self.lightmap_index = None
        if self.lightmap:
            index = lightmap.index_map(attributes.read_texels_entries(texels_mesh), *self.lightmap)
            self.lightmap_index = _texture(self.lightmap[0], self.lightmap[1], index, 'R32F')
        self.data_texture, stride = None, 0
        if self.method.data is not None:
            texels, stride = attributes.read_texels(mesh if texels_mesh is None else texels_mesh, self.method.data)
            self.data_texture = float_texture(texels)
        self.gaunt_texture, gaunt_count = (None, 0)
        if self.method.gaunt_table:
            self.gaunt_texture, gaunt_count = gaunt_texture(s, sv)
        self.designs = self._designs()
        self.uses_band_limited_texture = bool(band_limited_texture) and self.method.band_limited_texture
        # the atlas's layout where glossy weights are lit by the prefiltered environment, else ()
        self.prefiltered = prefiltered_layout() if prefiltered and self.lobes.weighted else ()
        design_sizes = [len(d.weights) for d in self.designs] + [0, 0]
        self.variant = Variant(self.method, self.lobe == "phong", s, sv, stride, design_sizes[0],
                               gaunt_count, per_pixel, vertex_target,
                               band_limited_map.texture_size(s) if self.uses_band_limited_texture else (),
                               lobe_weights=self._weighted(self.prefiltered), diffuse_lobe=self.lobes.diffuse,
                               diffuse_design_size=design_sizes[1], lightmap=self.lightmap,
                               prefiltered=self.prefiltered)
        self.shader = shader_program(self.variant)
        self._lobe_factors = (None, None)   # (lobe_vec4s, lobe_order, lobe_count), lobe_factors()

        positions = attributes.read_positions(mesh)
        # how far the mesh reaches from its origin: where the reflection rays start (ray_bvh.block_rows)
        self.radius = float(np.sqrt(np.max(np.sum(np.square(positions, dtype=np.float64), axis=1)))) \
            if len(positions) else 0.0
        normals = attributes.read_normals(mesh)
        slots, uvs, sides = attributes.read_surface(mesh)
        self.slot_count = int(slots.max()) + 1 if slots is not None and len(slots) else 1
        self.has_uvs = uvs is not None
        self.albedo_image = None
        surface = {}    # per-vertex albedo inputs; the test target reads B alone
        if slots is not None and not vertex_target:
            surface["material_slot"] = slots
        if uvs is not None and not vertex_target:
            surface["uv"] = uvs
        self.batches = []   # (GPUBatch, whether its back faces are culled)
        self.mirrored = False   # the model matrix of the last frame_block turns the winding
        if vertex_target:
            content = {"pos": positions, "nrm": normals}
            if per_pixel:
                index = np.arange(self.vertex_count, dtype=np.float32)
                content["corners"] = np.repeat(index[:, None], 3, axis=1)
                content["bary"] = np.tile(np.array([[1.0, 0.0, 0.0]], dtype=np.float32),
                                          (self.vertex_count, 1))
            self.batches.append((compat.make_batch('POINTS', content), False))
        else:
            triangles = attributes.read_triangles(mesh)
            # faces seen from both sides (bake/sides.py): each copy is drawn from its own side only
            own_side = np.zeros(len(triangles), bool) if sides is None else sides[triangles[:, 0]] > 0.5
            subsets = [(culled, chosen) for culled, chosen in ((False, ~own_side), (True, own_side)) if chosen.any()]
            if per_pixel:
                loops = attributes.read_triangle_loops(mesh) if self.lightmap else None
                lightmap_uvs = attributes.read_loop_uvs(mesh, LIGHTMAP_UV) if self.lightmap else None
                for culled, chosen in subsets:
                    corners = triangles[chosen].reshape(-1)
                    content = {"pos": positions[corners], "nrm": normals[corners]}
                    if self.lightmap:
                        content["lightmap_uv"] = lightmap_uvs[loops[chosen].reshape(-1)]
                    else:
                        content.update(corners=np.repeat(triangles[chosen].astype(np.float32), 3, axis=0),
                                       bary=np.tile(np.eye(3, dtype=np.float32), (int(chosen.sum()), 1)))
                    content.update({name: values[corners] for name, values in surface.items()})
                    self.batches.append((compat.make_batch('TRIS', content), culled))
            else:
                shared = compat.vertex_buffer(dict({"pos": positions, "nrm": normals}, **surface))
                self.batches = [(compat.make_batch('TRIS', shared, indices=triangles[chosen]), culled)
                                for culled, chosen in subsets]
        self.ubo = None

    def _designs(self):
        """The lobes' designs for eq. (12) (methods with lobe_design), else []."""
        if not self.method.lobe_design:
            return []
        degree = self.light_order + self.visibility_order
        return [lobe_design(lobe, exponent, degree) for lobe, exponent in self.lobes.shaded()]

    def lobe_factors(self):
        """The block's rows of factors: the variant's lobes' Funk-Hecke factors to its lobe order,
        and with the prefiltered lookup (once weights are drawn) the horizon factors h_l w_l of
        lobe 0 (scene/lobes.horizon_factors), or 1 for a method that sees no horizon."""
        key = (self.variant.lobe_vec4s, self.variant.lobe_order, self.variant.lobe_count)
        if self._lobe_factors[0] != key:
            per_lobe = 4 * self.variant.lobe_vec4s
            out = np.zeros(per_lobe * self.variant.lobe_count, dtype=np.float32)
            rows = [native.get().zonal_coefficients(lobe, exponent, self.variant.lobe_order)
                    for lobe, exponent in self.lobes.shaded()]
            if self.variant.prefiltered_lookup:
                order = self.variant.horizon_order
                rows.append(lobes.horizon_factors(order) * rows[0][:order + 1]
                            if self.method.uses_visibility_order else np.ones(1))
            for k, factors in enumerate(rows):
                out[k * per_lobe:k * per_lobe + len(factors)] = factors
            self._lobe_factors = (key, out)
        return self._lobe_factors[1]

    def takes_sources(self, prefiltered):
        """Whether the map's bright sources light this data on their own (takes_sources;
        prefiltered: whether the prefiltered atlas is there to draw with)."""
        return takes_sources(self.record, self.variant.vertex_target, bool(self.prefiltered) and prefiltered)

    @property
    def traces_reflections(self):
        """Whether the glossy lobe, or a Lambert lobe's specular layer, can trace its visibility
        (with the prefiltered atlas; frame_block decides with the slots' weights)."""
        return (self.lobe == "phong" or self.lobes.layer) and bool(self.prefiltered) and not self.variant.vertex_target

    def _weighted(self, prefiltered):
        """Whether the slots' lobe weights are drawn, with the prefiltered atlas's layout or ():
        a Lambert lobe's specular layers need the prefiltered light (folded into it without)."""
        return self.lobes.weighted and (not self.lobes.layer or bool(prefiltered))

    def _use_surface(self, albedos, prefiltered, sources, traced):
        """The block's albedo and lobe weight rows for the materials' current albedos
        (materials.object_albedos), switching, once, to the variant they need - none for a lobe
        without weights whose albedos are all white - lit by `sources` bright sources on their own
        and tracing its glossy visibility with `traced` rays per pixel (0: not) where that variant
        can take them (a glossy lobe
        only where the prefiltered atlas lights it: while a new environment's is made, neither).
        Returns {field: rows}."""
        if self.variant.vertex_target:
            return {}
        rows = np.zeros((self.slot_count, 4))
        rows[:, :3] = materials.DEFAULT_SURFACE   # slots the bake had and the object lost
        weights = np.tile(lobes.DIFFUSE_ONLY, (self.slot_count, 1))
        prefiltered = self.prefiltered if prefiltered else ()
        image = None
        for slot, albedo in enumerate(albedos[:self.slot_count]):
            rows[slot, :3] = albedo.colour
            # a rough dielectric's layer (beside another slot's Phong lobe) needs the prefiltered light
            weights[slot] = albedo.weights if prefiltered or not lobes.rough_layer(albedo.weights) else lobes.DIFFUSE_ONLY
            if albedo.image is not None and self.has_uvs:
                rows[slot, 3] = 1.0
                image = albedo.image
        weighted = self._weighted(prefiltered)
        white = not weighted and image is None and bool(np.all(rows[:, :3] == 1.0))
        variant = dataclasses.replace(self.variant, material_count=0 if white else self.slot_count,
                                      material_slots=not white and self.slot_count > 1,
                                      albedo_texture=image is not None, lobe_weights=weighted,
                                      prefiltered=prefiltered, sources=0, reflection_rays=0)
        lit_alone = variant.prefiltered_lookup or not variant.glossy
        variant = dataclasses.replace(variant, sources=sources if lit_alone else 0,
                                      reflection_rays=traced if variant.prefiltered_lookup else 0)
        if variant != self.variant:
            self.variant = variant
            self.shader = shader_program(variant)
            self.ubo = None
        self.albedo_image = image
        if white:
            return {}
        return dict(albedo=rows, **({"lobe_weights": weights} if weighted else {}))

    def frame_block(self, model, view_projection, camera, light, local_to_environment,
                    exposure_scale, target=(1, 1), depth_bias=0.0, albedos=(), prefiltered=True, strength=1.0,
                    band_limited_scale=1.0, sources=None, rays=None, ray_count=REFLECTION_RAYS):
        """The uniform block's bytes for one draw.

        model: 4x4 object-to-world; view_projection: 4x4 world-to-clip; camera: (x, y, z, w) with
        w = 1 for an eye position, w = 0 for a direction towards an orthographic viewer; light:
        [(s+1)^2, 3] coefficients of x -> L(g R x) (already rotated); local_to_environment: g R,
        for the band-limited texture and the prefiltered atlas (they hold the unrotated
        environment, looked up at g R x); albedos:
        the object's materials.object_albedos (a slot without one: the 0.8 default surface);
        prefiltered: whether the prefiltered atlas is there to draw with (the truncated lobe
        meanwhile), for data made with the prefiltered lookup; strength: the environment's, which
        the atlas is without; band_limited_scale: that of the band-limited texture's codes;
        sources: (scene/light_sources.Source list, their shadow rows) lighting the data on their
        own (takes_sources; `light` is then the rest of the map), or None; rays: the ray_bvh and
        ray_offset rows (ray_bvh.block_rows) where the glossy lobe or the specular layer traces
        its visibility with `ray_count` rays per pixel, or None. The
        shader gets the eye relative to the object's origin, differenced here in float64 (far from
        the world origin float32 world positions would round the view away)."""
        self.refresh_design()
        surface_rows = self._use_surface(list(albedos), prefiltered, len(sources[0]) if sources else 0,
                                         ray_count if rays is not None else 0)
        self.mirrored = bool(np.linalg.det(np.asarray(model, dtype=np.float64)[:3, :3]) < 0.0)
        camera = np.array(camera, dtype=np.float64)
        if camera[3] > 0.5:
            camera[:3] -= np.asarray(model, dtype=np.float64)[:3, 3]
        values = {"model": model, "view_projection": view_projection,
                  "world_to_local": transforms.rotation_part(model).T, "camera": camera,
                  "params": (exposure_scale, target[0], target[1], depth_bias),
                  "light": light, "lobe": self.lobe_factors()}
        if self.variant.band_limited_texture or self.variant.prefiltered_lookup:
            values["local_to_environment"] = local_to_environment
        if self.variant.band_limited_texture:
            values["band_limited_scale"] = (band_limited_scale,)
        if self.variant.prefiltered_lookup:
            values["prefiltered_scale"] = (strength,)
        if self.designs:
            values["design"] = np.concatenate([d.texels() for d in self.designs])
        if self.variant.sources:
            values["source_direction"], values["source_irradiance"] = light_sources.shading_rows(
                sources[0], local_to_environment, strength)
            values["source_shadow"] = sources[1]
            if self.variant.prefiltered_lookup:
                values["source_points"] = light_sources.highlight_rows(sources[0], local_to_environment)
        if self.variant.reflection_rays:
            values.update(rays)
        values.update(surface_rows)
        return self.variant.frame_block(values)

    def draw(self, block, environment_textures=None):
        """Draws with the block (frame_block) and the environment textures the variant reads
        ({sampler name: GPUTexture}: the band-limited texture, the prefiltered atlas, the sources'
        shadow maps)."""
        import gpu
        buffer = gpu.types.Buffer('FLOAT', block.size, block)
        if self.ubo is None:
            self.ubo = gpu.types.GPUUniformBuf(buffer)
        else:
            self.ubo.update(buffer)
        bind(self.shader)
        self.shader.uniform_block("sd", self.ubo)
        textures = dict(environment_textures or {})
        textures.update({DATA_SAMPLER[1]: self.data_texture, GAUNT_SAMPLER[1]: self.gaunt_texture,
                         LIGHTMAP_INDEX_SAMPLER[1]: self.lightmap_index})
        if self.variant.albedo_texture:
            textures[ALBEDO_TEXTURE_SAMPLER[1]] = gpu.texture.from_image(self.albedo_image)
        if self.variant.weighted:
            textures[BRDF_TABLE_SAMPLER[1]] = brdf_table_texture()
        for _, name in self.variant.samplers():
            self.shader.uniform_sampler(name, textures[name])
        gpu.state.front_facing_set(self.mirrored)   # the local winding is the world's turned
        for batch, culled in self.batches:
            gpu.state.face_culling_set('BACK' if culled else 'NONE')
            batch.draw(self.shader)
        gpu.state.face_culling_set('NONE')
        gpu.state.front_facing_set(False)

    def refresh_design(self):
        """Swaps the final lobe designs in for the Gauss rules standing in, once they are built: a
        variant of the new sizes and a new uniform buffer."""
        if all(d.final for d in self.designs):
            return
        designs = self._designs()
        if any(new is not old for new, old in zip(designs, self.designs)):
            self.designs = designs
            sizes = [len(d.weights) for d in designs] + [0]
            self.variant = dataclasses.replace(self.variant, lobe_design_size=sizes[0],
                                               diffuse_design_size=sizes[1])
            self.shader = shader_program(self.variant)
            self.ubo = None
