/* sd-lighting: the environment's bright sources (SD_SOURCES: how many), each lighting the Lambert
 * lobe and the prefiltered glossy one on its own, shadowed per pixel
 * (scene/light_sources.py, live/source_shadows.py; docs/msd-notes.md, "Bright sources").
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
 * sharp along its long side's edges and soft across them. The receiver's plane (the triangle's,
 * from the screen-space derivatives of its position) sets what each sample compares with, so a
 * surface tilted to the source - even at grazing light - does not shadow itself (no acne) without
 * a bias large enough to lift shadows off their contacts.
 */
#ifdef SD_SOURCES

/* per source; with three or four, fewer (their shadows overlap, each carries less of the light) */
#if SD_SOURCES > 2
#  define SD_BLOCKER_SAMPLES 12
#  define SD_FILTER_SAMPLES 16
#else
#  define SD_BLOCKER_SAMPLES 16
#  define SD_FILTER_SAMPLES 32       /* over a penumbra SD_WIDE_PENUMBRA texels wide or more */
#endif
#define SD_NARROW_FILTER_SAMPLES 8   /* over a narrower one (a sun's shadow near its caster) */
#define SD_WIDE_PENUMBRA 3.0

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

/* The share of source i that reaches point p (world, relative to the object's origin: the block's
 * rows are, light_sources.rows_from) on a surface of geometric normal n (world, unit). */
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
  /* the receiver's plane: t changes by dot(slope, offset) across (u, v) (tilt capped at 50:1); the
   * map holds a caster's t at its texel's centre, up to half a texel from where it is read */
  vec2 slope = -(sizes.z * sizes.z) * vec2(dot(n, row_u.xyz), dot(n, row_v.xyz)) / max(dot(n, row_t.xyz), 0.02);
  float bias = 1.5 * texel + 0.5 * (abs(slope.x) + abs(slope.y)) / float(SD_SHADOW_MAP_SIZE);
  float least = 1.0 / float(SD_SHADOW_MAP_SIZE);
  /* blocker search over what could hide any of the source: blockers at most sizes.y - t above */
  vec2 reach = extent.zw * max(sizes.y - t, 0.0);
  float blockers = 0.0, blocker_distance = 0.0;
  for (int k = 0; k < SD_BLOCKER_SAMPLES; k++) {
    vec2 offset = sd_ellipse_offset(extent, reach, 1.5 * least, sd_disc_point(k, SD_BLOCKER_SAMPLES));
    float plane = t + dot(slope, offset);
    float depth = sd_shadow_depth(i, uv + offset);
    if (depth > plane + bias) {
      blocker_distance += depth - plane;
      blockers += 1.0;
    }
  }
  /* nothing or everything over the search area, which holds the filter's: lit, or in the umbra */
  if (blockers == 0.0) {
    return 1.0;
  }
  if (blockers == float(SD_BLOCKER_SAMPLES)) {
    return 0.0;
  }
  /* the penumbra of the mean blocker distance: the source's semi-axes seen from there */
  vec2 radii = extent.zw * (blocker_distance / blockers);
  int count = (max(radii.x, radii.y) * float(SD_SHADOW_MAP_SIZE) < SD_WIDE_PENUMBRA) ? SD_NARROW_FILTER_SAMPLES :
                                                                                          SD_FILTER_SAMPLES;
  float lit = 0.0;
  for (int k = 0; k < count; k++) {
    vec2 offset = sd_ellipse_offset(extent, radii, least, sd_disc_point(k, count));
    lit += (sd_shadow_depth(i, uv + offset) > t + dot(slope, offset) + bias) ? 0.0 : 1.0;
  }
  return lit / float(count);
}

/* The share of a source's light a surface receives, as n . l is for a point source: a uniform disc
 * of angular radius sigma (sin^2 sigma given) at cos theta = n . l from the normal, clipped by the
 * surface's horizon. Above it: cos theta. Straddling it, the closed form of a sphere light's
 * irradiance (Snyder 1996, "Area light sources for real-time graphics"; as in Lagarde and de
 * Rousiers 2014, "Moving Frostbite to PBR", section 4.7.2) over pi sin^2 sigma: a softbox at the
 * horizon lights a floor with the half of it above, where cos theta at its centre would give ~0. */
float sd_source_cosine(float cos_theta, float sin2_sigma)
{
  if (cos_theta * cos_theta >= sin2_sigma) {
    return max(cos_theta, 0.0);
  }
  float sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 1e-12));
  float cot_sigma = sqrt(max(1.0 / sin2_sigma - 1.0, 0.0));
  float y = clamp(-cot_sigma * cos_theta / sin_theta, -1.0, 1.0);
  float s = sin_theta * sqrt(1.0 - y * y);
  float e = (cos_theta * acos(y) - cot_sigma * s) * sin2_sigma + atan(s, cot_sigma);
  return max(e, 0.0) / (3.14159265 * sin2_sigma);
}

