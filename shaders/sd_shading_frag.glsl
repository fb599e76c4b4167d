/* sd-lighting fragment shader (prepended by sd_shading_lib.glsl).
 *
 * Writes scene-linear radiance times 2^exposure (sd.params.x), times the surface's albedo; the
 * viewport applies the sRGB curve to it (the Standard view transform). Each lobe's B is clamped at
 * 0 per channel: the truncated formulas ring below zero next to bright lights, and displayed
 * radiance is never negative (drawing.cpu_reference clamps the same way).
 */

/* The albedo B is multiplied by (SD_ALBEDO: the slot's colour, or its image texture at the pixel's
 * UV, which Blender's GPU textures return as scene-linear values). */
vec3 sd_surface_albedo()
{
#ifdef SD_ALBEDO
#  ifdef SD_ALBEDO_TEXTURE
  if (sd_albedo.a > 0.5) {
    return texture(sd_albedo_texture, sd_uv).rgb;
  }
#  endif
  return sd_albedo.rgb;
#else
  return vec3(1.0);
#endif
}

/* The surface's radiance from lobe 0's B and (SD_DIFFUSE_LOBE) the Lambert lobe's: the albedo
 * times the one lobe's, or the Lambert lobe times diffuse x albedo plus the Phong lobe times
 * metal x albedo + dielectric, with the slot's weights (diffuse, metal, dielectric) - the vertex
 * target (no albedos) shows the two lobes' sum. */
vec3 sd_surface(vec3 lobe0, vec3 diffuse)
{
  vec3 albedo = sd_surface_albedo();
  lobe0 = max(lobe0, vec3(0.0));
#ifdef SD_DIFFUSE_LOBE
  diffuse = max(diffuse, vec3(0.0));
#  ifdef SD_ALBEDO
  return diffuse * (sd_lobe_weights.x * albedo) + lobe0 * (sd_lobe_weights.y * albedo + vec3(sd_lobe_weights.z));
#  else
  return diffuse + lobe0;
#  endif
#else
  return lobe0 * albedo;
#endif
}

#ifdef SD_PER_PIXEL
/* Adds a triangle corner's B (vertex index `corner`) with its barycentric weight. */
void sd_add_corner(float weight, float corner, vec3 normal, vec3 view, inout vec3 rgb, inout vec3 diffuse)
{
  if (weight > 0.0) {
    int p = int(corner + 0.5);
    rgb += weight * sd_shade(p, normal, view);
#  ifdef SD_DIFFUSE_LOBE
    diffuse += weight * sd_shade_diffuse(p, normal);
#  endif
  }
}
#endif

void main()
{
  vec3 diffuse = vec3(0.0);
#ifdef SD_PER_PIXEL
  vec3 normal = normalize(sd_normal);
  vec3 view = sd_view_direction(sd_origin_offset);
  vec3 rgb = vec3(0.0);
  sd_add_corner(sd_bary.x, sd_corners.x, normal, view, rgb, diffuse);
  sd_add_corner(sd_bary.y, sd_corners.y, normal, view, rgb, diffuse);
  sd_add_corner(sd_bary.z, sd_corners.z, normal, view, rgb, diffuse);
  fragColor = vec4(sd_surface(sd.params.x * rgb, sd.params.x * diffuse), 1.0);
#else
#  ifdef SD_DIFFUSE_LOBE
  diffuse = sd_diffuse_color;
#  endif
  fragColor = vec4(sd_surface(sd_color, diffuse), 1.0);
#endif
}
