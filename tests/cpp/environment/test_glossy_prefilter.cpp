// The split sum (glossy_prefilter.h): the prefiltered atlas against a brute-force convolution of
// the map's texels, its layout and level 0, the GGX directional albedo against closed forms, and the
// lobe's mean direction (glossy_bend) against a quadrature over the hemisphere.
#include "environment_test_support.h"
#include "sdlighting/glossy_prefilter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace sd::test {
namespace {

// The prefilter against the exact convolution of a map with a bright soft blob: relative RMS over a
// level, and its worst texel (filtered importance sampling near r is a biased estimator).
constexpr double kFilteredSampling = 0.02;
// Texels 20 degrees and more from a small sun 2000x the sky (0.5 % measured; sampling the whole
// lobe put them up to 21 % off).
constexpr double kAwayFromTheSun = 0.02;
// A cube map's atlas against its equirect copy's, relative RMS over a level (0.25 % measured; 2.7 %
// before its tail was summed over an equirect resampling).
constexpr double kCubeAgainstEquirect = 0.01;
// Quasi-Monte Carlo (Hammersley, 4096 points) against a closed form.
constexpr double kQuasiMonteCarlo = 2e-3;
// The lobe's mean direction by Hammersley half vectors against a quadrature over l (degrees).
constexpr double kMeanDirectionDegrees = 0.5;

// The atlas's RGB at texel (i, j) of level k (rows bottom-first within the level).
glm::dvec3 atlas_texel(const std::vector<float>& atlas, const PrefilterLayout& layout, int k, int i, int j) {
  const auto origin = layout.level_origin(k);
  const size_t t = (static_cast<size_t>(origin[1] + j) * layout.atlas_width() + origin[0] + i) * 3;
  return {atlas[t], atlas[t + 1], atlas[t + 2]};
}

// Direction of texel (i, j) of a level: its rows run bottom-first, equirect_pixel_direction's top-first.
glm::dvec3 level_direction(const PrefilterLayout& layout, int k, int i, int j) {
  return equirect_pixel_direction(i, layout.level_height(k) - 1 - j, layout.level_width(k), layout.level_height(k));
}

// ∫ L(l) D(h) (r·l)⁺ dl / ∫ D(h) (r·l)⁺ dl with n = v = r over the map's texels (their centres).
glm::dvec3 brute_force_prefilter(const Environment& env, const glm::dvec3& r, double roughness) {
  const double a2 = std::pow(roughness * roughness, 2);
  glm::dvec3 sum(0.0);
  double weight = 0.0;
  for (int64_t t = 0; t < env.texel_count(); ++t) {
    const glm::dvec3 l = env.texel_direction(t);
    const double r_dot_l = glm::dot(r, l);
    if (r_dot_l <= 0.0) continue;
    const double n_dot_h = glm::dot(r, glm::normalize(r + l));
    const double d = (a2 - 1.0) * n_dot_h * n_dot_h + 1.0;
    const double w = a2 / (kPi * d * d) * r_dot_l * env.texel_solid_angle(t);
    sum += w * env.texel_radiance(t);
    weight += w;
  }
  return sum / weight;
}

// A smooth map with a bright soft blob: a gradient sky and a Gaussian bump of about 8 degrees.
Radiance soft_sun() {
  const glm::dvec3 sun = glm::normalize(glm::dvec3(0.4, -0.3, 0.6));
  return [sun](const glm::dvec3& d) {
    const double angle = std::acos(std::clamp(glm::dot(d, sun), -1.0, 1.0));
    const double blob = 40.0 * std::exp(-0.5 * std::pow(angle / 0.14, 2));
    const double sky = 0.3 + 0.2 * d.z;
    return glm::dvec3(sky + blob, sky + 0.8 * blob, 1.4 * sky + 0.5 * blob);
  };
}

TEST(GlossyPrefilter, LayoutTilesTheAtlasWithoutOverlap) {
  for (const PrefilterLayout& layout : {PrefilterLayout{256, 7}, PrefilterLayout{1024, 9}, PrefilterLayout{64, 3},
                                        PrefilterLayout{64, 4}}) {
    std::vector<int> owner(static_cast<size_t>(layout.atlas_width()) * layout.atlas_height(), -1);
    for (int k = 0; k < layout.levels; ++k) {
      const auto origin = layout.level_origin(k);
      ASSERT_EQ(layout.level_width(k), 2 * layout.level_height(k));
      for (int j = 0; j < layout.level_height(k); ++j)
        for (int i = 0; i < layout.level_width(k); ++i) {
          ASSERT_LT(origin[0] + i, layout.atlas_width()) << layout.width0 << " x " << layout.levels << ", level " << k;
          ASSERT_LT(origin[1] + j, layout.atlas_height()) << layout.width0 << " x " << layout.levels << ", level " << k;
          int& o = owner[static_cast<size_t>(origin[1] + j) * layout.atlas_width() + origin[0] + i];
          ASSERT_EQ(o, -1) << "level " << k << " overlaps level " << o;
          o = k;
        }
    }
  }
}

TEST(GlossyPrefilter, AlphaDoublesFromLevelToLevelUpToOne) {
  const PrefilterLayout layout{1024, 9};
  EXPECT_DOUBLE_EQ(layout.roughness(0), 0.0);
  EXPECT_DOUBLE_EQ(layout.roughness(8), 1.0);
  EXPECT_DOUBLE_EQ(layout.roughness(1), std::sqrt(1.0 / 128.0));
  for (int k = 1; k + 1 < layout.levels; ++k) {
    EXPECT_DOUBLE_EQ(std::pow(layout.roughness(k + 1), 4), 4.0 * std::pow(layout.roughness(k), 4)) << k;
    EXPECT_GE(layout.level_width(k), layout.level_width(k + 1)) << k;
  }
  EXPECT_EQ(layout.level_width(1), 1024);
  EXPECT_EQ(layout.level_width(8), 16);
}

TEST(GlossyPrefilter, ConstantMapStaysConstantAtEveryRoughness) {
  const Environment env = Environment::from_equirect_pixels(
      64, 32, equirect_pixels(64, 32, [](const glm::dvec3&) { return glm::dvec3(0.5, 1.0, 2.0); }));
  const PrefilterLayout layout{64, 4};
  const std::vector<float> atlas = prefilter_ggx(env, layout, 32);
  for (int k = 0; k < layout.levels; ++k)
    for (int j = 0; j < layout.level_height(k); ++j)
      for (int i = 0; i < layout.level_width(k); ++i) {
        const glm::dvec3 v = atlas_texel(atlas, layout, k, i, j);
        ASSERT_NEAR(v.x, 0.5, 1e-5);
        ASSERT_NEAR(v.z, 2.0, 4e-5);
      }
}

TEST(GlossyPrefilter, LevelZeroIsTheMapItself) {
  const Environment env = Environment::from_equirect_pixels(128, 64, equirect_pixels(128, 64, soft_sun()));
  const PrefilterLayout layout{128, 3};
  const std::vector<float> atlas = prefilter_ggx(env, layout, 16);
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 128; ++i) {
      const glm::dvec3 expected = env.texel_radiance(static_cast<int64_t>(63 - j) * 128 + i);
      ASSERT_LT(glm::length(atlas_texel(atlas, layout, 0, i, j) - expected), 1e-5 * glm::length(expected));
    }
}

