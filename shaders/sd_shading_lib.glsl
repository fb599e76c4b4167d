/* sd-lighting: the shading formulas of the method of spherical designs (MSD) and of PRT, in GLSL.
 *
 * This file is the GPU twin of native/src/shading/shading.cpp (sdnative.shade): every function below
 * follows the CPU evaluator step by step, so that the viewport agrees with it to float32 rounding.
 * Equation numbers are the seed's (msd-notes.md).
 *
 * Everything happens in the baked object's bake space (its local space with its scale applied:
 * bake/geometry.py): the per-vertex data (normals, visibility, designs) were baked there, and the
 * environment coefficients in sd.light[] are those of x -> L(g R x), with g the environment
 * rotation and R the rotation part of the object's matrix (rotated on the CPU once per frame and
 * per object).
 *
 * The shader is specialised with defines (addon/sd_lighting/live/shader_variant.py, from the
 * method table methods.py); exactly one SD_METHOD_* is defined:
 *   SD_METHOD_UNSHADOWED         sum_l w_l sum_m L_lm y_lm(a)                 (V = 1)
 *   SD_METHOD_AMBIENT_OCCLUSION  AO x unshadowed
 *   SD_METHOD_PRT_DIFFUSE        eq. (2): sum_i L_i T_i
 *   SD_METHOD_PRT_MATRIX         eqs. (8)-(9): sum_i L_i sum_j M_ij w_j y_j(a)
 *   SD_METHOD_PRT_GAUNT          eq. (10): sum over real Gaunt coefficients G_abc L_a V_b w_c y_c(a)
 *   SD_METHOD_MSD_LOBE           eq. (12), Theorem 2.1: sum_nu lambda_nu L~(g_a x_nu) V~(g_a x_nu)
 *   SD_METHOD_MSD_VISIBILITY     eq. (13), Theorem 2.2: sum_nu lambda_Vnu L~(x_Vnu) w~(x_Vnu . a)
 * and:
 *   SD_GLOSSY            Phong lobe around the mirrored view (otherwise Lambert around the normal)
 *   SD_DIFFUSE_LOBE      (with SD_GLOSSY) a Lambert lobe besides the Phong one: lobe 1, read with
 *                        the same per-vertex data in the same pass (sd_shade_pair)
 *   SD_LIGHT_COUNT       (s+1)^2 environment coefficients
 *   SD_VIS_COUNT         (s'+1)^2 visibility coefficients (methods with V~ or M)
 *   SD_VIS_ORDER         s' (truncated lobe of eq. 13)
 *   SD_BASIS_ORDER/COUNT order of the SH basis evaluated at a direction, and its (order+1)^2
 *   SD_SH_DIAGONAL, SD_SH_A, SD_SH_B, SD_SH_TABLE_SIZE   its recurrence constants (see below)
 *   SD_LOBE_VEC4S        vec4s holding one lobe's Funk-Hecke factors w_l (four per vec4); lobe 1's
 *                        follow lobe 0's in sd.lobe[]
 *   SD_LOBE_DESIGN_SIZE  nodes of the lobe design (eq. 12); SD_DIFFUSE_DESIGN_SIZE those of lobe
 *                        1's, after lobe 0's in sd.design[]
 *   SD_DATA_STRIDE       texels of per-vertex data per vertex (0: none); for eq. (13) one, the
 *                        header of the vertex's design of V
 *   SD_TEXTURE_WIDTH_LOG2  log2 of the data textures' width
 *   SD_LIGHTMAP          (with SD_PER_PIXEL) the data are texture-space: one entry per stored texel
 *                        of a SD_LIGHTMAP_WIDTH x SD_LIGHTMAP_HEIGHT lightmap (its row in the R32F
 *                        map sd_lightmap_index, -1 where none is stored), read at the pixel's
 *                        lightmap UV (bake/lightmap.py) instead of at its triangle's vertices
 *   SD_GAUNT_COUNT       real Gaunt coefficients (eq. 10)
 *   SD_PREFILTERED       (with SD_LOBE_WEIGHTS) lobe 0's light is the environment prefiltered by
 *                        the slot's GGX lobe (native glossy_prefilter.h: the split sum), looked up
 *                        per pixel at g R d, d the mean direction of the lobe the view reflects
 *                        (sdnative.glossy_bend), in the atlas sd_prefiltered (SD_PREFILTERED_MAP names
 *                        it; SD_PREFILTERED_WIDTH, SD_PREFILTERED_LEVELS its layout), times the
 *                        share of lobe 0's low-order light the baked visibility lets through
 *                        (sd_visibility_ratio; SD_OPEN_ORDER: the order the method's B reaches
 *                        where V = 1; SD_HORIZON_LOBE: the block's row of horizon factors,
 *                        SD_HORIZON_ORDER their order)
 *   SD_LAMBERT_LAYER     (with SD_PREFILTERED, without SD_GLOSSY) lobe 0 is the diffuse, and the
 *                        prefiltered light, shadowed by lobe 0's visibility ratio, lights the
 *                        slots' specular layers (rough dielectrics: scene/lobes.py)
 *   SD_BAND_LIMITED_TEXTURE  (MSD 12, 13 only) L~ is looked up in the band-limited texture
 *                        sd_band_limited_texture (unrotated L~ on cube faces, by bilinear cell of
 *                        SD_BAND_LIMITED_CELLS per face edge) at g R x (sd.local_to_environment)
 *                        instead of summed from sd.light[]
 *
 * Per-vertex data live in the RGBA32F texture sd_data: vertex p's texels are
 * [p * SD_DATA_STRIDE, (p + 1) * SD_DATA_STRIDE), row-major over the texture
 * (2^SD_TEXTURE_WIDTH_LOG2 texels wide); they are the method's stored array, the bake's
 * FLOAT_COLOR attributes in order, or for eq. (13) a header texel (column and row of the vertex's
 * first node texel, its node count) followed, after all headers, by every vertex's nodes at their
 * own count (addon/sd_lighting/store/bake_data.py).
 *
 * Metal-safe: explicit float literals, no implicit int/float conversions.
 */

