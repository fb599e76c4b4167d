/* sd-lighting vertex shader (prepended by sd_shading_lib.glsl).
 *
 * Per-vertex shading (the seed's way, default): B is evaluated here for the vertex whose index is
 * gl_VertexID (an indexed batch: gl_VertexID is the index) and interpolated over the triangle.
 * SD_PER_PIXEL: the vertex passes position, normal and corner on; the fragment shader evaluates B
 * with the pixel's normal and view for each of the triangle's three vertices' data (non-indexed
 * batch with the triangle's vertex indices in `corners` and the barycentric corner in `bary`).
 * SD_LIGHTMAP (with SD_PER_PIXEL): instead of `corners` and `bary`, the corner's `lightmap_uv`, at
 * which the fragment shader reads the texture-space data.
 * SD_VERTEX_TARGET (tests): vertex p is drawn as a point at pixel (p % width, p / width) of a
 * float target, so the readback holds exactly what the shader computed for every vertex.
 * SD_ALBEDO: the vertex's material slot picks its albedo from sd.albedo (SD_MATERIAL_SLOTS: the
 * attribute material_slot, else slot 0), passed on with the UV of the albedo texture, and with
 * SD_LOBE_WEIGHTS the slot's lobe weights and n.v. SD_DIFFUSE_LOBE: the Lambert lobe's B goes in
 * sd_diffuse_color. SD_PREFILTERED (per vertex): instead of lobe 0's B and n.v, its visibility
 * ratio, and the position and normal with which the fragment looks the glossy light up;
 * SD_LAMBERT_LAYER: lobe 0's B is the diffuse, in sd_diffuse_color.
 */
void main()
{
  vec4 world = sd.model * vec4(pos, 1.0);

#ifdef SD_VERTEX_TARGET
  int p = gl_VertexID;
  float width = sd.params.y;
  float height = sd.params.z;
  vec2 pixel = vec2(float(p % int(width)), float(p / int(width))) + vec2(0.5);
  gl_Position = vec4(2.0 * pixel.x / width - 1.0, 2.0 * pixel.y / height - 1.0, 0.0, 1.0);
#else
  gl_Position = sd.view_projection * world;
  /* A small pull towards the eye, so that the overlay wins the depth test against the viewport's
   * own drawing of the same surface. */
  gl_Position.z -= sd.params.w * gl_Position.w;
#endif

#ifdef SD_ALBEDO
#  ifdef SD_MATERIAL_SLOTS
  int slot = int(material_slot + 0.5);
#  else
  int slot = 0;
#  endif
  sd_albedo = sd.albedo[slot];
#  ifdef SD_LOBE_WEIGHTS
  sd_lobe_weights = sd.lobe_weights[slot];
#  endif
#  ifdef SD_ALBEDO_TEXTURE
  sd_uv = uv;
#  endif
#endif

#ifdef SD_PER_PIXEL
  sd_origin_offset = mat3(sd.model) * pos;
  sd_normal = nrm;
#  ifdef SD_LIGHTMAP
  sd_lightmap_uv = lightmap_uv;
#  else
  sd_bary = bary;
  sd_corners = corners;
#  endif
#else
  vec3 normal = normalize(nrm);
  vec3 view = sd_view_direction(mat3(sd.model) * pos);
  vec3 b0, b1;
  sd_shade_lobes(gl_VertexID, normal, view, b0, b1);
#  ifdef SD_PREFILTERED
  /* lobe 0's light is looked up per pixel; the vertex gives the share its visibility lets through */
  sd_visibility = sd_visibility_ratio(b0, sd_lobe_axis(normal, view), normal);
  sd_origin_offset = mat3(sd.model) * pos;
  sd_normal = nrm;
#  else
  sd_color = sd.params.x * b0;
#    ifdef SD_SOURCES
  /* the sources are shaded per pixel (sd_source_light) */
  sd_origin_offset = mat3(sd.model) * pos;
  sd_normal = nrm;
#    endif
#  endif
#  if defined(SD_DIFFUSE_LOBE)
  sd_diffuse_color = sd.params.x * b1;
#  elif defined(SD_LAMBERT_LAYER)
  sd_diffuse_color = sd.params.x * b0;
#  endif
#  if defined(SD_LOBE_WEIGHTS) && !defined(SD_PREFILTERED)
  sd_n_dot_v = dot(normal, view);
#  endif
#endif
}
