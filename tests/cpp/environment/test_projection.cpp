// Tests of sdlighting/sh_projection.h and environment_error.h: SH projection, band-limited textures, band energies and the error measures, also on Blender's HDRIs (skipped, with a message, only when the files are absent). Two kinds of tolerance are kept apart: kExact (1e-12,
// results the code computes exactly up to rounding) and the quadrature / Monte Carlo tolerances,
// each derived where it is used.
#include "environment_test_support.h"
#include "sdlighting/environment.h"
#include "sdlighting/environment_error.h"
#include "sdlighting/ringing.h"
#include "sdlighting/sh_projection.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/zonal_lobe.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sd {
namespace {

using namespace test;

// ---------------------------------------------------------------------------------------------
// Projection

// The texel rules' bound (projection.cpp): 1e-5 of max |y_lm| <= √(2l+1) times the map's mass.
double texel_rule_bound(const Environment& env, int order) {
  return 1e-5 * std::sqrt(2.0 * order + 1.0) * std::max({env.mass(0), env.mass(1), env.mass(2)});
}

TEST(Environment, ProjectionIntegratesTexelsAsAreas) {
  std::mt19937_64 rng(3);
  const Environment equirect = Environment::from_equirect_pixels(50, 27, random_pixels(50 * 27 * 3, 5.0f, rng));
  const Environment cube = Environment::from_cube_pixels(7, random_pixels(6 * 7 * 7 * 3, 5.0f, rng));
  const Environment small = Environment::from_equirect_pixels(5, 3, random_pixels(5 * 3 * 3, 5.0f, rng));
  const Environment small_cube = Environment::from_cube_pixels(2, random_pixels(6 * 2 * 2 * 3, 5.0f, rng));
  for (const Environment* env : {&equirect, &cube, &small, &small_cube}) {
    for (int order : {0, 3, 16}) {
      const std::vector<double> fast = sh(*env, order), brute = brute_force_sh(*env, order);
      EXPECT_LT(max_abs_difference(fast, brute), texel_rule_bound(*env, order)) << "order " << order;
    }
  }
  EXPECT_THROW(sh(equirect, -1), std::invalid_argument);
  EXPECT_THROW(sh(equirect, 17), std::invalid_argument);
}

TEST(Environment, ConstantMapsOfAnySizeProjectToTheConstant) {
  // Texels taken as points lit a 2 × 1 map like two point lights (L_22 = −1.9 c by the midpoint rule).
  const double c = 2.5;
  std::vector<Environment> maps;
  for (auto [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {2, 1}, {1, 2}, {4, 2}, {3, 5}, {16, 8}, {64, 32}, {1024, 512}}) {
    maps.push_back(Environment::from_equirect_pixels(w, h, std::vector<float>(3 * w * h, float(c))));
  }
  for (int n : {1, 2, 3, 8, 33}) maps.push_back(Environment::from_cube_pixels(n, std::vector<float>(18 * n * n, float(c))));
  for (const Environment& env : maps) {
    const std::vector<double> sh = sd::sh(env, 16);
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(sh[ch], c, kExact * c) << env.width() << " x " << env.height();
    for (size_t q = 3; q < sh.size(); ++q) {
      ASSERT_LT(std::abs(sh[q]), texel_rule_bound(env, 16)) << env.width() << " x " << env.height() << " coefficient " << q / 3;
    }
    // L̃ is the constant too.
    for (float v : band_limited(env, 16, 8, 4)) ASSERT_NEAR(v, c, 1e-4 * c);
  }
}

TEST(Environment, ProjectionIsIndependentOfThreadCount) {
  std::mt19937_64 rng(4);
  const Environment env = Environment::from_equirect_pixels(257, 130, random_pixels(257 * 130 * 3, 3.0f, rng));
  const std::vector<double> one = sh(env, 8, 1);
  EXPECT_EQ(sh(env, 8, 2), one);  // bit-identical
  EXPECT_EQ(sh(env, 8, 3), one);
  EXPECT_EQ(sh(env, 8, 0), one);
  const Environment cube = Environment::from_cube_pixels(20, random_pixels(6 * 20 * 20 * 3, 3.0f, rng));
  EXPECT_EQ(sh(cube, 6, 1), sh(cube, 6, 2));
  EXPECT_EQ(sh(cube, 6, 1), sh(cube, 6, 5));
}

TEST(Environment, RecoversBandLimitedFunctionWithinMidpointError) {
  const BandLimited f = random_band_limited(6, 11);
  const double coarse =
      recovery_error(f, sh(Environment::from_equirect_pixels(128, 64, equirect_pixels(128, 64, f)), 6));
  const double fine =
      recovery_error(f, sh(Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, f)), 6));
  // Midpoint rule in θ (the φ sums are exact for |m| < W): error ∝ 1/H², so ×16 from 64 to 256 rows.
  EXPECT_LT(fine, 3e-4);
  EXPECT_GT(coarse / fine, 8.0);
  EXPECT_LT(coarse / fine, 32.0);
}

