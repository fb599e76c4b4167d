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

#ifdef SD_LOBE_WEIGHTS
/* The GGX lobe's table that starts at row `first_row` of sd_environment_brdf_table (SD_BRDF_TABLE_SIZE
 * square, n.v = (i + 0.5) / size across, roughness j / (size - 1) up) at n.v and the roughness,
 * bilinear between its entries, clamped at its edges. */
vec4 sd_brdf_table(float n_dot_v, float roughness, int first_row)
{
  float last = float(SD_BRDF_TABLE_SIZE - 1);
  vec2 xy = vec2(clamp(n_dot_v * float(SD_BRDF_TABLE_SIZE) - 0.5, 0.0, last), clamp(roughness, 0.0, 1.0) * last);
  ivec2 i0 = ivec2(floor(xy));
  ivec2 i1 = min(i0 + ivec2(1), ivec2(SD_BRDF_TABLE_SIZE - 1));
  vec2 f = xy - vec2(i0);
  i0.y += first_row;
  i1.y += first_row;
  vec4 bottom = mix(texelFetch(sd_environment_brdf_table, i0, 0),
                    texelFetch(sd_environment_brdf_table, ivec2(i1.x, i0.y), 0), f.x);
  vec4 top = mix(texelFetch(sd_environment_brdf_table, ivec2(i0.x, i1.y), 0),
                 texelFetch(sd_environment_brdf_table, i1, 0), f.x);
  return mix(bottom, top, f.y);
}

/* The split sum's terms integrated natively (sdnative.environment_brdf_table), rows
 * 0..SD_BRDF_TABLE_SIZE - 1 of the table: (A, B) of Schlick's Fresnel (single-scattering albedo F0 A + B), E_avg the cosine-weighted
 * mean of A + B over n.v (scene/lobes.average_albedo), and B of the dielectric Fresnel of IOR 1.5
 * remapped to F0..1 (A + B is the same for both shapes). */
vec4 sd_environment_brdf(float n_dot_v, float roughness)
{
  return sd_brdf_table(n_dot_v, roughness, 0);
}

/* The dielectric layer's Fresnel shape at cos c = v.h: the real Fresnel of IOR SD_DIELECTRIC_IOR
 * (Walter et al. 2007, eq. 22) remapped to 0 at c = 1 and 1 at c = 0, the shape the table's
 * dielectric B integrates and Cycles' Principled BSDF reflects (3.x: interpolate_fresnel_color;
 * 4.x: the dielectric closure's Fresnel). */
float sd_dielectric_shape(float c)
{
  float n = float(SD_DIELECTRIC_IOR);
  float g = sqrt(n * n - 1.0 + c * c);
  float a = (g - c) / (g + c);
  float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
  float normal = (n - 1.0) * (n - 1.0) / ((n + 1.0) * (n + 1.0));
  return (0.5 * a * a * (1.0 + b * b) - normal) / (1.0 - normal);
}

/* The dielectric layer's Fresnel at cos c = v.h for its F0: f0 + (1 - f0) times the dielectric
 * shape. */
float sd_layer_fresnel(float f0, float c)
{
  return f0 + (1.0 - f0) * sd_dielectric_shape(clamp(c, 0.0, 1.0));
}

/* The slot's layer code (sd_lobe_weights.w, scene/lobes.py) as (layer, over): 1 where the slot
 * has a specular layer, and 1 where that layer lies over the diffuse (4.0+) rather than added to it
 * (before 4.0). */
vec2 sd_layers()
{
  float code = abs(sd_lobe_weights.w);
  float layer = step(0.5, code);
  return vec2(layer, layer * (1.0 - step(1.5, code)));
}

/* The glossy lobe's Fresnel per channel at cos c = v.h, what its taps weigh their light with: as
 * sd_surface mixes the layers (before 4.0 one lobe of F0 mixed towards the base colour by metallic,
 * with the dielectric's shape; 4.0+ a dielectric and a metal closure, the metal's Schlick's Fresnel
 * of the base colour `albedo`, sd_surface_albedo's). A gold's blue, F0 about 0.3, reflects the
 * grazing half of its lobe most. */
vec3 sd_tap_fresnel(float c, vec3 albedo)
{
  c = clamp(c, 0.0, 1.0);
  float metal = sd_lobe_weights.x;
  float f0 = sd_lobe_weights.y;
  float over = sd_layers().y;
  float shape = sd_dielectric_shape(c);
  float m = 1.0 - c;
  float schlick = m * m * m * m * m;
  vec3 mixed = mix(vec3(f0), albedo, metal);
  vec3 layers = mix(vec3(f0 + (1.0 - f0) * shape), albedo + (vec3(1.0) - albedo) * schlick, metal);
  return mix(mixed + (vec3(1.0) - mixed) * shape, layers, over);
}