TEST(GlossyPrefilter, MatchesTheConvolutionOfTheMapsTexels) {
  const Environment env = Environment::from_equirect_pixels(256, 128, equirect_pixels(256, 128, soft_sun()));
  const PrefilterLayout layout{256, 7};
  const std::vector<float> atlas = prefilter_ggx(env, layout, 128);
  for (int k = 1; k < layout.levels; ++k) {
    const int width = layout.level_width(k), height = layout.level_height(k);
    double worst = 0.0, squared = 0.0, norm = 0.0;
    for (int j = 1; j < height; j += std::max(1, height / 6))
      for (int i = 0; i < width; i += std::max(1, width / 8)) {
        const glm::dvec3 expected = brute_force_prefilter(env, level_direction(layout, k, i, j), layout.roughness(k));
        const glm::dvec3 got = atlas_texel(atlas, layout, k, i, j);
        worst = std::max(worst, glm::length(got - expected) / glm::length(expected));
        squared += glm::dot(got - expected, got - expected);
        norm += glm::dot(expected, expected);
      }
    EXPECT_LT(std::sqrt(squared / norm), kFilteredSampling) << "level " << k << " (roughness " << layout.roughness(k) << ")";
    EXPECT_LT(worst, kFilteredSampling) << "level " << k << " (roughness " << layout.roughness(k) << ")";
  }
}