/* Luminance of linear Rec. 709 RGB, Blender's default scene-linear (scene/lobes.LUMINANCE). */
#define SD_LUMINANCE vec3(0.2126, 0.7152, 0.0722)

/* ---------------------------------------------------------------------------------------------
 * Real spherical harmonics in the sdnative convention (spherical_harmonics.h): orthonormal for
 * dmu = dx / 4pi, y_00 = 1, y_1,-1 = sqrt(3) y, y_10 = sqrt(3) z, y_11 = sqrt(3) x, no
 * Condon-Shortley phase, flat index l^2 + l + m. The fully normalised recurrences:
 *   Q_mm = sqrt((2m+1)/(2m)) Q_{m-1,m-1}, Q_00 = 1, Q_11 = sqrt(3)          (SD_SH_DIAGONAL)
 *   Q_lm = a_lm z Q_{l-1,m} - b_lm Q_{l-2,m}                                 (SD_SH_A, SD_SH_B)
 *     with a_{m+1,m} = sqrt(2m+3), b_{m+1,m} = 0, and for l >= m+2
 *     a_lm = sqrt((2l-1)(2l+1) / ((l-m)(l+m))),
 *     b_lm = sqrt((2l+1)(l+m-1)(l-m-1) / ((l-m)(l+m)(2l-3)))
 *   y_l,+m = Q_lm Re (x + i y)^m,  y_l,-m = Q_lm Im (x + i y)^m.
 * The constants come as defines (comma-separated, the float64 values of
 * sdnative.sh_recurrence_constants); the a/b tables are indexed l (l + 1) / 2 + m.
 * ------------------------------------------------------------------------------------------- */
/* Funk-Hecke factor w_l of lobe 0 (the only one, or Phong) or 1 (Lambert; w_0 = 1), from the
 * frame block. */