/* The specular layer's directional albedo for F0 (per channel) and a Fresnel shape's (A, B, E_avg):
 * the single-scattering F0 A + B, times (multiscatter 1: Multiscatter GGX) the light multiple
 * scattering adds as Cycles' Multiscatter GGX keeps it (Kulla and Conty 2017, "Revisiting
 * physically based shading at Imageworks", its appendix's Fresnel of many bounces),
 * 1 + F_ms (1 - E) / E, with E = A + B, F_ms = F_avg E_avg / (1 - F_avg (1 - E_avg)) and
 * F_avg = F0 + (1 - F0) / 21, Schlick's cosine-weighted mean (the dielectric shape's own, 0.054 at
 * IOR 1.5, moves a plastic's layer by under 0.5 %). F0 = 1 reflects all the light; a plastic's
 * layer gains hardly anything. */
vec3 sd_specular_albedo(vec3 f0, vec3 abe, float multiscatter)
{
  float e = max(abe.x + abe.y, 1e-4);
  vec3 f_avg = f0 + (vec3(1.0) - f0) / 21.0;
  vec3 f_ms = f_avg * abe.z / (vec3(1.0) - f_avg * (1.0 - abe.z));
  return (f0 * abe.x + vec3(abe.y)) * (vec3(1.0) + (multiscatter * (1.0 - e) / e) * f_ms);
}
#endif

/* The surface's radiance from lobe 0's B (SD_PREFILTERED: its prefiltered light) and
 * (SD_DIFFUSE_LOBE) the Lambert lobe's (SD_LAMBERT_LAYER: lobe 0's B; `lobe0` its layers' light): with
 * SD_LOBE_WEIGHTS the slot's Principled split (scene/lobes.py): lobe 0 times the specular layer's
 * albedo (sd_specular_albedo; below), Lambert times (1 - metallic) albedo, less the dielectric
 * layer's albedo for F0 where the layer lies over the diffuse (layer 1; 2: added to it; 0: no
 * layer; negative: the lobe scatters once);
 * otherwise the albedo times the one lobe's B, or on the vertex target (no albedos) the two
 * lobes' sum. */
vec3 sd_surface(vec3 lobe0, vec3 diffuse, float n_dot_v)
{
  vec3 albedo = sd_surface_albedo();
  lobe0 = max(lobe0, vec3(0.0));
  diffuse = max(diffuse, vec3(0.0));
#if defined(SD_LOBE_WEIGHTS)
  float metal = sd_lobe_weights.x;
  float f0 = sd_lobe_weights.y;
  vec2 layers = sd_layers();
  float layer = layers.x;
  float over = layers.y;
  float multiscatter = step(0.0, sd_lobe_weights.w);
  vec4 brdf = sd_environment_brdf(n_dot_v, sd_lobe_weights.z);
  vec3 dielectric_shape = vec3(brdf.x + brdf.y - brdf.w, brdf.w, brdf.z);
  vec3 dielectric = sd_specular_albedo(vec3(f0), dielectric_shape, multiscatter);
  /* 4.0+: a dielectric and a metal closure (Schlick's Fresnel of the base colour) mixed by
   * metallic; before 4.0 one lobe of the mixed F0 with the dielectric's shape. */
  vec3 specular = mix(sd_specular_albedo(mix(vec3(f0), albedo, metal), dielectric_shape, multiscatter),
                      mix(dielectric, sd_specular_albedo(albedo, brdf.xyz, multiscatter), metal), over);
  vec3 rgb = lobe0 * (layer * specular);
#  if defined(SD_DIFFUSE_LOBE) || defined(SD_LAMBERT_LAYER)
  rgb += diffuse * ((1.0 - metal) * (1.0 - over * dielectric.x)) * albedo;
#  else
  /* A slot without a specular layer under the one glossy lobe (its material changed since the
   * bake): that lobe times the albedo, as without weights. */
  rgb += lobe0 * ((1.0 - layer) * albedo);
#  endif
  return rgb;
#elif defined(SD_DIFFUSE_LOBE)
  return lobe0 + diffuse;
#else
  return lobe0 * albedo;
#endif
}

