// Tests of sdlighting/environment.h: the texel layouts: orientation, solid angles and area averaging. Two kinds of tolerance are kept apart: kExact (1e-12,
// results the code computes exactly up to rounding) and the quadrature / Monte Carlo tolerances,
// each derived where it is used.
#include "environment_test_support.h"
#include "sdlighting/environment.h"
#include "sdlighting/sh_projection.h"
#include "sdlighting/spherical_harmonics.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace sd {
namespace {

using namespace test;

// ---------------------------------------------------------------------------------------------
// Orientation and geometry

TEST(Environment, OrientationOfSinglePixels) {
  // One bright pixel: its band-1 coefficients point at its direction (exactly, one texel).
  struct Case {
    int width, height, i, j;
    glm::dvec3 expected;
  };
  const Case cases[] = {
      {65, 33, 32, 16, {1.0, 0.0, 0.0}},  // horizontal centre of the image -> +X
      {66, 33, 16, 16, {0.0, 1.0, 0.0}},  // column W/4 (φ = π/2 exactly for W = 66, i = 16) -> +Y
      {66, 33, 49, 16, {0.0, -1.0, 0.0}},  // column 3W/4 -> −Y
      {66, 33, 0, 16, {-1.0, 0.0, 0.0}},  // left edge -> −X (within half a pixel)
  };
  for (const Case& k : cases) {
    std::vector<float> rgb(static_cast<size_t>(k.width) * k.height * 3, 0.0f);
    for (int c = 0; c < 3; ++c) rgb[3 * (static_cast<size_t>(k.j) * k.width + k.i) + c] = 100.0f;
    const Environment env = Environment::from_equirect_pixels(k.width, k.height, rgb);
    const glm::dvec3 d = normalized(band1_vector(sh(env, 1), 0));
    const double tolerance = k.i == 0 ? 1.0 - std::cos(kPi / k.width) + kExact : kExact;
    EXPECT_GT(glm::dot(d, k.expected), 1.0 - tolerance) << "pixel (" << k.i << ", " << k.j << ")";
    EXPECT_FLOAT_EQ(static_cast<float>(env.radiance(k.expected).x), 100.0f);
  }
  // The top row looks at +Z, the bottom row at −Z.
  for (int row : {0, 32}) {
    std::vector<float> rgb(static_cast<size_t>(64) * 33 * 3, 0.0f);
    for (int i = 0; i < 64; ++i) rgb[3 * (static_cast<size_t>(row) * 64 + i)] = 1.0f;
    const Environment env = Environment::from_equirect_pixels(64, 33, rgb);
    const glm::dvec3 d = normalized(band1_vector(sh(env, 1), 0));
    EXPECT_NEAR(d.z, row == 0 ? 1.0 : -1.0, kExact);
    EXPECT_EQ(env.radiance({0.0, 0.0, row == 0 ? 1.0 : -1.0}).x, 1.0);
  }
}

TEST(Environment, LookupFollowsCyclesFormula) {
  // texel_index(d) against u = 0.5 − atan2(y, x)/2π, v = 1 − acos(z)/π (v = 0 at the bottom row).
  const int width = 40, height = 24;
  std::vector<float> rgb(static_cast<size_t>(width) * height * 3, 0.0f);
  const Environment env = Environment::from_equirect_pixels(width, height, rgb);
  std::mt19937_64 rng(7);
  for (int k = 0; k < 2000; ++k) {
    const glm::dvec3 d = random_direction(rng);
    const double u = 0.5 - std::atan2(d.y, d.x) / (2.0 * kPi), v = 1.0 - std::acos(d.z) / kPi;
    const int i = std::min(width - 1, static_cast<int>(u * width));
    const int row_from_bottom = std::min(height - 1, static_cast<int>(v * height));
    EXPECT_EQ(env.texel_index(d), static_cast<int64_t>(height - 1 - row_from_bottom) * width + i);
    EXPECT_EQ(env.texel_index(3.5 * d), env.texel_index(d));  // length does not matter
  }
  EXPECT_THROW(env.texel_index({0.0, 0.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(env.texel_index({NAN, 0.0, 1.0}), std::invalid_argument);
}

TEST(Environment, TexelDirectionsAndLookupAgree) {
  const Environment equirect = Environment::from_equirect_pixels(37, 19, std::vector<float>(37 * 19 * 3, 1.0f));
  const Environment cube = Environment::from_cube_pixels(9, std::vector<float>(6 * 81 * 3, 1.0f));
  for (const Environment* env : {&equirect, &cube}) {
    for (int64_t t = 0; t < env->texel_count(); ++t) {
      ASSERT_EQ(env->texel_index(env->texel_direction(t)), t);
      ASSERT_NEAR(glm::length(env->texel_direction(t)), 1.0, kExact);
    }
  }
  // Texel centres against the independent formulas.
  for (int j = 0; j < 19; ++j)
    for (int i = 0; i < 37; ++i)
      ASSERT_LT(glm::length(equirect.texel_direction(j * 37 + i) - equirect_pixel_direction(i, j, 37, 19)), kExact);
  for (int f = 0; f < 6; ++f)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 9; ++i)
        ASSERT_LT(glm::length(cube.texel_direction((f * 9 + j) * 9 + i) - cube_pixel_direction(f, i, j, 9)), kExact);
  // Face centres look along the axes in the documented order +X, −X, +Y, −Y, +Z, −Z.
  const glm::dvec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int f = 0; f < 6; ++f) EXPECT_EQ(cube.texel_index(axes[f]), (f * 9 + 4) * 9 + 4);
}

TEST(Environment, SolidAnglesAreExactAndSumToOne) {
  const Environment equirect = Environment::from_equirect_pixels(48, 31, std::vector<float>(48 * 31 * 3, 1.0f));
  double sum = 0.0;
  for (int64_t t = 0; t < equirect.texel_count(); ++t) {
    const int j = static_cast<int>(t / 48);
    const double expected = (2.0 * kPi / 48) * (std::cos(kPi * j / 31) - std::cos(kPi * (j + 1) / 31)) / (4.0 * kPi);
    ASSERT_NEAR(equirect.texel_solid_angle(t), expected, 1e-15);
    sum += equirect.texel_solid_angle(t);
  }
  EXPECT_NEAR(sum, 1.0, kExact);
  EXPECT_NEAR(equirect.mass(0), 1.0, kExact);
  EXPECT_NEAR(equirect.mass(kLuminance), 1.0, kExact);

  const int n = 16;
  const Environment cube = Environment::from_cube_pixels(n, std::vector<float>(6 * n * n * 3, 1.0f));
  std::array<double, 6> per_face{};
  for (int64_t t = 0; t < cube.texel_count(); ++t) per_face[t / (n * n)] += cube.texel_solid_angle(t);
  for (double s : per_face) EXPECT_NEAR(s, 1.0 / 6.0, kExact);
  EXPECT_NEAR(cube.mass(1), 1.0, kExact);
  // One corner texel against a fine midpoint integration of dω = da db / (1 + a² + b²)^{3/2}.
  const int sub = 400;
  double omega = 0.0;
  const double h = (2.0 / n) / sub;
  for (int p = 0; p < sub; ++p) {
    for (int q = 0; q < sub; ++q) {
      const double a = -1.0 + (p + 0.5) * h, b = -1.0 + (q + 0.5) * h;
      omega += h * h / std::pow(1.0 + a * a + b * b, 1.5);
    }
  }
  EXPECT_NEAR(cube.texel_solid_angle(0), omega / (4.0 * kPi), 1e-9);
}

// ---------------------------------------------------------------------------------------------
// Area averaging

TEST(Environment, AreaAveragingPreservesMass) {
  std::mt19937_64 rng(9);
  const Environment env = Environment::from_equirect_pixels(100, 50, random_pixels(100 * 50 * 3, 10.0f, rng));
  for (auto [w, h] : {std::pair{37, 19}, std::pair{50, 25}, std::pair{7, 3}, std::pair{150, 61}}) {
    const Environment small = env.area_averaged(w, h);
    EXPECT_EQ(small.width(), w);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(small.mass(c), env.mass(c), 1e-7 * env.mass(c)) << w << "x" << h;
  }
  // Halving: each new texel is the solid-angle-weighted mean of its 2×2 block.
  const Environment half = env.area_averaged(50, 25);
  for (int j = 0; j < 25; ++j) {
    for (int i = 0; i < 50; ++i) {
      double num = 0.0, den = 0.0;
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) {
          const int64_t t = (2 * j + dj) * 100 + 2 * i + di;
          num += env.texel_radiance(t).y * env.texel_solid_angle(t);
          den += env.texel_solid_angle(t);
        }
      ASSERT_NEAR(half.texel_radiance(j * 50 + i).y, num / den, 1e-5);
    }
  }
  const Environment cube = Environment::from_cube_pixels(20, random_pixels(6 * 20 * 20 * 3, 10.0f, rng));
  for (int m : {7, 10, 1}) {
    const Environment small = cube.area_averaged(m, m);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(small.mass(c), cube.mass(c), 1e-7 * cube.mass(c));
  }
  const Environment constant = Environment::from_cube_pixels(20, std::vector<float>(6 * 400 * 3, 2.5f));
  const Environment constant_small = constant.area_averaged(7, 7);
  for (float v : constant_small.pixels()) EXPECT_NEAR(v, 2.5f, 1e-6f);
  EXPECT_THROW(cube.area_averaged(7, 8), std::invalid_argument);
  EXPECT_THROW(env.area_averaged(0, 8), std::invalid_argument);
}

}  // namespace
}  // namespace sd
