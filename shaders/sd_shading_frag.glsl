/* sd-lighting fragment shader (prepended by sd_shading_lib.glsl).
 *
 * Writes scene-linear radiance times 2^exposure (sd.params.x); the viewport applies the sRGB
 * curve to it (the Standard view transform).
 */
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
  fragColor = vec4(sd.params.x * rgb, 1.0);
#else
  fragColor = vec4(sd_color, 1.0);
#endif
}