#ifdef SD_PREFILTERED
/* Smith's Lambda of GGX (alpha^2 = a2) at a direction of cosine c to the normal. */
float sd_smith_lambda(float c, float a2)
{
  c = clamp(c, 1e-4, 1.0);
  return 0.5 * (sqrt(1.0 + a2 * (1.0 - c * c) / (c * c)) - 1.0);
}

/* The normal the GGX lobe sees, Cycles' (ensure_valid_specular_reflection, kernel/closure/
 * bsdf_util.h): where the interpolated normal mirrors the view below the triangle's own plane - on
 * a smooth, coarse mesh's rims - Cycles turns it towards the geometric normal, in the plane of the
 * two, until the reflection lies just above the triangle (cosine min(0.9 v.ng, 0.01)). `ng`: the
 * triangle's normal, from the screen-space derivatives of the pixel's position, turned to the view
 * (the shading normal where they give none, or where the normal faces the triangle's back: then
 * both are left as they are). The bright sources' Lambert light takes the turned normal too (3.x's
 * closures all take it; 4.x turns only the glossy ones). */
vec3 sd_glossy_normal(vec3 normal, vec3 view, out vec3 ng)
{
  ng = mat3(sd.world_to_local) * cross(dFdx(sd_origin_offset), dFdy(sd_origin_offset));
  if (dot(ng, ng) < 1e-30) {
    ng = normal;
    return normal;
  }
  ng = normalize(ng);
  float iz = dot(view, ng);
  if (iz < 0.0) {
    ng = -ng;
    iz = -iz;
  }
  float threshold = min(0.9 * iz, 0.01);
  if (dot(normal, ng) <= 0.0) {
    ng = normal;   /* no triangle horizon: the front triangle's would hide a back face's whole lobe */
    return normal;
  }
  if (dot(ng, 2.0 * dot(normal, view) * normal - view) >= threshold) {
    return normal;
  }
  vec3 x = normal - dot(normal, ng) * ng;
  x = dot(x, x) > 1e-12 ? normalize(x) : normal;
  float ix = dot(view, x);
  float a = ix * ix + iz * iz;
  float b = 2.0 * (a + iz * threshold);
  float c = (threshold + iz) * (threshold + iz);
  float root = sqrt(max(b * b - 4.0 * a * c, 0.0));
  float nz2 = 0.25 * ((ix < 0.0) ? b + root : b - root) / max(a, 1e-12);
  return sqrt(max(1.0 - nz2, 0.0)) * x + sqrt(max(nz2, 0.0)) * ng;
}

/* The share of a GGX lobe (roughness alpha) about `axis` above a plane of normal n, at the axis's
 * elevation e = axis.n: near the plane a reflected direction rises e plus twice its microfacet's
 * slope towards n, a slope whose marginal GGX distribution has the CDF (1 + x / sqrt(alpha^2 + x^2)) / 2. */
float sd_lobe_above(float e, float alpha)
{
  return 0.5 * (1.0 + e * inversesqrt(e * e + 4.0 * alpha * alpha + 1e-12));
}

/* The share of the prefiltered light that the triangle's own plane (ng) lets through beyond the
 * shading normal's, which the split sum's albedo already cuts at: where the lobe grazes the
 * triangle (a rim, and every bent normal above), the object itself hides its lower part, as in Cycles. */
float sd_triangle_horizon(vec3 axis, vec3 normal, vec3 ng, float roughness)
{
  float alpha = max(roughness * roughness, 1e-4);
  return min(sd_lobe_above(dot(axis, ng), alpha) / max(sd_lobe_above(dot(axis, normal), alpha), 1e-4), 1.0);
}

/* The frame of the GGX lobe (alpha^2 = a2) the view reflects, for drawing its visible normals
 * (Heitz 2018): the view in the shading normal's tangent frame (t1, t2, normal; v.z the cosine,
 * at least 1e-4), vh the view stretched to alpha = 1, b1 and b2 two directions across it. */
void sd_lobe_frame(vec3 normal, vec3 view, float alpha, out vec3 t1, out vec3 t2, out vec3 v, out vec3 vh,
                   out vec3 b1, out vec3 b2)
{
  sd_orthonormal_basis(normal, t1, t2);
  v = vec3(dot(view, t1), dot(view, t2), clamp(dot(view, normal), 1e-4, 1.0));
  vh = normalize(vec3(alpha * v.xy, v.z));
  float across = dot(vh.xy, vh.xy);
  b1 = (across > 1e-12) ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(across) : vec3(1.0, 0.0, 0.0);
  b2 = cross(vh, b1);
}