TEST(Environment, CubeAndEquirectOfOneFunctionAgree) {
  const BandLimited f = random_band_limited(5, 12);
  const std::vector<double> equirect = sh(Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, f)), 5);
  const Environment cube = Environment::from_cube_pixels(96, cube_pixels(96, f));
  const std::vector<double> cube_sh = sh(cube, 5);
  EXPECT_LT(recovery_error(f, equirect), 3e-4);
  EXPECT_LT(recovery_error(f, cube_sh), 3e-4);
  EXPECT_LT(max_abs_difference(equirect, cube_sh) / max_abs(f.c), 5e-4);
  // radiance() reads the same function through both layouts.
  std::mt19937_64 rng(5);
  for (int k = 0; k < 200; ++k) {
    const glm::dvec3 d = random_direction(rng);
    EXPECT_NEAR(cube.radiance(d).x, f(d).x, 0.05 * f.c[0]);
  }
}

TEST(Environment, RotatedShIsLookupThroughG) {
  std::mt19937_64 rng(21);
  const glm::dmat3 g = random_rotation(rng);
  const BandLimited f = random_band_limited(4, 13);
  // Definition: rotated coefficients evaluate to L(g x) (exact).
  const std::vector<double> rotated = rotated_sh(f.c, 4, g);
  for (int k = 0; k < 50; ++k) {
    const glm::dvec3 x = random_direction(rng);
    EXPECT_LT(glm::length(evaluate_sh_rgb(rotated, 4, x) - f(g * x)), kExact * f.c[0]);
  }
  // The map of x ↦ L(g x), projected, against rotated_sh of the original map's coefficients.
  const Radiance turned = [&](const glm::dvec3& x) { return f(g * x); };
  const std::vector<double> of_turned_map =
      sh(Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, turned)), 4);
  const std::vector<double> of_map = sh(Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, f)), 4);
  EXPECT_LT(max_abs_difference(rotated_sh(of_map, 4, g), of_turned_map) / max_abs(f.c), 5e-4);
  // Not the inverse: D(g) instead of D(gᵀ) is clearly wrong for a generic g.
  EXPECT_GT(max_abs_difference(rotated_sh(of_map, 4, glm::transpose(g)), of_turned_map) / max_abs(f.c), 1e-2);
  EXPECT_THROW(rotated_sh(f.c, 3, g), std::invalid_argument);
  EXPECT_THROW(rotated_sh(f.c, 4, 2.0 * g), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Band-limited maps and energies

TEST(Environment, BandLimitedMatchesExpansionAndApproachesMap) {
  const glm::dvec3 axis = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
  const Radiance smooth = [&](const glm::dvec3& d) {
    const double v = std::exp(3.0 * glm::dot(d, axis));
    return glm::dvec3(v, 0.5 * v, 2.0);
  };
  const int w = 256, h = 128;
  const Environment env = Environment::from_equirect_pixels(w, h, equirect_pixels(w, h, smooth));
  // Values are the expansion at texel centres (float rounding only).
  const std::vector<float> l8 = band_limited(env, 8, 64, 32);
  const std::vector<double> c8 = sh(env, 8);
  for (int j = 0; j < 32; j += 3)
    for (int i = 0; i < 64; i += 5) {
      const glm::dvec3 expected = evaluate_sh_rgb(c8, 8, equirect_pixel_direction(i, j, 64, 32));
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(l8[3 * (j * 64 + i) + c], expected[c], 1e-6 * (1.0 + std::abs(expected[c])));
    }
  // Relative L²(dμ) distance to the map: falls with the order, small at 16 (exp(3t) has
  // coefficients ~ 1.5^l / l!).
  auto distance = [&](int order) {
    const std::vector<float> approx = band_limited(env, order, w, h);
    double num = 0.0, den = 0.0;
    for (int64_t t = 0; t < env.texel_count(); ++t) {
      const double dmu = env.texel_solid_angle(t);
      for (int c = 0; c < 3; ++c) {
        const double diff = approx[3 * t + c] - env.pixels()[3 * t + c];
        num += diff * diff * dmu;
        den += double(env.pixels()[3 * t + c]) * env.pixels()[3 * t + c] * dmu;
      }
    }
    return std::sqrt(num / den);
  };
  // Truncation dominates up to order ~8; beyond, the midpoint rule's O((l/H)²) coefficient error
  // (the y_lm are not exactly orthonormal over the texels) is what remains, below 1e-3.
  const double d2 = distance(2), d4 = distance(4), d8 = distance(8), d16 = distance(16), d24 = distance(24);
  EXPECT_GT(d2, 0.05);
  EXPECT_GT(d2, 5.0 * d4);
  EXPECT_GT(d4, 5.0 * d8);
  EXPECT_LT(d16, 1e-3);
  EXPECT_LT(d24, 1e-3);  // order > 16 uses the cached high-order projection
  BandLimitedReport report;
  band_limited(env, 16, 64, 32, RingingWindow::None, &report);
  EXPECT_EQ(report.negative_texels, 0);
  EXPECT_GT(report.min_value[0], 0.0);
  EXPECT_THROW(band_limited(env, 65, 8, 4), std::invalid_argument);
  EXPECT_THROW(band_limited(env, 4, 0, 4), std::invalid_argument);
}

TEST(Environment, TextureOfRotatedCoefficients) {
  std::mt19937_64 rng(41);
  const glm::dmat3 g = random_rotation(rng);
  const BandLimited f = random_band_limited(5, 16);
  const std::vector<double> rotated = rotated_sh(f.c, 5, g);
  BandLimitedReport report;
  const std::vector<float> texture = band_limited_texture(rotated, 5, 48, 24, RingingWindow::None, &report);
  double lowest = 1e300;
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 48; ++i) {
      const glm::dvec3 expected = f(g * equirect_pixel_direction(i, j, 48, 24));  // L(g x) at the texel centre
      for (int c = 0; c < 3; ++c) {
        ASSERT_NEAR(texture[3 * (j * 48 + i) + c], expected[c], 1e-6 * f.c[c]);
        lowest = std::min(lowest, expected[0]);
      }
    }
  EXPECT_NEAR(report.min_value[0], lowest, 1e-6 * f.c[0]);
  EXPECT_EQ(report.negative_texels, 0);
  EXPECT_THROW(band_limited_texture(rotated, 4, 48, 24), std::invalid_argument);
  EXPECT_THROW(band_limited_texture(rotated, 5, 0, 24), std::invalid_argument);
  std::vector<double> bad = rotated;
  bad[7] = NAN;
  EXPECT_THROW(band_limited_texture(bad, 5, 48, 24), std::invalid_argument);
}