TEST(GlossyPrefilter, AWideMapOfAnyWidthIsSummedOverItsAverage) {
  // 600 x 300: wider than the tails' map (box-filtered down to it) and no power of two.
  const Environment env = Environment::from_equirect_pixels(600, 300, equirect_pixels(600, 300, soft_sun()));
  const PrefilterLayout layout{128, 6};
  const std::vector<float> atlas = prefilter_ggx(env, layout, 64);
  for (int k = 1; k < layout.levels; ++k)
    for (const auto& [i, j] : {std::pair{3, 40}, std::pair{50, 20}, std::pair{90, 55}}) {
      const int width = layout.level_width(k), height = layout.level_height(k);
      const int column = i * width / 128, row = j * height / 64;
      const glm::dvec3 expected = brute_force_prefilter(env, level_direction(layout, k, column, row), layout.roughness(k));
      EXPECT_LT(glm::length(atlas_texel(atlas, layout, k, column, row) - expected), kFilteredSampling * glm::length(expected))
          << "level " << k << " texel " << column << ", " << row;
    }
}

TEST(GlossyPrefilter, ANarrowMapOfAnyWidthIsSummedOverItself) {
  // 90 x 45: narrower than the tails' map and no power of two (the row FFTs are 90 long).
  const Environment env = Environment::from_equirect_pixels(90, 45, equirect_pixels(90, 45, soft_sun()));
  const PrefilterLayout layout{64, 5};
  const std::vector<float> atlas = prefilter_ggx(env, layout, 64);
  for (int k = 1; k < layout.levels; ++k)
    for (int j = 1; j < layout.level_height(k); j += 5)
      for (int i = 0; i < layout.level_width(k); i += 7) {
        const glm::dvec3 expected = brute_force_prefilter(env, level_direction(layout, k, i, j), layout.roughness(k));
        EXPECT_LT(glm::length(atlas_texel(atlas, layout, k, i, j) - expected), kFilteredSampling * glm::length(expected))
            << "level " << k << " texel " << i << ", " << j;
      }
}

TEST(GlossyPrefilter, TinyMapsGiveFiniteLevels) {
  // Texels of 90 degrees and more: the tails are summed over a resampled copy.
  for (const auto& [width, height] : {std::pair{1, 1}, std::pair{2, 1}, std::pair{4, 2}, std::pair{3, 1}}) {
    const Environment env = Environment::from_equirect_pixels(
        width, height, equirect_pixels(width, height, [](const glm::dvec3& d) { return glm::dvec3(1.0 + d.z, 1.0, 0.5); }));
    const std::vector<float> atlas = prefilter_ggx(env, PrefilterLayout{16, 4}, 16);
    for (float v : atlas) ASSERT_TRUE(std::isfinite(v)) << width << " x " << height;
    const glm::dvec3 any = atlas_texel(atlas, PrefilterLayout{16, 4}, 3, 3, 2);
    EXPECT_NEAR(any.y, 1.0, 1e-5) << width << " x " << height;   // the constant channel stays so
  }
}