/* sd_lobe_tap's shift of this pixel's Hammersley set: ((j + 1/2) / 16, (k + 1/2) / 16), j the
 * pixel's index in a 4 x 4 Bayer matrix, k its bits reversed. */
vec2 sd_tap_shift()
{
  ivec2 cell = ivec2(gl_FragCoord.xy) % 4;
  int x = cell.x ^ cell.y;
  int j = ((x & 1) << 3) | ((cell.y & 1) << 2) | (x & 2) | ((cell.y & 2) >> 1);
  int k = ((j & 1) << 3) | ((j & 2) << 1) | ((j & 4) >> 1) | ((j & 8) >> 3);
  return (vec2(float(j), float(k)) + 0.5) / 16.0;
}

/* The microfacet normal (tangent frame) of Hammersley point i of `count` ((i + 1/2) / count, the
 * radical inverse of i in base 2), mapped onto the visible normals of sd_lobe_frame's frame. Each
 * pixel of a 4 x 4 tile shifts the set (interleaved sampling, Keller and Heidrich 2001): by its
 * Bayer index j within each radial stratum, (i + (j + 1/2) / 16) / count, and turns it by j's
 * bits reversed, so that the tile's 16 pixels together cast 16 times as many directions. With one
 * set for every pixel a flat facet, whose pixels share a lobe, kept that set's error whole, from
 * facet to facet; interleaved it is a fine grain a 4 x 4 block averages out (msd-notes, "Glossy
 * light"). `shift`: sd_tap_shift's, the pixel's. */
vec3 sd_lobe_tap(int i, int count, vec2 shift, vec3 vh, vec3 b1, vec3 b2, float alpha)
{
  float u2 = 0.0;
  float digit = 0.5;
  for (int bits = i; bits > 0; bits /= 2) {
    u2 += digit * float(bits % 2);
    digit *= 0.5;
  }
  float radius = sqrt((float(i) + shift.x) / float(count));
  float phi = 6.283185307179586 * fract(u2 + shift.y);
  float p1 = radius * cos(phi);
  float s = 0.5 * (1.0 + vh.z);
  float p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * radius * sin(phi);
  vec3 m = p1 * b1 + p2 * b2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
  return normalize(vec3(alpha * m.xy, max(m.z, 1e-6)));
}

/* Tap h's weight in the estimate of the lobe's mean over its visible normals, G2 / G1(v), and the
 * roughness of the prefiltered level whose lobe covers about the tap's solid angle 1 / (count pdf)
 * (filtered importance sampling, Krivanek and Colbert 2008: the level of alpha^2 = that solid
 * angle / 4 pi). l: the reflected direction, l.z > 0. */
vec2 sd_tap_weight(vec3 v, vec3 h, vec3 l, int count, float a2, float lambda_v)
{
  float w = (1.0 + lambda_v) / (1.0 + lambda_v + sd_smith_lambda(l.z, a2));
  float q = (a2 - 1.0) * h.z * h.z + 1.0;
  float d = a2 / (3.141592653589793 * q * q);
  float solid_angle = 4.0 * v.z * (1.0 + lambda_v) / (float(count) * d);
  return vec2(w, sqrt(sqrt(solid_angle / 12.566370614359172)));
}

/* The mean light of the GGX lobe the view reflects, per channel, from SD_GLOSSY_TAPS of its
 * directions (sd_lobe_tap), each read from the prefiltered level of its solid angle and weighed by
 * sd_tap_weight and by its Fresnel (sd_tap_fresnel: a plastic's layer and a gold's blue reflect a
 * grazing lobe's far side most). Where the split sum's lobe about one direction misses the real one (a rough metal, and
 * every lobe at a grazing view: stretched along the plane of n and v, cut at the horizon, its
 * tails towards the view heavier; msd-notes, "Glossy light"). */
vec3 sd_sampled_glossy_light(vec3 normal, vec3 view, vec3 ng, float roughness, vec3 albedo)
{
  float alpha = max(roughness * roughness, 1e-4);
  float a2 = alpha * alpha;
  vec3 t1, t2, v, vh, b1, b2;
  sd_lobe_frame(normal, view, alpha, t1, t2, v, vh, b1, b2);
  float lambda_v = sd_smith_lambda(v.z, a2);
  vec3 sum = vec3(0.0);
  vec3 weights = vec3(0.0);
  vec2 shift = sd_tap_shift();
  for (int i = 0; i < SD_GLOSSY_TAPS; i++) {
    vec3 h = sd_lobe_tap(i, SD_GLOSSY_TAPS, shift, vh, b1, b2, alpha);
    vec3 l = 2.0 * dot(v, h) * h - v;
    if (l.z > 0.0) {
      vec2 tap = sd_tap_weight(v, h, l, SD_GLOSSY_TAPS, a2, lambda_v);
      vec3 w = tap.x * sd_tap_fresnel(dot(v, h), albedo);
      vec3 direction = l.x * t1 + l.y * t2 + l.z * normal;
      /* a direction below the triangle is the object's own (sd_triangle_horizon) */
      sum += (w * step(0.0, dot(direction, ng))) * sd_prefiltered_light(direction, tap.y);
      weights += w;
    }
  }
  return sum / max(weights, vec3(1e-12));
}