TEST(Environment, WindowsReduceRinging) {
  EXPECT_EQ(ringing_window_factor(RingingWindow::None, 5, 8), 1.0);
  EXPECT_NEAR(ringing_window_factor(RingingWindow::Hanning, 0, 8), 1.0, kExact);
  EXPECT_NEAR(ringing_window_factor(RingingWindow::Hanning, 9, 8), 0.0, kExact);
  EXPECT_NEAR(ringing_window_factor(RingingWindow::Hanning, 3, 5), 0.5 * (1.0 + std::cos(kPi * 0.5)), kExact);
  EXPECT_NEAR(ringing_window_factor(RingingWindow::Lanczos, 3, 5), std::sin(kPi * 0.5) / (kPi * 0.5), kExact);
  EXPECT_EQ(ringing_window_from_name("hanning"), RingingWindow::Hanning);
  EXPECT_EQ(ringing_window_from_name("lanczos"), RingingWindow::Lanczos);
  EXPECT_THROW(ringing_window_from_name("boxcar"), std::invalid_argument);

  const Environment env = Environment::from_equirect_pixels(256, 128, equirect_pixels(256, 128, sun_map({0.6, 0.0, 0.8}, 4.0)));
  BandLimitedReport none, hanning, lanczos;
  band_limited(env, 8, 128, 64, RingingWindow::None, &none);
  band_limited(env, 8, 128, 64, RingingWindow::Hanning, &hanning);
  band_limited(env, 8, 128, 64, RingingWindow::Lanczos, &lanczos);
  EXPECT_LT(none.min_value[0], 0.0);  // the unwindowed truncation of a sun rings below zero
  EXPECT_GT(none.negative_fraction, 0.05);
  for (const BandLimitedReport* r : {&hanning, &lanczos}) {
    EXPECT_GT(r->min_value[0], none.min_value[0]);
    EXPECT_LT(r->negative_texels, none.negative_texels);
    EXPECT_LT(r->negative_solid_angle, none.negative_solid_angle);
  }
  EXPECT_NEAR(none.negative_fraction, double(none.negative_texels) / (128 * 64), kExact);
}

