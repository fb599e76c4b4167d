/* sd-lighting fragment shader (prepended by sd_shading_lib.glsl).
 *
 * Writes scene-linear radiance times 2^exposure (sd.params.x), times the surface's albedo; the
 * viewport applies the sRGB curve to it (the Standard view transform). Clamped at 0 per channel:
 * the truncated formulas ring below zero next to bright lights, and displayed radiance is never
 * negative (drawing.cpu_reference clamps the same way).
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

void main()
{
#ifdef SD_PER_PIXEL
  vec3 normal = normalize(sd_normal);
  vec3 view = sd_view_direction(sd_origin_offset);
  vec3 rgb = vec3(0.0);
  if (sd_bary.x > 0.0) {
    rgb += sd_bary.x * sd_shade(int(sd_corners.x + 0.5), normal, view);
  }
  if (sd_bary.y > 0.0) {
    rgb += sd_bary.y * sd_shade(int(sd_corners.y + 0.5), normal, view);
  }
  if (sd_bary.z > 0.0) {
    rgb += sd_bary.z * sd_shade(int(sd_corners.z + 0.5), normal, view);
  }
  fragColor = vec4(max(sd.params.x * rgb, vec3(0.0)) * sd_surface_albedo(), 1.0);
#else
  fragColor = vec4(max(sd_color, vec3(0.0)) * sd_surface_albedo(), 1.0);
#endif
}