#ifdef SD_REFLECTION_RAYS
/* The share of the glossy lobe's light (or a Lambert lobe's specular layer's) that reaches the
 * pixel past the scene's triangles, traced
 * (the Reflection Rays option): SD_REFLECTION_RAYS directions of the lobe the view reflects
 * (sd_lobe_tap; one, along `axis`, below SD_SINGLE_RAY_ROUGHNESS, where the lobe is narrower than
 * the taps' spread would matter), each a ray from the pixel through the ray BVH (sd_ray_occluded),
 * weighed by its light times its Fresnel (sd_tap_fresnel), in luminance, and by sd_tap_weight, as
 * the sampled light it shadows is.
 * Directions below the triangle are left out: sd_triangle_horizon takes that share. The baked
 * visibility ratio, of order s' at the vertices, is too smooth for a sharp lobe: it lets through a
 * crease's reflection of the object itself (msd-notes, "Glossy light"). The rays start
 * sd.ray_offset.x along the triangle's normal (live/ray_bvh.py). A slot without a specular layer
 * beside the Lambert lobe casts none (sd_surface draws no lobe 0 there). `albedo`: sd_surface_albedo's, read where every pixel reads it (an image's
 * derivatives). */
float sd_traced_visibility(vec3 normal, vec3 view, vec3 ng, vec3 axis, float roughness, vec3 albedo)
{
#  if defined(SD_DIFFUSE_LOBE) || defined(SD_LAMBERT_LAYER)
  if (sd_layers().x < 0.5) {   /* no specular layer */
    return 1.0;
  }
#  endif
  mat3 to_world = transpose(mat3(sd.world_to_local));
  vec3 origin = sd.ray_bvh.yzw + sd_origin_offset + sd.ray_offset.x * (to_world * ng);
  if (roughness < SD_SINGLE_RAY_ROUGHNESS) {   /* below the triangle: sd_triangle_horizon's */
    return (dot(axis, ng) > 0.0 && sd_ray_occluded(origin, to_world * axis, 0.0)) ? 0.0 : 1.0;
  }
  float alpha = max(roughness * roughness, 1e-4);
  float a2 = alpha * alpha;
  vec3 t1, t2, v, vh, b1, b2;
  sd_lobe_frame(normal, view, alpha, t1, t2, v, vh, b1, b2);
  float lambda_v = sd_smith_lambda(v.z, a2);
  vec2 light = vec2(0.0);   /* reaching the pixel, all */
  vec2 shift = sd_tap_shift();
  for (int i = 0; i < SD_REFLECTION_RAYS; i++) {
    vec3 h = sd_lobe_tap(i, SD_REFLECTION_RAYS, shift, vh, b1, b2, alpha);
    vec3 l = 2.0 * dot(v, h) * h - v;
    vec3 direction = l.x * t1 + l.y * t2 + l.z * normal;
    if (l.z > 0.0 && dot(direction, ng) > 0.0) {
      vec2 tap = sd_tap_weight(v, h, l, SD_REFLECTION_RAYS, a2, lambda_v);
      float w = tap.x * max(dot(sd_tap_fresnel(dot(v, h), albedo) * sd_prefiltered_light(direction, tap.y),
                                SD_LUMINANCE), 1e-6);
      light += vec2(sd_ray_occluded(origin, to_world * direction, 0.0) ? 0.0 : w, w);
    }
  }
  return (light.y > 0.0) ? light.x / light.y : 1.0;
}
#endif