TEST(Environment, BandEnergiesAndParseval) {
  const Environment env = Environment::from_equirect_pixels(256, 128, equirect_pixels(256, 128, sun_map({0.0, 0.6, 0.8}, 6.0)));
  const std::vector<double> e = band_energies(env, 16);
  ASSERT_EQ(e.size(), 17u * 4);
  const std::vector<double> c = sh(env, 16);
  for (int l = 0; l <= 16; ++l) {
    double expected[4] = {0, 0, 0, 0};
    for (int m = -l; m <= l; ++m) {
      const double* x = c.data() + 3 * sh_index(l, m);
      for (int ch = 0; ch < 3; ++ch) expected[ch] += x[ch] * x[ch];
      const double y = 0.2126 * x[0] + 0.7152 * x[1] + 0.0722 * x[2];
      expected[3] += y * y;
    }
    for (int ch = 0; ch < 4; ++ch) EXPECT_NEAR(e[4 * l + ch], expected[ch], kExact * e[ch]) << l << " " << ch;
  }
  // E_0 = mass².
  for (int ch = 0; ch < 4; ++ch) EXPECT_NEAR(e[ch], env.mass(ch) * env.mass(ch), kExact * e[ch]);
  // ε(0) = sqrt(1 − mass²/‖L‖²) exactly.
  EXPECT_NEAR(low_frequency_error(env, 0, 0),
              std::sqrt(1.0 - env.mass(0) * env.mass(0) / env.norm_squared(0)), kExact);
  // ε(s) by Parseval against a direct texel sum of (L − L̃_s)² Δμ, which takes L̃_s at the texel
  // centres only: O((s/H)²) of ‖L̃_s‖², allow 1e-3.
  for (int s : {2, 4, 8}) {
    const std::vector<double> cs = sh(env, s);
    double num = 0.0;
    for (int64_t t = 0; t < env.texel_count(); ++t) {
      const double diff = env.texel_radiance(t).x - evaluate_sh_rgb(cs, s, env.texel_direction(t)).x;
      num += diff * diff * env.texel_solid_angle(t);
    }
    const double direct = std::sqrt(num / env.norm_squared(0));
    EXPECT_NEAR(low_frequency_error(env, s, 0), direct, 1e-3) << "s = " << s;
  }
  double previous = 2.0;
  for (int s = 0; s <= 64; ++s) {
    const double eps = low_frequency_error(env, s);
    EXPECT_LE(eps, previous);
    previous = eps;
  }
  EXPECT_THROW(band_energies(env, 65), std::invalid_argument);
  EXPECT_THROW(low_frequency_error(env, 2, 4), std::invalid_argument);
}