float sd_lobe_factor(int lobe, int l)
{
  return sd.lobe[lobe * SD_LOBE_VEC4S + l / 4][l % 4];
}

#ifdef SD_BASIS_ORDER
const float sd_sh_diagonal[SD_BASIS_ORDER + 1] = float[SD_BASIS_ORDER + 1](SD_SH_DIAGONAL);
const float sd_sh_a[SD_SH_TABLE_SIZE] = float[SD_SH_TABLE_SIZE](SD_SH_A);
const float sd_sh_b[SD_SH_TABLE_SIZE] = float[SD_SH_TABLE_SIZE](SD_SH_B);

/* SD_SH_SUM (MSD 13 with the SH path, whose only use of the basis is sums of L at a direction): the
 * recurrences below compute sum_{l <= order} f_l sum_m L_lm y_lm(d), f_l = 1 (lobe < 0) or lobe's
 * factor w_l, summed while the basis is generated, without a basis array (faster where arrays
 * spill). Otherwise they fill the basis y_i(d) up to SD_BASIS_ORDER. */
#  if defined(SD_METHOD_MSD_VISIBILITY) && !defined(SD_BAND_LIMITED_TEXTURE)
#    define SD_SH_SUM
vec3 sd_banded_light(vec3 d, int lobe, int order)
#  else
void sd_sh_basis(vec3 d, out float y[SD_BASIS_COUNT])
#  endif
{
#  ifdef SD_SH_SUM
  vec3 sum = vec3(0.0);
#  else
  int order = SD_BASIS_ORDER;
#  endif
  float re = 1.0;
  float im = 0.0;
  for (int m = 0; m <= order; m++) {
    if (m > 0) {
      float r = re * d.x - im * d.y;
      im = re * d.y + im * d.x;
      re = r;
    }
    float q_prev2 = 0.0;
    float q_prev = 0.0;
    float q = sd_sh_diagonal[m];
    for (int l = m; l <= order; l++) {
      if (l > m) {
        int k = (l * (l + 1)) / 2 + m;
        q = sd_sh_a[k] * d.z * q_prev - sd_sh_b[k] * q_prev2;
      }
      q_prev2 = q_prev;
      q_prev = q;
      int center = l * l + l;
#  ifdef SD_SH_SUM
      float f = (lobe < 0) ? 1.0 : sd_lobe_factor(lobe, l);
      sum += sd.light[center + m].rgb * (f * q * re);
      if (m > 0) {
        sum += sd.light[center - m].rgb * (f * q * im);
      }
#  else
      y[center + m] = q * re;
      if (m > 0) {
        y[center - m] = q * im;
      }
#  endif
    }
  }
#  ifdef SD_SH_SUM
  return sum;
#  endif
}

#  ifdef SD_SH_SUM
/* L~(d) = sum_i L_i y_i(d) for the rotated environment. */
vec3 sd_light_at(vec3 d)
{
  return sd_banded_light(d, -1, SD_BASIS_ORDER);
}
#  endif
#endif

#ifdef SD_BAND_LIMITED_TEXTURE
/* L~(g R d) from the band-limited texture of the unrotated L~: cube faces by bilinear cell
 * (addon/sd_lighting/live/band_limited_map.py, whose lookup() this is): the face of e = g R d's
 * largest component, (u, v) the other two over it, and the cell of the four texel centres around
 * them, two texels holding their RGB as 16-bit codes in 24-bit integer floats.
 * Texel k of a face is centred at -1 + (k - 0.5) 2 / n, n = SD_BAND_LIMITED_CELLS - 1; the gutter
 * (k = 0, n + 1) continues the face past its edges. The face is chosen by selects, not branches:
 * a software rasteriser runs every branch its lanes take. */