/* The unshadowed glossy light at the pixel: the environment prefiltered by the slot's GGX lobe,
 * times its strength (the atlas is without it), read at `axis`, the mean direction of the lobe the
 * view reflects (sdnative.glossy_bend_table, rows SD_BRDF_TABLE_SIZE.. of the table: the lobe leans
 * from the mirrored view towards the normal at grazing views, a dielectric's less, its Fresnel
 * weighing the grazing light more; mixed by metallic). Where one lookup is too far off the lobe is
 * sampled instead (sd_sampled_glossy_light): at a view grazing below n.v = SD_SAMPLED_N_DOT_V
 * (wholly from 0.1 below it down), and on a metal rougher than SD_SAMPLED_ROUGHNESS (over the 0.1
 * below); elsewhere the one lookup is as close for about a hundredth of the cost. Either way
 * without the lobe's share below the triangle (ng: sd_triangle_horizon, or the taps there
 * dropped), which the object itself hides. The visibility
 * is the baked lobe's ratio, around the mirrored view, or traced (sd_traced_visibility).
 * `albedo`: as sd_traced_visibility's. */
vec3 sd_open_glossy_light(vec3 normal, vec3 view, vec3 ng, vec3 albedo, out vec3 axis)
{
  float roughness = sd_lobe_weights.z;
  vec2 bends = sd_brdf_table(dot(normal, view), roughness, SD_BRDF_TABLE_SIZE).xy;
  float bend = mix(bends.y, bends.x, sd_lobe_weights.x);   /* the dielectric layer's, the metal's */
  axis = mix(normal, sd_mirrored_view(normal, view), bend);
  /* a back-facing shading normal (view = -normal) can cancel the mix */
  axis = dot(axis, axis) > 1e-12 ? normalize(axis) : normal;
  vec3 open = sd_prefiltered_light(axis, roughness) * sd_triangle_horizon(axis, normal, ng, roughness);
  float sampled = sd_lobe_weights.x * smoothstep(SD_SAMPLED_ROUGHNESS - 0.1, SD_SAMPLED_ROUGHNESS, roughness);
  sampled = max(sampled, 1.0 - smoothstep(SD_SAMPLED_N_DOT_V - 0.1, SD_SAMPLED_N_DOT_V, dot(normal, view)));
  if (sampled > 0.0) {
    open = mix(open, sd_sampled_glossy_light(normal, view, ng, roughness, albedo), sampled);
  }
  return sd.prefiltered_scale.x * open;
}
#endif

#if defined(SD_SOURCES) && defined(SD_PREFILTERED)
/* Source i's highlight (one the atlas is without, source_irradiance.w = 1;
 * light_sources.HIGHLIGHT_RADIUS) as the prefiltered light is (what sd_surface multiplies by the
 * layer's albedo E, the strength in): its power L Omega = pi x its irradiance times the GGX lobe
 * D G2 / (4 n.v) summed over its SD_HIGHLIGHT_POINTS points (light_sources.highlight_rows: the
 * source's own texels gathered into directions with their share of its power per channel, so that
 * a sun is as peaked and its core as white as the map has them and a lamp as long; those below the
 * horizon dark; a point without texels has no share), each D's alpha^2 widened as its texels
 * spread the light (so that a mirror-like lobe sees their profile, not a point), over
 * the lobe's albedo - a metal's with F = 1 (its Fresnel hardly varies), a dielectric's as its
 * Fresnel at the source's centre weighs it, F(v.h) of the layer's shape (sd_dielectric_shape)
 * over the layer's albedo (a sun at a grazing reflection is stronger than the layer's mean albedo
 * says). Summed over points, not with alpha widened by the whole source: a widened GGX's tails
 * are the wide lobe's, several times a narrow lobe's around a sun's reflection. On its own, a sun
 * is neither blurred by the atlas's level nor seen by the sampled lobe's taps as spots
 * (msd-notes, "Bright sources"). */