TEST(Environment, BandEnergiesAreRotationInvariant) {
  std::mt19937_64 rng(31);
  const glm::dmat3 g = random_rotation(rng);
  const BandLimited f = random_band_limited(6, 15);
  const Radiance turned = [&](const glm::dvec3& x) { return f(g * x); };
  const std::vector<double> a = band_energies(Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, f)), 8);
  const std::vector<double> b =
      band_energies(Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, turned)), 8);
  for (int l = 1; l <= 6; ++l)
    for (int ch = 0; ch < 4; ++ch) EXPECT_NEAR(a[4 * l + ch], b[4 * l + ch], 2e-3 * a[4 * l + ch] + 1e-9 * a[ch]);
}

// ---------------------------------------------------------------------------------------------
// Lobe-filtered error

// The product rule over axes or normals of the brute-force checks: gauss_legendre's n_t nodes in
// cos θ × n_phi equally spaced φ = 2π (p + 0.5) / n_phi, weights summing to 1 (exact to degree
// 2 n_t − 1 in cos θ).
SphereRule gauss_legendre_product_rule(int n_t, int n_phi) {
  std::vector<double> t, wt;
  gauss_legendre(n_t, t, wt);
  for (double& w : wt) w /= 2.0;
  return test::product_rule(t, wt, n_phi, 0.5);
}

// The relative RMS over axes a of B(a) − B̃_s(a), with B by brute force over the texels of the map
// split `split` × `split` (the same piecewise-constant map: the texel integrals of B by the midpoint
// rule on sub-texels) and the RMS by a product rule over axes (Gauss–Legendre in cos θ × equally
// spaced φ).
double brute_force_lobe_error(const Environment& env, const ZonalLobe& lobe, int s, int n_t, int n_phi, int split) {
  const SphereRule axes = gauss_legendre_product_rule(n_t, n_phi);
  const std::vector<double> w = lobe.coefficients(s);
  const std::vector<double> c = sh(env, s);
  std::vector<double> ylum(sh_count(s));
  for (int i = 0; i < sh_count(s); ++i) ylum[i] = 0.2126 * c[3 * i] + 0.7152 * c[3 * i + 1] + 0.0722 * c[3 * i + 2];
  const Environment fine = env.area_averaged(split * env.width(), split * env.height());
  std::vector<glm::dvec3> dirs;
  std::vector<double> texel_weight;
  for (int64_t q = 0; q < fine.texel_count(); ++q) {
    dirs.push_back(fine.texel_direction(q));
    texel_weight.push_back(luminance(fine.texel_radiance(q)) * fine.texel_solid_angle(q));
  }
  double num = 0.0, den = 0.0;
  for (size_t k = 0; k < axes.dirs.size(); ++k) {
    const glm::dvec3& a = axes.dirs[k];
    double b = 0.0;
    for (size_t q = 0; q < dirs.size(); ++q) b += texel_weight[q] * lobe.value(glm::dot(a, dirs[q]));
    const std::vector<double> y = sh_basis(s, a);
    double truncated = 0.0;
    for (int l = 0; l <= s; ++l)
      for (int m = -l; m <= l; ++m) truncated += w[l] * ylum[sh_index(l, m)] * y[sh_index(l, m)];
    num += axes.weights[k] * (b - truncated) * (b - truncated);
    den += axes.weights[k] * b * b;
  }
  return std::sqrt(num / den);
}

