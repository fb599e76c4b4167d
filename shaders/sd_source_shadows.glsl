/* sd-lighting: the environment's bright sources (SD_SOURCES: how many), each lighting the Lambert
 * lobe on its own and shadowed per pixel (scene/light_sources.py, live/source_shadows.py).
 *
 * Source i's shadow map is tile i of sd_shadow_map (SD_SHADOW_MAP_SIZE square, side by side along
 * u): an orthographic view from its direction over the sphere of everything that casts, storing
 * per texel the largest t (distance towards the source) of a caster. sd.source_shadow holds
 * SD_SOURCE_ROWS rows per source (light_sources.shadow_rows): a world point's u, v and t, the
 * source's major axis and semi-axes on the map, and the map's sizes.
 *
 * The penumbra is that of percentage-closer soft shadows (Fernando 2005, "Percentage-closer soft
 * shadows"): the mean blocker distance found over the area that could block the source sets the
 * width of the filter; both are ellipses with the source's own axes, so a window's shadow is
 * sharp along its long side's edges and soft across them. The receiver's plane (from the pixel's
 * normal) sets what each sample compares with, so a surface tilted to the source does not shadow
 * itself (no acne) without a bias large enough to lift shadows off their contacts.
 */
#ifdef SD_SOURCES

#define SD_BLOCKER_SAMPLES 16
#define SD_FILTER_SAMPLES 32

/* Point k of `count` spread evenly over the unit disc (Vogel's spiral): a fixed pattern, so the
 * shadows do not shimmer as the view or the world turns. */
vec2 sd_disc_point(int k, int count)
{
  float r = sqrt((float(k) + 0.5) / float(count));
  float a = 2.39996323 * float(k);
  return r * vec2(cos(a), sin(a));
}

/* The t source i's map stores at (u, v) (nearest texel; the map's edge beyond it). */
float sd_shadow_depth(int i, vec2 uv)
{
  ivec2 xy = clamp(ivec2(uv * float(SD_SHADOW_MAP_SIZE)), ivec2(0), ivec2(SD_SHADOW_MAP_SIZE - 1));
  return texelFetch(sd_shadow_map, ivec2(xy.x + i * SD_SHADOW_MAP_SIZE, xy.y), 0).r;
}

/* Where sample `disc` of an ellipse of semi-axes `radii` along the source's axes lies, in (u, v)
 * (each semi-axis at least `least`). */
vec2 sd_ellipse_offset(vec4 extent, vec2 radii, float least, vec2 disc)
{
  radii = max(radii, vec2(least));
  return disc.x * radii.x * extent.xy + disc.y * radii.y * vec2(-extent.y, extent.x);
}

/* The share of source i that reaches world point p, of world normal n (unit). */
float sd_source_visibility(int i, vec3 p, vec3 n)
{
  int row = SD_SOURCE_ROWS * i;
  vec4 row_u = sd.source_shadow[row];
  vec4 row_v = sd.source_shadow[row + 1];
  vec4 row_t = sd.source_shadow[row + 2];
  vec4 extent = sd.source_shadow[row + 3];
  vec4 sizes = sd.source_shadow[row + 4];
  float texel = sizes.x;
  /* looked up a texel off the surface, along its normal: what the map rounds a caster to stays below */
  vec4 q = vec4(p + n * texel, 1.0);
  vec2 uv = vec2(dot(row_u, q), dot(row_v, q));
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) {
    return 1.0;   /* outside everything that casts */
  }
  float t = dot(row_t, q);
  /* the receiver's plane: t changes by dot(slope, offset) across (u, v) (tilt capped at 4:1) */
  vec2 slope = -(sizes.z * sizes.z) * vec2(dot(n, row_u.xyz), dot(n, row_v.xyz)) / max(dot(n, row_t.xyz), 0.25);
  float bias = 1.5 * texel;
  float least = 1.0 / float(SD_SHADOW_MAP_SIZE);
  /* blocker search over what could hide any of the source: blockers at most sizes.y - t above */
  vec2 reach = extent.zw * max(sizes.y - t, 0.0);
  float blockers = 0.0, distance = 0.0;
  for (int k = 0; k < SD_BLOCKER_SAMPLES; k++) {
    vec2 offset = sd_ellipse_offset(extent, reach, 1.5 * least, sd_disc_point(k, SD_BLOCKER_SAMPLES));
    float plane = t + dot(slope, offset);
    float depth = sd_shadow_depth(i, uv + offset);
    if (depth > plane + bias) {
      distance += depth - plane;
      blockers += 1.0;
    }
  }
  if (blockers == 0.0) {
    return 1.0;
  }
  /* the penumbra of the mean blocker distance: the source's semi-axes seen from there */
  vec2 radii = extent.zw * (distance / blockers);
  float lit = 0.0;
  for (int k = 0; k < SD_FILTER_SAMPLES; k++) {
    vec2 offset = sd_ellipse_offset(extent, radii, least, sd_disc_point(k, SD_FILTER_SAMPLES));
    lit += (sd_shadow_depth(i, uv + offset) > t + dot(slope, offset) + bias) ? 0.0 : 1.0;
  }
  return lit / float(SD_FILTER_SAMPLES);
}

/* The sources' light on the Lambert lobe at the pixel (position sd_origin_offset from the
 * object's origin, bake-space normal `normal`, unit): the sum of each source's irradiance times
 * n . l and its visibility. `visible`: the luminance share of that light the shadows let through
 * (1 where no source faces the normal); `weight`: the sources' share of the unshadowed light,
 * against the remainder's mean radiance L_00 (what the Lambert lobe gives in a uniform world). */
vec3 sd_source_light(vec3 normal, out float visible, out float weight)
{
  const vec3 luminance = vec3(0.2126, 0.7152, 0.0722);
  vec3 world = sd_origin_offset + sd.model[3].xyz;
  vec3 world_normal = normalize(transpose(mat3(sd.world_to_local)) * normal);
  vec3 lit = vec3(0.0);
  vec3 open = vec3(0.0);
  for (int i = 0; i < SD_SOURCES; i++) {
    float c = dot(normal, sd.source_direction[i].xyz);
    if (c > 0.0) {
      vec3 e = c * sd.source_irradiance[i].rgb;
      open += e;
      lit += e * sd_source_visibility(i, world, world_normal);
    }
  }
  float open_y = dot(open, luminance);
  visible = open_y > 0.0 ? dot(lit, luminance) / open_y : 1.0;
  weight = open_y / max(open_y + dot(sd.light[0].rgb, luminance), 1e-8);
  return lit;
}

#endif