vec3 sd_source_highlight(int i, vec3 normal, vec3 view, float roughness)
{
  vec3 centre = sd.source_direction[i].xyz;
  float alpha = max(roughness * roughness, 1e-3);
  float a2 = alpha * alpha;
  float n_dot_v = clamp(dot(normal, view), 1e-4, 1.0);
  float lambda_v = sd_smith_lambda(n_dot_v, a2);
  vec3 lobe = vec3(0.0);
  for (int k = 0; k < SD_HIGHLIGHT_POINTS; k++) {
    vec4 point = sd.source_points[2 * (SD_HIGHLIGHT_POINTS * i + k)];
    vec3 share = sd.source_points[2 * (SD_HIGHLIGHT_POINTS * i + k) + 1].rgb;
    float n_dot_l = dot(normal, point.xyz);
    vec3 h = view + point.xyz;   /* zero only where a back-facing shading normal has the view behind it */
    if (n_dot_l > 0.0 && dot(h, h) > 1e-12) {
      float widened = a2 + point.w;
      float n_dot_h = dot(normal, h) * inversesqrt(dot(h, h));
      float q = n_dot_h * n_dot_h * (widened - 1.0) + 1.0;
      lobe += share * (widened / (3.141592653589793 * q * q) / (1.0 + lambda_v + sd_smith_lambda(n_dot_l, a2)));
    }
  }
  vec4 brdf = sd_environment_brdf(n_dot_v, roughness);
  float f0 = sd_lobe_weights.y;
  vec3 h = view + centre;
  float v_dot_h = dot(h, h) > 1e-12 ? dot(view, h) * inversesqrt(dot(h, h)) : 0.0;
  float fresnel = sd_layer_fresnel(f0, v_dot_h);
  float layer = f0 * (brdf.x + brdf.y - brdf.w) + brdf.w;
  float albedo = mix(fresnel / max(layer, 1e-4), 1.0 / max(brdf.x + brdf.y, 1e-4), sd_lobe_weights.x);
  return (3.141592653589793 * lobe * albedo / (4.0 * n_dot_v)) * sd.source_irradiance[i].rgb;
}

/* The sources' light at the pixel: on the Lambert lobe (sd_source_light), returned; on the glossy
 * one, each small source's highlight added to `highlights`, shadowed (sd_source_highlight), and the
 * visibility ratio of the prefiltered light `open` (read around `axis`) made to see the shadows of
 * the sources it holds: the ratio is of the remainder's lobe alone, mixed by those sources' share
 * of `open` (sd_source_in_atlas), so that a softbox's reflection goes dark in its shadow and the
 * sky's beside it keeps the baked ratio (with reflection rays the traced visibility sees those
 * shadows itself and is left as it is). `stored`: 1, or 0 where no data is (a lightmap pixel
 * without a texel: no light at all). Called where every pixel does (sd_source_light takes
 * screen-space derivatives). */
vec3 sd_sources_on_lobes(vec3 normal, vec3 view, vec3 axis, vec3 open, float stored, inout float visibility,
                         inout vec3 highlights)
{
  float roughness = sd_lobe_weights.z;
  float visible[SD_SOURCES];
  vec3 lit = sd_source_light(normal, view, visible);
  vec2 held = vec2(0.0);   /* the atlas's sources' part of `open`: unshadowed, shadowed */
  for (int i = 0; i < SD_SOURCES; i++) {
    if (sd.source_irradiance[i].w > 0.5) {
      highlights += (stored * visible[i]) * sd_source_highlight(i, normal, view, roughness);
    }
#  ifndef SD_REFLECTION_RAYS   /* the traced visibility sees those sources' shadows too */
    else {
      held += sd_source_in_atlas(i, axis, roughness) * vec2(1.0, visible[i]);
    }
#  endif
  }
#  ifndef SD_REFLECTION_RAYS
  float share = clamp(held.x / max(dot(open, SD_LUMINANCE), 1e-8), 0.0, 1.0);
  visibility = mix(visibility, held.x > 0.0 ? held.y / held.x : 1.0, stored * share);
#  endif
  return stored * lit;
}
#endif

#ifdef SD_PER_PIXEL
/* Adds the B of data entry `entry` (a triangle corner's vertex, or a lightmap texel) with its
 * interpolation weight. */
void sd_add_entry(float weight, int entry, vec3 normal, vec3 view, inout vec3 rgb, inout vec3 diffuse)
{
  if (weight > 0.0) {
    vec3 b0, b1;
    sd_shade_lobes(entry, normal, view, b0, b1);
    rgb += weight * b0;
    diffuse += weight * b1;
  }
}
#endif

#ifdef SD_LIGHTMAP
/* Adds the B of lightmap texel (x, y), clamped to the map (as a GPU's clamp-to-edge lookup does),
 * when the texture-space data store it (bake/lightmap.py: sd_lightmap_index holds its row, or
 * -1), and its weight to `total`. */