TEST(Environment, LobeFilteredErrorMatchesBruteForce) {
  const Environment env = Environment::from_equirect_pixels(96, 48, equirect_pixels(96, 48, sun_map({0.5, 0.5, 0.7071}, 8.0)));
  // B(a) = Σ_texels L ∫_texel w(a·x) dμ(x) has the map's coefficients of every order, so its RMS
  // truncation error is Σ_{l>s} ŵ_l² E_l exactly; the midpoint rule on texels split 2 × 2 is off
  // by ~(l h / 2)²/24 (about 1e-3 at l = 8 here), and the product rule over axes (degree 2 n_t − 1
  // in cos θ) integrates (B − B̃)² up to B's tail beyond order ~n_t: a few 1e-3 relative.
  struct Case {
    ZonalLobe lobe;
    int s;
  };
  for (const Case& k : {Case{ZonalLobe::lambert(), 2}, Case{ZonalLobe::lambert(), 4}, Case{ZonalLobe::phong(8.0), 4},
                        Case{ZonalLobe::phong(32.0), 6}}) {
    const double formula = lobe_filtered_error(env, k.lobe, k.s);
    const double brute = brute_force_lobe_error(env, k.lobe, k.s, 32, 64, 2);
    EXPECT_NEAR(formula, brute, 5e-3 * brute) << "sigma " << k.lobe.exponent << " s " << k.s;
  }
}