vec3 sd_light_at(vec3 d)
{
  vec3 e = mat3(sd.local_to_environment) * d;
  vec3 a = abs(e);
  bool x_major = a.x >= a.y && a.x >= a.z;
  bool y_major = !x_major && a.y >= a.z;
  float major = x_major ? e.x : (y_major ? e.y : e.z);
  vec2 uv = (x_major ? e.yz : (y_major ? e.xz : e.xy)) / abs(major);
  int face = (x_major ? 0 : (y_major ? 2 : 4)) + ((major < 0.0) ? 1 : 0);
  vec2 t = (uv + vec2(1.0)) * (0.5 * float(SD_BAND_LIMITED_CELLS - 1)) + vec2(0.5);
  vec2 corner = clamp(floor(t), vec2(0.0), vec2(float(SD_BAND_LIMITED_CELLS - 1)));
  vec2 f = t - corner;
  ivec2 cell = ivec2(2 * int(corner.x), face * SD_BAND_LIMITED_CELLS + int(corner.y));
  /* each texel: (low, high) words of the cell's bottom row, then of its top row, 24 bits each */
  uvec4 w0 = uvec4(texelFetch(sd_band_limited_texture, cell, 0));
  uvec4 w1 = uvec4(texelFetch(sd_band_limited_texture, cell + ivec2(1, 0), 0));
  /* codes A, B, C of both rows at once: texel 0 holds r0 r1 g0, texel 1 g1 b0 b1 (x = 0, 1) */
  vec2 r0 = vec2(w0.xz & 0xffffu), r1 = vec2((w0.xz >> 16) | ((w0.yw & 0xffu) << 8)), g0 = vec2(w0.yw >> 8);
  vec2 g1 = vec2(w1.xz & 0xffffu), b0 = vec2((w1.xz >> 16) | ((w1.yw & 0xffu) << 8)), b1 = vec2(w1.yw >> 8);
  vec2 r = mix(r0, r1, f.x);   /* (bottom, top) */
  vec2 g = mix(g0, g1, f.x);
  vec2 b = mix(b0, b1, f.x);
  return (mix(vec3(r.x, g.x, b.x), vec3(r.y, g.y, b.y), f.y) - vec3(32768.0)) * sd.band_limited_scale.x;
}

#endif

#if defined(SD_BASIS_ORDER) && defined(SD_LIGHT_COUNT) && !defined(SD_BAND_LIMITED_TEXTURE)
/* L~(x) = sum_i L_i y_i(x) for the rotated environment, given the basis at x. */
vec3 sd_light_sum(float y[SD_BASIS_COUNT])
{
  vec3 sum = vec3(0.0);
  for (int i = 0; i < SD_LIGHT_COUNT; i++) {
    sum += sd.light[i].rgb * y[i];
  }
  return sum;
}
#endif

#if defined(SD_METHOD_PRT_MATRIX) || defined(SD_METHOD_PRT_GAUNT)
/* The lobe's Funk-Hecke expansion at the axis: w_l y_lm(a) (PRT 8-10). */
void sd_lobe_basis(vec3 a, int lobe, out float y[SD_BASIS_COUNT])
{
  sd_sh_basis(a, y);
  for (int l = 0; l <= SD_BASIS_ORDER; l++) {
    for (int i = l * l; i < (l + 1) * (l + 1); i++) {
      y[i] *= sd_lobe_factor(lobe, l);
    }
  }
}
#endif

/* The mirrored view v_n = 2 (n.v) n - v, normalised (as the CPU evaluator does). */
vec3 sd_mirrored_view(vec3 normal, vec3 view)
{
  return normalize(2.0 * dot(normal, view) * normal - view);
}

/* Lobe 0's axis a: the normal for Lambert, the mirrored view for Phong. */
vec3 sd_lobe_axis(vec3 normal, vec3 view)
{
#ifdef SD_GLOSSY
  return sd_mirrored_view(normal, view);
#else
  return normalize(normal);
#endif
}

