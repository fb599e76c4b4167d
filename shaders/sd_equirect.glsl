/* sd-lighting: bilinear lookup in an equirect map, for the world background
 * (sd_background_frag.glsl) and the levels of the prefiltered environment (sd_shading_lib.glsl:
 * sd_prefiltered_light). SD_EQUIRECT_MAP names the
 * sampler2D holding one map, SD_PREFILTERED_MAP the atlas of prefiltered levels (defined by the
 * shader that uses them; without either this file is empty).
 *
 * A map is in Blender's equirect orientation, u = 0.5 - atan2(y, x) / 2pi, v = 1 - acos(z) / pi,
 * texel centres at ((i + 0.5) / W, (j + 0.5) / H), rows bottom-first (j = 0 at the south pole), as
 * GPU textures hold them; filtered here, not by the sampler, so the wrap at the seam and across the
 * poles is exact whatever the sampler state, and an atlas's blocks do not bleed into each other.
 */
#if defined(SD_EQUIRECT_MAP) || defined(SD_PREFILTERED_MAP)
/* Texel (i, j) of the map held in the block of `size` texels at `origin` of texture `map` (0:
 * SD_EQUIRECT_MAP, 1: SD_PREFILTERED_MAP), wrapped in u (the seam) and continued across the poles:
 * the virtual row past a pole is the edge row half a turn round (colatitude -h/2 at phi is +h/2 at
 * phi + pi). */
vec3 sd_equirect_texel(int map, ivec2 origin, ivec2 size, int i, int j)
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
  ivec2 xy = origin + ivec2(i, j);
#  ifdef SD_PREFILTERED_MAP
  if (map == 1) {
    return texelFetch(SD_PREFILTERED_MAP, xy, 0).rgb;
  }
#  endif
#  ifdef SD_EQUIRECT_MAP
  return texelFetch(SD_EQUIRECT_MAP, xy, 0).rgb;
#  else
  return vec3(0.0);
#  endif
}

/* The map in the block (see sd_equirect_texel) at the unit direction e, bilinear between the four
 * nearest texel centres. */
vec3 sd_equirect_block(int map, ivec2 origin, ivec2 size, vec3 e)
{
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
  vec3 bottom = mix(sd_equirect_texel(map, origin, size, i, j), sd_equirect_texel(map, origin, size, i + 1, j), fx);
  vec3 top = mix(sd_equirect_texel(map, origin, size, i, j + 1), sd_equirect_texel(map, origin, size, i + 1, j + 1), fx);
  return mix(bottom, top, fy);
}
#endif

#ifdef SD_EQUIRECT_MAP
/* SD_EQUIRECT_MAP at the unit direction e. */
vec3 sd_equirect(vec3 e)
{
  return sd_equirect_block(0, ivec2(0), textureSize(SD_EQUIRECT_MAP, 0), e);
}
#endif