TEST(GlossyPrefilter, KeepsASunsLightOutOfTheDarkSkyAroundIt) {
  // A 4-degree sun 2000x the sky: the texels away from it hold the sky and the lobe's far tail,
  // where sampling the whole lobe read the sun's coarse texels (several times the exact value).
  const glm::dvec3 sun = glm::normalize(glm::dvec3(0.3, 0.5, 0.4));
  const Environment env = Environment::from_equirect_pixels(256, 128, equirect_pixels(256, 128, sun_map(sun, 4.0)));
  const PrefilterLayout layout{256, 7};
  const std::vector<float> atlas = prefilter_ggx(env, layout, 64);
  for (int k = 1; k < layout.levels; ++k) {
    const int width = layout.level_width(k), height = layout.level_height(k);
    double worst = 0.0;
    for (int j = 0; j < height; j += std::max(1, height / 8))
      for (int i = 0; i < width; i += std::max(1, width / 8)) {
        const glm::dvec3 r = level_direction(layout, k, i, j);
        if (glm::dot(r, sun) > std::cos(20.0 * kPi / 180.0)) continue;
        const glm::dvec3 expected = brute_force_prefilter(env, r, layout.roughness(k));
        worst = std::max(worst, glm::length(atlas_texel(atlas, layout, k, i, j) - expected) / glm::length(expected));
      }
    EXPECT_LT(worst, kAwayFromTheSun) << "level " << k << " (roughness " << layout.roughness(k) << ")";
  }
}

TEST(GlossyPrefilter, ACubeMapPrefiltersAsItsEquirectCopy) {
  const PrefilterLayout layout{128, 6};
  const std::vector<float> cube = prefilter_ggx(Environment::from_cube_pixels(64, cube_pixels(64, soft_sun())), layout, 64);
  const std::vector<float> equirect =
      prefilter_ggx(Environment::from_equirect_pixels(256, 128, equirect_pixels(256, 128, soft_sun())), layout, 64);
  for (int k = 1; k < layout.levels; ++k) {
    double squared = 0.0, norm = 0.0;
    for (int j = 0; j < layout.level_height(k); ++j)
      for (int i = 0; i < layout.level_width(k); ++i) {
        const glm::dvec3 d = atlas_texel(cube, layout, k, i, j) - atlas_texel(equirect, layout, k, i, j);
        squared += glm::dot(d, d);
        norm += glm::dot(atlas_texel(equirect, layout, k, i, j), atlas_texel(equirect, layout, k, i, j));
      }
    EXPECT_LT(std::sqrt(squared / norm), kCubeAgainstEquirect) << "level " << k;
  }
}

TEST(GlossyPrefilter, RefusesBadLayoutsAndSampleCounts) {
  const Environment env = Environment::from_equirect_pixels(8, 4, std::vector<float>(96, 1.0f));
  EXPECT_THROW(prefilter_ggx(env, PrefilterLayout{100, 3}, 16), std::invalid_argument);
  EXPECT_THROW(prefilter_ggx(env, PrefilterLayout{1 << 30, 20}, 16), std::invalid_argument);
  EXPECT_THROW(prefilter_ggx(env, PrefilterLayout{64, 8}, 16), std::invalid_argument);
  EXPECT_THROW(prefilter_ggx(env, PrefilterLayout{64, 2}, 16), std::invalid_argument);
  EXPECT_THROW(prefilter_ggx(env, PrefilterLayout{64, 3}, 0), std::invalid_argument);
  EXPECT_THROW(prefilter_ggx(env, PrefilterLayout{64, 3}, 5000), std::invalid_argument);
}

TEST(EnvironmentBrdf, AMirrorReflectsEverything) {
  // α → 0: G = 1 and h = n, so A + B = 1 with B = (1 − n·v)⁵.
  for (double n_dot_v : {1.0, 0.7, 0.3}) {
    const auto ab = environment_brdf(n_dot_v, 0.0, 4096);
    EXPECT_NEAR(ab[0] + ab[1], 1.0, kQuasiMonteCarlo) << n_dot_v;
    EXPECT_NEAR(ab[1], std::pow(1.0 - n_dot_v, 5.0), kQuasiMonteCarlo) << n_dot_v;
  }
}