/* Per-vertex data: texel `index` of the data texture, and texel k of vertex p. The texture is
 * 2^SD_TEXTURE_WIDTH_LOG2 texels wide, so the row and column are a shift and a mask (integer
 * division is slow on CPU rasterisers). */
#if SD_DATA_STRIDE > 0
vec4 sd_data_texel(int index)
{
  return texelFetch(sd_data, ivec2(index & ((1 << SD_TEXTURE_WIDTH_LOG2) - 1), index >> SD_TEXTURE_WIDTH_LOG2), 0);
}

vec4 sd_vertex_texel(int p, int k)
{
  return sd_data_texel(p * SD_DATA_STRIDE + k);
}

/* Coefficient i of a vertex's SH data whose texels start at `first`. */
float sd_vertex_coefficient(int p, int first, int i)
{
  return sd_vertex_texel(p, first + i / 4)[i % 4];
}
#endif

#if defined(SD_METHOD_MSD_LOBE) || defined(SD_PREFILTERED)
/* Two tangents completing a to an orthonormal basis: any rotation g_a taking e3 to a (Duff et
 * al. 2017; the CPU evaluator's orthonormal_basis has another twist, which does not matter for a
 * zonal lobe: Theorem 2.1, nor for the sampled glossy lobe, whose frame v fixes). */
void sd_orthonormal_basis(vec3 a, out vec3 t1, out vec3 t2)
{
  float sign_z = (a.z >= 0.0) ? 1.0 : -1.0;
  float c = -1.0 / (sign_z + a.z);
  float d = a.x * a.y * c;
  t1 = vec3(1.0 + sign_z * a.x * a.x * c, sign_z * d, -sign_z * a.x);
  t2 = vec3(d, sign_z + a.y * a.y * c, -a.y);
}
#endif

#if defined(SD_METHOD_MSD_VISIBILITY) || defined(SD_PREFILTERED)
/* sum_{l <= order} (2l+1) f_l P_l(t) for the factors f_l of block row `lobe`: a lobe's w_l give
 * the lobe truncated at that order (eq. 13's w~), SD_HORIZON_LOBE's the horizon factor. */
float sd_legendre_sum(float t, int lobe, int order)
{
  float p_prev = 1.0;
  float p = t;
  float sum = sd_lobe_factor(lobe, 0);
  if (order >= 1) {
    sum += 3.0 * sd_lobe_factor(lobe, 1) * t;
  }
  for (int l = 2; l <= order; l++) {
    float fl = float(l);
    float next = ((2.0 * fl - 1.0) * t * p - (fl - 1.0) * p_prev) / fl;
    p_prev = p;
    p = next;
    sum += (2.0 * fl + 1.0) * sd_lobe_factor(lobe, l) * p;
  }
  return sum;
}
#endif

/* SD_LOBE1(code): code that only the Lambert lobe 1 needs, compiled with SD_DIFFUSE_LOBE. */
#ifdef SD_DIFFUSE_LOBE
#  define SD_LOBE1(code) code
#else
#  define SD_LOBE1(code)
#endif

#if defined(SD_METHOD_UNSHADOWED) || defined(SD_METHOD_AMBIENT_OCCLUSION) || defined(SD_PREFILTERED)
/* Funk-Hecke up to `order` (<= SD_BASIS_ORDER): the lobe's unshadowed light
 * sum_{l <= order} w_l sum_m L_lm y_lm(a). */
vec3 sd_open_light(vec3 a, int lobe, int order)
{
#  ifdef SD_SH_SUM
  return sd_banded_light(a, lobe, order);
#  else
  vec3 rgb = vec3(0.0);
  float y[SD_BASIS_COUNT];
  sd_sh_basis(a, y);
  for (int l = 0; l <= order; l++) {
    vec3 band = vec3(0.0);
    for (int i = l * l; i < (l + 1) * (l + 1); i++) {
      band += sd.light[i].rgb * y[i];
    }
    rgb += sd_lobe_factor(lobe, l) * band;
  }
  return rgb;
#  endif
}
#endif