TEST(Environment, LobeFilteredErrorIsMonotoneAndSmallestOrderFindsIt) {
  const Environment env = Environment::from_equirect_pixels(128, 64, equirect_pixels(128, 64, sun_map({0.0, 0.0, 1.0}, 3.0)));
  for (const ZonalLobe& lobe : {ZonalLobe::lambert(), ZonalLobe::phong(8.0), ZonalLobe::phong(32.0)}) {
    double previous = 1.0 + kExact;
    for (int s = 0; s <= 64; ++s) {
      const double e = lobe_filtered_error(env, lobe, s);
      EXPECT_LE(e, previous) << "s = " << s;
      EXPECT_GE(e, 0.0);
      previous = e;
    }
    EXPECT_EQ(lobe_filtered_error(env, lobe, 64), 0.0);
    for (double target : {0.3, 0.05, 0.01}) {
      const int s = smallest_order(env, lobe, target, 64);
      ASSERT_GE(s, 0);
      EXPECT_LE(lobe_filtered_error(env, lobe, s), target);
      if (s > 0) EXPECT_GT(lobe_filtered_error(env, lobe, s - 1), target);
    }
  }
  // Narrower lobes need more bands.
  EXPECT_LT(smallest_order(env, ZonalLobe::lambert(), 0.02, 64), smallest_order(env, ZonalLobe::phong(32.0), 0.02, 64));
  EXPECT_EQ(smallest_order(env, ZonalLobe::phong(32.0), 1e-9, 4), -1);
  EXPECT_THROW(smallest_order(env, ZonalLobe::lambert(), -1.0, 4), std::invalid_argument);
  // A black map: nothing to miss.
  const Environment black = Environment::from_equirect_pixels(8, 4, std::vector<float>(96, 0.0f));
  EXPECT_EQ(lobe_filtered_error(black, ZonalLobe::lambert(), 2), 0.0);
  EXPECT_EQ(low_frequency_error(black, 2), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Blender's HDRIs (datafiles/studiolights/world/*.exr)

TEST(EnvironmentBlender, UnshadowedLambertAtOrder8AgainstBruteForce) {
  if (!have_blender_hdris()) GTEST_SKIP() << "Blender's studio lights are not installed at " << kBlenderWorlds;
  // B(n) = Σ_texels L 4 max(0, n·d) Δμ over the HDRI's pixels averaged 2 × 2 (a quarter of the
  // brute force's time; ReferenceDownsamplingIsNegligibleForTheErrors) against B̃_8(n) = Σ_{l<=8}
  // ŵ_l L_lm y_lm(n) of the same map, for 512 normals of a product rule (16 Gauss nodes in cos θ × 32 azimuths,
  // exact to degree 31) and the six axes.
  //
  // Measured: the relative RMS over normals is 0.1–1.4 % (within 1 % on six of the eight maps;
  // studio 1.1 %, sunrise 1.4 %), and it equals lobe_filtered_error(lambert, 8) — Funk–Hecke and
  // Parseval on real data. Per normal, the relative error is NOT within 1 %: where B is small
  // (normals facing away from a sun) it reaches tens of percent of B, while staying below 10 %
  // of the map's mean irradiance (∫ B dμ(n) = mass).
  const SphereRule rule = gauss_legendre_product_rule(16, 32);
  std::vector<glm::dvec3> normals = rule.dirs;
  std::vector<double> normal_weights = rule.weights;
  for (const glm::dvec3 axis : {glm::dvec3(1, 0, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, -1, 0),
                                glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1)}) {
    normals.push_back(axis);
    normal_weights.push_back(0.0);  // checked per normal only
  }
  const std::vector<double> w = ZonalLobe::lambert().coefficients(8);
  int64_t clamped = 0;
  int within_one_percent = 0;
  for (const char* name : kBlenderHdris) {
    const Environment full = Environment::load(kBlenderWorlds + name + ".exr");
    clamped += full.clamped_negative_pixels();
    const Environment env = full.area_averaged(full.width() / 2, full.height() / 2);
    const int64_t count = env.texel_count();
    std::vector<double> dx(count), dy(count), dz(count), lr(count), lg(count), lb(count);
    for (int64_t q = 0; q < count; ++q) {
      const glm::dvec3 d = env.texel_direction(q), l = env.texel_radiance(q) * env.texel_solid_angle(q);
      dx[q] = d.x, dy[q] = d.y, dz[q] = d.z, lr[q] = l.x, lg[q] = l.y, lb[q] = l.z;
    }
    const std::vector<double> c = sh(env, 8);
    double num = 0.0, den = 0.0, worst_relative = 0.0;
    for (size_t k = 0; k < normals.size(); ++k) {
      const glm::dvec3 n = normals[k];
      double br = 0.0, bg = 0.0, bb = 0.0;
      for (int64_t q = 0; q < count; ++q) {
        const double cosine = std::max(0.0, n.x * dx[q] + n.y * dy[q] + n.z * dz[q]);
        br += cosine * lr[q], bg += cosine * lg[q], bb += cosine * lb[q];
      }
      const glm::dvec3 direct = 4.0 * glm::dvec3(br, bg, bb);
      const std::vector<double> y = sh_basis(8, n);
      glm::dvec3 sh_value(0.0);
      for (int l = 0; l <= 8; ++l)
        for (int m = -l; m <= l; ++m) {
          const int i = sh_index(l, m);
          sh_value += w[l] * y[i] * glm::dvec3(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
        }
      for (int ch = 0; ch < 3; ++ch) {
        EXPECT_NEAR(sh_value[ch], direct[ch], 0.10 * env.mass(ch)) << name << " normal " << k << " channel " << ch;
        worst_relative = std::max(worst_relative, std::abs(sh_value[ch] - direct[ch]) / direct[ch]);
      }
      const double e = luminance(sh_value) - luminance(direct);
      num += normal_weights[k] * e * e;
      den += normal_weights[k] * luminance(direct) * luminance(direct);
    }
    const double rms = std::sqrt(num / den), formula = lobe_filtered_error(env, ZonalLobe::lambert(), 8);
    std::printf("  %-10s Lambert s=8: relative RMS over normals %.3f %% (lobe_filtered_error %.3f %%), worst "
                "normal %.1f %% of its B\n",
                name, 100 * rms, 100 * formula, 100 * worst_relative);
    EXPECT_NEAR(rms, formula, 0.05 * formula) << name;
    EXPECT_LT(rms, 0.015) << name;
    within_one_percent += rms <= 0.01 ? 1 : 0;
  }
  EXPECT_GE(within_one_percent, 6);
  EXPECT_GT(clamped, 0);  // these maps hold small negative pixels (msd-notes)
}

TEST(EnvironmentBlender, LobeFilteredErrorsMatchTheNotes) {
  if (!have_blender_hdris()) GTEST_SKIP() << "Blender's studio lights are not installed at " << kBlenderWorlds;
  // msd-notes: Lambert s=4 0.2–3 %, Phong σ=8 6–20 %, σ=32 22–63 %, ε(8) 0.6–1.0. Checked with a
  // margin for the rounding of those ranges; the measured values are printed.
  double lo[4] = {1, 1, 1, 1}, hi[4] = {0, 0, 0, 0};
  for (const char* name : kBlenderHdris) {
    const Environment env = Environment::load(kBlenderWorlds + name + ".exr");
    const double v[4] = {lobe_filtered_error(env, ZonalLobe::lambert(), 4), lobe_filtered_error(env, ZonalLobe::phong(8), 4),
                         lobe_filtered_error(env, ZonalLobe::phong(32), 4), low_frequency_error(env, 8)};
    std::printf("  %-10s Lambert s=4 %6.2f %%  Phong8 s=4 %6.2f %%  Phong32 s=4 %6.2f %%  eps(8) %.3f\n", name,
                100 * v[0], 100 * v[1], 100 * v[2], v[3]);
    for (int q = 0; q < 4; ++q) lo[q] = std::min(lo[q], v[q]), hi[q] = std::max(hi[q], v[q]);
    EXPECT_LT(v[0], v[1]);
    EXPECT_LT(v[1], v[2]);
  }
  EXPECT_GT(lo[0], 0.001);
  EXPECT_LT(hi[0], 0.04);
  EXPECT_GT(lo[1], 0.03);
  EXPECT_LT(hi[1], 0.25);
  EXPECT_GT(lo[2], 0.11);
  EXPECT_LT(hi[2], 0.70);
  EXPECT_GT(lo[3], 0.55);
  EXPECT_LE(hi[3], 1.0);
}

TEST(EnvironmentBlender, ReferenceDownsamplingIsNegligibleForTheErrors) {
  if (!have_blender_hdris()) GTEST_SKIP() << "Blender's studio lights are not installed at " << kBlenderWorlds;
  // A 4× coarser copy (much coarser than any reference copy) changes the lobe-filtered errors
  // of lobes up to σ = 32 by less than 3 % of their value: box filtering only touches high bands.
  for (const char* name : {"sunrise", "studio", "sunset"}) {
    const Environment env = Environment::load(kBlenderWorlds + name + ".exr");
    const Environment coarse = env.area_averaged(env.width() / 4, env.height() / 4);
    for (const ZonalLobe& lobe : {ZonalLobe::lambert(), ZonalLobe::phong(8.0), ZonalLobe::phong(32.0)}) {
      const double a = lobe_filtered_error(env, lobe, 4), b = lobe_filtered_error(coarse, lobe, 4);
      EXPECT_NEAR(b, a, 0.03 * a) << name << " sigma " << lobe.exponent;
    }
  }
}

}  // namespace
}  // namespace sd