TEST(EnvironmentBrdf, DielectricShapeAtAMirrorIsTheRemappedFresnel) {
  // α → 0: B is the remapped Fresnel at n·v itself, here from the s- and p-polarised reflectances.
  const double ior = 1.5, f0 = std::pow((ior - 1.0) / (ior + 1.0), 2.0);
  for (double n_dot_v : {1.0, 0.7, 0.3, 0.05}) {
    const double cos_t = std::sqrt(1.0 - (1.0 - n_dot_v * n_dot_v) / (ior * ior));
    const double rs = std::pow((n_dot_v - ior * cos_t) / (n_dot_v + ior * cos_t), 2.0);
    const double rp = std::pow((cos_t - ior * n_dot_v) / (cos_t + ior * n_dot_v), 2.0);
    const auto ab = environment_brdf(n_dot_v, 0.0, 4096, ior);
    EXPECT_NEAR(ab[0] + ab[1], 1.0, kQuasiMonteCarlo) << n_dot_v;
    EXPECT_NEAR(ab[1], (0.5 * (rs + rp) - f0) / (1.0 - f0), kQuasiMonteCarlo) << n_dot_v;
  }
}

TEST(EnvironmentBrdf, FresnelShapeLeavesTheLobesAlbedo) {
  for (double n_dot_v : {0.9, 0.4})
    for (double roughness : {0.3, 0.8}) {
      const auto schlick = environment_brdf(n_dot_v, roughness, 4096);
      const auto dielectric = environment_brdf(n_dot_v, roughness, 4096, 1.5);
      EXPECT_NEAR(schlick[0] + schlick[1], dielectric[0] + dielectric[1], 1e-12);
      EXPECT_GT(dielectric[1], schlick[1]);   // IOR 1.5 rises earlier than (1 - v.h)^5
    }
  for (double ior : {-1.0, 0.5, 1.0, 2e6}) {
    EXPECT_THROW(environment_brdf(0.5, 0.5, 64, ior), std::invalid_argument) << ior;
    EXPECT_THROW(environment_brdf_table(4, 64, ior), std::invalid_argument) << ior;
  }
}

TEST(EnvironmentBrdf, RoughestLobeAtNormalIncidenceLosesLnTwo) {
  // α = 1, v = n: D is uniform in (n·h)², n·l = 2 (n·h)² − 1 uniform in [−1, 1], and the
  // height-correlated G2 = 2 n·l / (n·l + 1): A + B = ∫₀¹ n·l / (n·l + 1) = 1 − ln 2.
  const auto ab = environment_brdf(1.0, 1.0, 4096);
  EXPECT_NEAR(ab[0] + ab[1], 1.0 - std::log(2.0), kQuasiMonteCarlo);
}

TEST(EnvironmentBrdf, StaysWithinEnergyAndRefusesBadInput) {
  for (double n_dot_v : {1.0, 0.5, 0.1, 0.01})
    for (double roughness : {0.0, 0.2, 0.5, 1.0}) {
      const auto ab = environment_brdf(n_dot_v, roughness, 4096);
      EXPECT_GE(ab[0], 0.0);
      EXPECT_GE(ab[1], 0.0);
      EXPECT_LE(ab[0] + ab[1], 1.0 + kQuasiMonteCarlo);
    }
  EXPECT_THROW(environment_brdf(0.0, 0.5), std::invalid_argument);
  EXPECT_THROW(environment_brdf(0.5, 1.5), std::invalid_argument);
  EXPECT_THROW(environment_brdf(0.5, 0.5, 0), std::invalid_argument);
}

TEST(EnvironmentBrdf, TableHoldsTheIntegralAtItsEntries) {
  const int size = 8;
  const std::vector<float> table = environment_brdf_table(size, 256);
  for (int j : {0, 3, 7})
    for (int i : {0, 4, 7}) {
      const auto ab = environment_brdf((i + 0.5) / size, j / 7.0, 256);
      EXPECT_FLOAT_EQ(table[2 * (j * size + i)], static_cast<float>(ab[0]));
      EXPECT_FLOAT_EQ(table[2 * (j * size + i) + 1], static_cast<float>(ab[1]));
    }
  EXPECT_THROW(environment_brdf_table(1), std::invalid_argument);
  EXPECT_THROW(environment_brdf_table(300), std::invalid_argument);
}