#ifdef SD_PREFILTERED
/* The share of lobe 0's light (axis a0) that the baked visibility lets through at a surface of
 * normal n (msd-notes, "Glossy light"): the method's low-order B (b0) over what the same formula
 * gives where nothing but the surface's own tangent plane occludes - the lobe's Funk-Hecke sum to
 * SD_OPEN_ORDER times the horizon factor, the share of the truncated lobe above the plane in a
 * uniform world -, in luminance, within [0, 1]. The horizon itself is the split sum's (its
 * directional albedo); the ratio keeps what other geometry hides. Both are offset by a tenth of
 * the environment's mean radiance (L_00): where the truncated sums come near zero (a lobe facing
 * a dark ground) their ratio would swing between 0 and 1 with the ringing, not the shadow. */
float sd_visibility_ratio(vec3 b0, vec3 a0, vec3 n)
{
  const vec3 luminance = SD_LUMINANCE;
  float offset = max(0.1 * dot(sd.light[0].rgb, luminance), 1e-8);
  float horizon = min(sd_legendre_sum(dot(a0, normalize(n)), SD_HORIZON_LOBE, SD_HORIZON_ORDER), 1.0);
  float open = max(horizon * dot(sd_open_light(a0, 0, SD_OPEN_ORDER), luminance), 0.0);
  float shadowed = max(dot(b0, luminance), 0.0);
  return clamp((shadowed + offset) / (open + offset), 0.0, 1.0);
}

/* Level k of the prefiltered atlas (glossy_prefilter.h's PrefilterLayout) at the environment
 * direction e. */
vec3 sd_prefiltered_level(vec3 e, int k)
{
  int w0 = SD_PREFILTERED_WIDTH;
  int width = (k == 0) ? w0 : (w0 >> min(k - 1, SD_PREFILTERED_LEVELS - 3));
  ivec2 origin = (k < 2) ? ivec2(0, k * w0 / 2) : ivec2(w0 - (w0 >> (k - 2)), w0);
  return sd_equirect_block(1, origin, ivec2(width, width / 2), e);
}

/* Perceptual roughness of the atlas's level k: 0, then sqrt(alpha_k), alpha_k = 2^(k - (levels - 1)). */
float sd_prefiltered_roughness(int k)
{
  return (k == 0) ? 0.0 : exp2(0.5 * float(k - (SD_PREFILTERED_LEVELS - 1)));
}

/* The environment prefiltered by the GGX lobe of perceptual roughness r around the local direction
 * d (looked up at g R d): between two GGX levels linear in alpha^2, as a blur's variance adds
 * (linear in alpha, the blend of a sharper and a wider level blurred a bright facet more than the
 * lobe between them does); between the map itself (level 0) and level 1 linear in alpha = r^2 (in
 * alpha^2 a near-mirror read the map's texels almost alone, sharper than Cycles shows it; linear
 * in r, r = 0.05 took 57 % of level 1, whose alpha is three times its own). */
vec3 sd_prefiltered_light(vec3 d, float roughness)
{
  vec3 e = normalize(mat3(sd.local_to_environment) * d);
  float r = clamp(roughness, 0.0, 1.0);
  /* the level at or below r: 0 below level 1's roughness, else k from r = 2^((k - levels + 1) / 2) */
  float past_first = 2.0 * log2(max(r, 1e-6)) + float(SD_PREFILTERED_LEVELS - 1);
  int k = (past_first < 1.0) ? 0 : min(int(past_first), SD_PREFILTERED_LEVELS - 2);
  float below = sd_prefiltered_roughness(k);
  float above = sd_prefiltered_roughness(k + 1);
  /* alpha, or alpha^2 */
  float x = r * r, x0 = below * below, x1 = above * above;
  if (k > 0) {
    x *= x;
    x0 *= x0;
    x1 *= x1;
  }
  float t = clamp((x - x0) / (x1 - x0), 0.0, 1.0);
  return mix(sd_prefiltered_level(e, k), sd_prefiltered_level(e, k + 1), t);
}
#endif