/* The GGX lobe of the prefiltered atlas at source i (one the atlas holds: its highlight is not
 * shaded on its own): of the map's light P_r(axis) the prefilter averages around the direction it
 * is read at (glossy_prefilter.h, n = v = r: l drawn with density D(h) / 4, weighted by n . l, over
 * their sum), the part the source gives - its power times that kernel at its direction, D with
 * alpha^2 widened by the disc's half angle squared (the lobe over a disc, not a point; h turns
 * half as far as l), over the kernel's integral Z(alpha) (1 for a sharp lobe, 1/4 at alpha = 1;
 * 1 / (1 + 0.708 alpha + 2.292 alpha^2) within 2 %). Times E_i / 4 = strength x power. */
float sd_source_in_atlas(int i, vec3 axis, float roughness)
{
  vec3 l = sd.source_direction[i].xyz;
  float n_dot_l = dot(axis, l);
  if (n_dot_l <= 0.0) {
    return 0.0;
  }
  float alpha = max(roughness * roughness, 1e-3);
  float a2 = alpha * alpha + 0.25 * sd.source_direction[i].w;
  float n_dot_h = dot(axis, normalize(axis + l));
  float d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
  float kernel = a2 / (d * d) * n_dot_l * (1.0 + 0.708 * alpha + 2.292 * alpha * alpha);
  return kernel * 0.25 * dot(sd.source_irradiance[i].rgb, SD_LUMINANCE);
}

/* Principled v1's diffuse (a slot whose specular layer is added, before Blender 4.0) over Lambert's
 * for light from l seen from v: Cycles' principled_diffuse after Burley 2015, the Lambert part
 * (1 - F_l / 2)(1 - F_v / 2) and the retro-reflection R (F_l + F_v + F_l F_v (R - 1)),
 * R = roughness (1 + l . v), F_x = (1 - n . x)^5. A low sun lights a smooth plastic's ground about
 * a quarter less than Lambert's. 1 elsewhere (4.0's Lambert, or a slot without weights). */
float sd_diffuse_shape(vec3 n, vec3 v, vec3 l)
{
#ifdef SD_LOBE_WEIGHTS
  if (abs(sd_lobe_weights.w) > 1.5) {
    float f_l = pow(1.0 - clamp(dot(n, l), 0.0, 1.0), 5.0);
    float f_v = pow(1.0 - clamp(dot(n, v), 0.0, 1.0), 5.0);
    float r = sd_lobe_weights.z * (1.0 + dot(l, v));
    return (1.0 - 0.5 * f_l) * (1.0 - 0.5 * f_v) + r * (f_l + f_v + f_l * f_v * (r - 1.0));
  }
#endif
  return 1.0;
}

/* The sources' light on the Lambert lobe at the pixel (position sd_origin_offset from the
 * object's origin, bake-space normal `normal` and view `view`, unit): the sum of each source's
 * irradiance times its cosine (sd_source_cosine), the diffuse's shape (sd_diffuse_shape) and its
 * visibility; `visible`: each source's visibility, 0 below the surface's horizon (the glossy
 * lobe's too). */
vec3 sd_source_light(vec3 normal, vec3 view, out float visible[SD_SOURCES])
{
  vec3 world = sd_origin_offset;   /* world, relative to the object's origin */
  /* the triangle's own plane (the shading normal of a smooth mesh tilts away from it), on the
   * side the shading normal faces */
  vec3 shading_normal = transpose(mat3(sd.world_to_local)) * normal;
  vec3 face = cross(dFdx(world), dFdy(world));
  vec3 world_normal = dot(face, face) > 0.0 ? normalize(face) : normalize(shading_normal);
  world_normal *= (dot(world_normal, shading_normal) < 0.0) ? -1.0 : 1.0;
  vec3 lit = vec3(0.0);
  for (int i = 0; i < SD_SOURCES; i++) {
    float c = sd_source_cosine(dot(normal, sd.source_direction[i].xyz), sd.source_direction[i].w);
    visible[i] = (c > 0.0) ? sd_source_visibility(i, world, world_normal) : 0.0;
    lit += (c * visible[i] * sd_diffuse_shape(normal, view, sd.source_direction[i].xyz)) *
           sd.source_irradiance[i].rgb;
  }
  return lit;
}

#endif