// The mean direction of f₁ (n·l) (GGX, F = 1, Smith height-correlated G2), n = +z, v in the xz
// plane, by the midpoint rule over l in (θ, φ): its angle from n in degrees, towards r (x < 0).
double lobe_mean_angle_by_quadrature(double n_dot_v, double roughness) {
  const double alpha = roughness * roughness, a2 = alpha * alpha;
  const glm::dvec3 v(std::sqrt(1.0 - n_dot_v * n_dot_v), 0.0, n_dot_v);
  const auto lambda_term = [a2](double c) { return std::sqrt(a2 + (1.0 - a2) * c * c); };
  const int rows = 1200, columns = 2400;
  double x = 0.0, z = 0.0;
  for (int j = 0; j < rows; ++j) {
    const double theta = (j + 0.5) * 0.5 * kPi / rows;
    for (int i = 0; i < columns; ++i) {
      const double phi = (i + 0.5) * 2.0 * kPi / columns;
      const glm::dvec3 l(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      const glm::dvec3 h = glm::normalize(l + v);
      const double d = (a2 - 1.0) * h.z * h.z + 1.0;
      const double g2 = 2.0 * l.z * n_dot_v / (l.z * lambda_term(n_dot_v) + n_dot_v * lambda_term(l.z));
      // f₁ (n·l) dl = D G2 / (4 n·v) sin θ dθ dφ; constant factors drop out of the direction
      const double weight = a2 / (d * d) * g2 * std::sin(theta);
      x += weight * l.x;
      z += weight * l.z;
    }
  }
  return std::atan2(-x, z) * 180.0 / kPi;
}

// The angle from n of normalize(mix(n, r, bend)) in degrees.
double bent_angle(double n_dot_v, double bend) {
  const double sin_r = std::sqrt(1.0 - n_dot_v * n_dot_v);
  return std::atan2(bend * sin_r, 1.0 - bend + bend * n_dot_v) * 180.0 / kPi;
}

TEST(GlossyBend, IsTheLobesMeanDirection) {
  for (double roughness : {0.3, 0.5, 0.8})
    for (double n_dot_v : {0.9, 0.5, 0.15}) {
      const double bend = glossy_bend(n_dot_v, roughness, 4096);
      EXPECT_NEAR(bent_angle(n_dot_v, bend), lobe_mean_angle_by_quadrature(n_dot_v, roughness), kMeanDirectionDegrees)
          << roughness << " " << n_dot_v;
    }
}

TEST(GlossyBend, AMirrorReadsTheMirroredViewAndRoughLobesLeanToTheNormal) {
  for (double n_dot_v : {1.0, 0.7, 0.2, 0.05}) EXPECT_NEAR(glossy_bend(n_dot_v, 0.0, 4096), 1.0, 1e-4) << n_dot_v;   // α = 1e-4
  for (double roughness : {0.3, 0.5, 1.0}) EXPECT_EQ(glossy_bend(1.0, roughness, 256), 1.0) << roughness;
  for (double roughness : {0.3, 0.5, 0.8}) {
    double last = 1.0;
    for (double n_dot_v : {0.95, 0.7, 0.4, 0.1}) {
      const double bend = glossy_bend(n_dot_v, roughness, 4096);
      EXPECT_LT(bend, last) << roughness << " " << n_dot_v;
      EXPECT_GE(bend, 0.0);
      last = bend;
    }
  }
  EXPECT_LT(glossy_bend(0.3, 0.8, 4096), glossy_bend(0.3, 0.4, 4096));
}

TEST(GlossyBend, TableHoldsItAtItsEntriesAndBadInputIsRefused) {
  const int size = 8;
  const std::vector<float> table = glossy_bend_table(size, 256);
  ASSERT_EQ(table.size(), static_cast<size_t>(size * size));
  for (int j : {0, 3, 7})
    for (int i : {0, 4, 7}) EXPECT_FLOAT_EQ(table[j * size + i], static_cast<float>(glossy_bend((i + 0.5) / size, j / 7.0, 256)));
  EXPECT_THROW(glossy_bend(0.0, 0.5), std::invalid_argument);
  EXPECT_THROW(glossy_bend(0.5, -0.1), std::invalid_argument);
  EXPECT_THROW(glossy_bend(0.5, 0.5, 0), std::invalid_argument);
  EXPECT_THROW(glossy_bend_table(1), std::invalid_argument);
  EXPECT_THROW(glossy_bend_table(8, 0), std::invalid_argument);
}

}  // namespace
}  // namespace sd::test