#ifdef SD_METHOD_MSD_LOBE
/* Eq. (12), Theorem 2.1: the lobe's design turned onto the axis a, L~ and V~ (coefficients v) at
 * its nodes. */
vec3 sd_lobe_design_sum(float v[SD_VIS_COUNT], vec3 a, int lobe)
{
  vec3 t1, t2;
  sd_orthonormal_basis(a, t1, t2);
  int first = (lobe == 0) ? 0 : SD_LOBE_DESIGN_SIZE;
#  ifdef SD_DIFFUSE_LOBE
  int end = (lobe == 0) ? SD_LOBE_DESIGN_SIZE : SD_LOBE_DESIGN_SIZE + SD_DIFFUSE_DESIGN_SIZE;
#  else
  int end = SD_LOBE_DESIGN_SIZE;
#  endif
  vec3 rgb = vec3(0.0);
  float y[SD_BASIS_COUNT];
  for (int nu = first; nu < end; nu++) {
    vec4 node = sd.design[nu];
    vec3 x = node.x * t1 + node.y * t2 + node.z * a;
    sd_sh_basis(x, y);
    float v_tilde = 0.0;
    for (int j = 0; j < SD_VIS_COUNT; j++) {
      v_tilde += v[j] * y[j];
    }
#  ifdef SD_BAND_LIMITED_TEXTURE
    rgb += (node.w * v_tilde) * sd_light_at(x);
#  else
    rgb += (node.w * v_tilde) * sd_light_sum(y);
#  endif
  }
  return rgb;
}
#endif

/* B of lobe 0 (axis a0, local space) and, with SD_DIFFUSE_LOBE, of the Lambert lobe 1 (axis a1)
 * for vertex p; b1 stays zero without it. Where a method's work per vertex does not depend on the
 * lobe it is done once for both: PRT (8)'s row of M, PRT (10)'s L_a V~_b G_abc, MSD (13)'s L~ at
 * each node. */