void sd_add_texel(float weight, vec2 texel, vec3 normal, vec3 view, inout vec3 rgb, inout vec3 diffuse,
                  inout float total)
{
  ivec2 xy = clamp(ivec2(texel), ivec2(0), ivec2(SD_LIGHTMAP_WIDTH - 1, SD_LIGHTMAP_HEIGHT - 1));
  float row = texelFetch(sd_lightmap_index, xy, 0).r;
  if (row >= 0.0) {
    sd_add_entry(weight, int(row + 0.5), normal, view, rgb, diffuse);
    total += weight;
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
#  ifdef SD_LIGHTMAP
  /* Bilinear between the four texel centres around the pixel's lightmap UV (B is linear in the
   * data, so blending the four B is blending the data), over those stored: all four wherever a
   * chart is (the dilation's ring). */
  vec2 t = sd_lightmap_uv * vec2(float(SD_LIGHTMAP_WIDTH), float(SD_LIGHTMAP_HEIGHT)) - vec2(0.5);
  vec2 base = floor(t);
  vec2 f = t - base;
  float total = 0.0;
  sd_add_texel((1.0 - f.x) * (1.0 - f.y), base, normal, view, rgb, diffuse, total);
  sd_add_texel(f.x * (1.0 - f.y), base + vec2(1.0, 0.0), normal, view, rgb, diffuse, total);
  sd_add_texel((1.0 - f.x) * f.y, base + vec2(0.0, 1.0), normal, view, rgb, diffuse, total);
  sd_add_texel(f.x * f.y, base + vec2(1.0, 1.0), normal, view, rgb, diffuse, total);
  if (total > 0.0) {
    rgb /= total;
    diffuse /= total;
  }
  float stored = (total > 0.0) ? 1.0 : 0.0;   /* no texel stored here: no light, as before */
#  else
  sd_add_entry(sd_bary.x, int(sd_corners.x + 0.5), normal, view, rgb, diffuse);
  sd_add_entry(sd_bary.y, int(sd_corners.y + 0.5), normal, view, rgb, diffuse);
  sd_add_entry(sd_bary.z, int(sd_corners.z + 0.5), normal, view, rgb, diffuse);
  float stored = 1.0;
#  endif
#  ifdef SD_PREFILTERED
  float visibility = stored * sd_visibility_ratio(rgb, sd_lobe_axis(normal, view), normal);
#    ifdef SD_LAMBERT_LAYER
  diffuse = rgb;
#    endif
  vec3 ng;
  normal = sd_glossy_normal(normal, view, ng);
  vec3 axis;
  vec3 albedo = sd_surface_albedo();
  vec3 open = sd_open_glossy_light(normal, view, ng, albedo, axis);
#    ifdef SD_REFLECTION_RAYS
  visibility = stored * sd_traced_visibility(normal, view, ng, axis, sd_lobe_weights.z, albedo);
#    endif
  vec3 highlights = vec3(0.0);
#    ifdef SD_SOURCES
  diffuse += sd_sources_on_lobes(normal, view, axis, open, stored, visibility, highlights);
#    endif
  rgb = sd.params.x * (visibility * open + highlights);
#  else
#    ifdef SD_SOURCES
  float visible[SD_SOURCES];
  rgb += stored * sd_source_light(normal, view, visible);
#    endif
  rgb *= sd.params.x;
#  endif
  fragColor = vec4(sd_surface(rgb, sd.params.x * diffuse, dot(normal, view)), 1.0);
#else
#  if defined(SD_DIFFUSE_LOBE) || defined(SD_LAMBERT_LAYER)
  diffuse = sd_diffuse_color;
#  endif
#  ifdef SD_PREFILTERED
  vec3 view = sd_view_direction(sd_origin_offset);
  vec3 ng;
  vec3 normal = sd_glossy_normal(normalize(sd_normal), view, ng);
  float visibility = sd_visibility;
  vec3 axis;
  vec3 albedo = sd_surface_albedo();
  vec3 open = sd_open_glossy_light(normal, view, ng, albedo, axis);
#    ifdef SD_REFLECTION_RAYS
  visibility = sd_traced_visibility(normal, view, ng, axis, sd_lobe_weights.z, albedo);
#    endif
  vec3 highlights = vec3(0.0);
#    ifdef SD_SOURCES
  diffuse += sd.params.x * sd_sources_on_lobes(normal, view, axis, open, 1.0, visibility, highlights);
#    endif
  fragColor = vec4(sd_surface(sd.params.x * (visibility * open + highlights), diffuse, dot(normal, view)), 1.0);
#  else
  float n_dot_v = 1.0;
#    ifdef SD_LOBE_WEIGHTS
  n_dot_v = sd_n_dot_v;
#    endif
  vec3 color = sd_color;
#    ifdef SD_SOURCES
  vec3 normal = normalize(sd_normal);
  float visible[SD_SOURCES];
  color += sd.params.x * sd_source_light(normal, sd_view_direction(sd_origin_offset), visible);
#    endif
  fragColor = vec4(sd_surface(color, diffuse, n_dot_v), 1.0);
#  endif
#endif
}
