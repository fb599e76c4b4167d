/* sd-lighting: bilinear lookup in an equirect map, for the band-limited texture of the shading
 * (sd_shading_lib.glsl) and the world background (sd_background_frag.glsl). SD_EQUIRECT_MAP names
 * the sampler2D it reads (defined by the shader that uses it; without it this file is empty).
 *
 * The map is in Blender's equirect orientation, u = 0.5 - atan2(y, x) / 2pi, v = 1 - acos(z) / pi,
 * texel centres at ((i + 0.5) / W, (j + 0.5) / H), rows bottom-first (j = 0 at the south pole), as
 * GPU textures hold them; filtered here, not by the sampler, so the wrap at the seam and across the
 * poles is exact whatever the sampler state.
 */
#ifdef SD_EQUIRECT_MAP
/* Texel (i, j), wrapped in u (the seam) and continued across the poles: the virtual row past a
 * pole is the edge row half a turn round (colatitude -h/2 at phi is +h/2 at phi + pi). */
vec3 sd_equirect_texel(ivec2 size, int i, int j)
{
  if (j < 0 || j >= size.y) {
    j = (j < 0) ? 0 : size.y - 1;
    i += size.x / 2;
  }
  /* i is in [-1, 3 W / 2] here; no % (undefined for negative operands) */
  if (i < 0) {
    i += size.x;
  }
  else if (i >= size.x) {
    i -= size.x;
  }
  return texelFetch(SD_EQUIRECT_MAP, ivec2(i, j), 0).rgb;
}

/* The map at the unit direction e, bilinear between the four nearest texel centres. */
vec3 sd_equirect(vec3 e)
{
  ivec2 size = textureSize(SD_EQUIRECT_MAP, 0);
  float u = 0.5 - atan(e.y, e.x) * 0.15915494309189535;
  float v = 1.0 - acos(clamp(e.z, -1.0, 1.0)) * 0.3183098861837907;
  float x = u * float(size.x) - 0.5;
  float y = v * float(size.y) - 0.5;
  float x0 = floor(x);
  float y0 = floor(y);
  float fx = x - x0;
  float fy = y - y0;
  int i = int(x0);
  int j = int(y0);
  vec3 bottom = mix(sd_equirect_texel(size, i, j), sd_equirect_texel(size, i + 1, j), fx);
  vec3 top = mix(sd_equirect_texel(size, i, j + 1), sd_equirect_texel(size, i + 1, j + 1), fx);
  return mix(bottom, top, fy);
}
#endif