void sd_shade_pair(int p, vec3 a0, vec3 a1, out vec3 b0, out vec3 b1)
{
  b0 = vec3(0.0);
  b1 = vec3(0.0);

#if defined(SD_METHOD_UNSHADOWED) || defined(SD_METHOD_AMBIENT_OCCLUSION)
  b0 = sd_open_light(a0, 0, SD_BASIS_ORDER);
  SD_LOBE1(b1 = sd_open_light(a1, 1, SD_BASIS_ORDER);)
#  ifdef SD_METHOD_AMBIENT_OCCLUSION
  float ao = sd_vertex_texel(p, 0).x;
  b0 *= ao;
  b1 *= ao;
#  endif

#elif defined(SD_METHOD_PRT_DIFFUSE)
  /* Eq. (2): one dot product with the transfer vector (Lambert only). */
  for (int t = 0; t < SD_DATA_STRIDE; t++) {
    vec4 texel = sd_vertex_texel(p, t);
    for (int c = 0; c < 4; c++) {
      int i = 4 * t + c;
      if (i < SD_LIGHT_COUNT) {
        b0 += sd.light[i].rgb * texel[c];
      }
    }
  }

#elif defined(SD_METHOD_PRT_MATRIX)
  /* Eqs. (8)-(9): T_i = sum_j M_ij w_j y_j(a), B = sum_i L_i T_i; M row-major in the texels. */
  float y0[SD_BASIS_COUNT];
  sd_lobe_basis(a0, 0, y0);
  SD_LOBE1(float y1[SD_BASIS_COUNT]; sd_lobe_basis(a1, 1, y1);)
  for (int i = 0; i < SD_LIGHT_COUNT; i++) {
    float t0 = 0.0;
    SD_LOBE1(float t1 = 0.0;)
    for (int j = 0; j < SD_VIS_COUNT; j++) {
      float m = sd_vertex_coefficient(p, 0, i * SD_VIS_COUNT + j);
      t0 += m * y0[j];
      SD_LOBE1(t1 += m * y1[j];)
    }
    b0 += sd.light[i].rgb * t0;
    SD_LOBE1(b1 += sd.light[i].rgb * t1;)
  }

#elif defined(SD_METHOD_PRT_GAUNT)
  /* Eq. (10): sum over G_abc != 0 of L_a V~_b G_abc w_c y_c(a). */
  float y0[SD_BASIS_COUNT];
  sd_lobe_basis(a0, 0, y0);
  SD_LOBE1(float y1[SD_BASIS_COUNT]; sd_lobe_basis(a1, 1, y1);)
  float v[SD_VIS_COUNT];
  for (int j = 0; j < SD_VIS_COUNT; j++) {
    v[j] = sd_vertex_coefficient(p, 0, j);
  }
  for (int e = 0; e < SD_GAUNT_COUNT; e++) {
    vec4 entry = texelFetch(sd_gaunt, ivec2(e & ((1 << SD_TEXTURE_WIDTH_LOG2) - 1), e >> SD_TEXTURE_WIDTH_LOG2), 0); /* a, b, c, G */
    vec3 light = sd.light[int(entry.x)].rgb;
    float vg = v[int(entry.y)] * entry.w;
    int c = int(entry.z);
    b0 += light * (vg * y0[c]);
    SD_LOBE1(b1 += light * (vg * y1[c]);)
  }

#elif defined(SD_METHOD_MSD_LOBE)
  float v[SD_VIS_COUNT];
  for (int j = 0; j < SD_VIS_COUNT; j++) {
    v[j] = sd_vertex_coefficient(p, 0, j);
  }
  b0 = sd_lobe_design_sum(v, a0, 0);
  SD_LOBE1(b1 = sd_lobe_design_sum(v, a1, 1);)

#elif defined(SD_METHOD_MSD_VISIBILITY)
  /* Eq. (13), Theorem 2.2: the vertex's design of V, L~ and the truncated lobe at its nodes; the
   * header says where its nodes start (column, row) and how many it has. */
  vec4 header = sd_vertex_texel(p, 0);
  int first = (int(header.y) << SD_TEXTURE_WIDTH_LOG2) + int(header.x);
  int count = int(header.z);
  for (int nu = 0; nu < count; nu++) {
    vec4 node = sd_data_texel(first + nu); /* x, y, z, lambda */
    vec3 light = node.w * sd_light_at(node.xyz);
    b0 += sd_legendre_sum(dot(node.xyz, a0), 0, SD_VIS_ORDER) * light;
    SD_LOBE1(b1 += sd_legendre_sum(dot(node.xyz, a1), 1, SD_VIS_ORDER) * light;)
  }
#endif
}

/* B of lobe 0 (b0) and, with SD_DIFFUSE_LOBE, of the Lambert lobe (b1; zero without it) for vertex
 * p seen along `view` (unit, from the surface to the eye) with surface normal `normal`, both in
 * the object's local space. */
void sd_shade_lobes(int p, vec3 normal, vec3 view, out vec3 b0, out vec3 b1)
{
  sd_shade_pair(p, sd_lobe_axis(normal, view), normalize(normal), b0, b1);
}

/* Unit direction to the eye, in the object's local space, from the point `offset` away from the
 * object's origin (in world axes: mat3(sd.model) * pos). sd.camera holds the eye relative to that
 * origin, differenced in float64 on the CPU (gpu_shading.py): the eye minus a float32 world
 * position lost the view to rounding far from the world origin (a translation of 1e6 rounds
 * positions to 1/16: B 6e-3 off at 6 units, Phong 8). */
vec3 sd_view_direction(vec3 offset)
{
  vec3 to_eye = (sd.camera.w > 0.5) ? (sd.camera.xyz - offset) : sd.camera.xyz;
  return normalize(mat3(sd.world_to_local) * normalize(to_eye));
}
