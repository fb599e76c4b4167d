// Tests of sdlighting/environment.h. Two kinds of tolerance are kept apart: kExact (1e-12, results
// the code computes exactly up to rounding) and the quadrature / Monte Carlo tolerances, each
// derived where it is used. Real HDRIs: Blender's studio lights (skipped, with a message, only
// when the files are absent).
#include "sdlighting/environment.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_design.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/zonal_lobe.h"
#include "sphere_test_support.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

namespace sd {
namespace {

constexpr double kExact = 1e-12;
constexpr double kPi = 3.14159265358979323846;
const std::string kBlenderWorlds = "/usr/share/blender/datafiles/studiolights/world/";
const char* const kBlenderHdris[] = {"city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset"};

using Radiance = std::function<glm::dvec3(const glm::dvec3&)>;
using test::equirect_pixel_direction;
using test::random_direction;
using test::random_rotation;
using test::SphereRule;

// ---- references written independently of the library ----

std::vector<float> equirect_pixels(int width, int height, const Radiance& f) {
  std::vector<float> rgb(static_cast<size_t>(width) * height * 3);
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const glm::dvec3 v = f(equirect_pixel_direction(i, j, width, height));
      for (int c = 0; c < 3; ++c) rgb[3 * (static_cast<size_t>(j) * width + i) + c] = static_cast<float>(v[c]);
    }
  }
  return rgb;
}

// The OpenGL face table inverted by hand: face coordinates sc = 2s − 1, tc = 2t − 1 of face f.
glm::dvec3 cube_pixel_direction(int face, int i, int j, int n) {
  const double sc = 2.0 * (i + 0.5) / n - 1.0, tc = 2.0 * (j + 0.5) / n - 1.0;
  const glm::dvec3 table[6] = {{1.0, -tc, -sc}, {-1.0, -tc, sc}, {sc, 1.0, tc},
                               {sc, -1.0, -tc}, {sc, -tc, 1.0}, {-sc, -tc, -1.0}};
  return glm::normalize(table[face]);
}

std::vector<float> cube_pixels(int n, const Radiance& f) {
  std::vector<float> rgb(static_cast<size_t>(6) * n * n * 3);
  for (int face = 0; face < 6; ++face) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const glm::dvec3 v = f(cube_pixel_direction(face, i, j, n));
        for (int c = 0; c < 3; ++c) rgb[3 * ((static_cast<size_t>(face) * n + j) * n + i) + c] = static_cast<float>(v[c]);
      }
    }
  }
  return rgb;
}

double luminance(const glm::dvec3& v) { return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z; }

// A random positive band-limited RGB function of order s: coefficients c[3 i + ch].
struct BandLimited {
  int order;
  std::vector<double> c;
  glm::dvec3 operator()(const glm::dvec3& d) const {
    const std::vector<double> y = sh_basis(order, d);
    glm::dvec3 v(0.0);
    for (int i = 0; i < sh_count(order); ++i) v += y[i] * glm::dvec3(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
    return v;
  }
};

BandLimited random_band_limited(int order, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  BandLimited f{order, std::vector<double>(3 * sh_count(order))};
  std::array<double, 3> bound = {0.0, 0.0, 0.0};
  for (int l = 1; l <= order; ++l) {
    for (int m = -l; m <= l; ++m) {
      for (int ch = 0; ch < 3; ++ch) {
        const double v = normal(rng) / (l + 1.0);
        f.c[3 * sh_index(l, m) + ch] = v;
        bound[ch] += std::abs(v) * std::sqrt(2.0 * l + 1.0);  // |y_lm| <= sqrt(2l+1)
      }
    }
  }
  for (int ch = 0; ch < 3; ++ch) f.c[ch] = 0.5 + bound[ch];  // positive everywhere: nothing clamped
  return f;
}

// `count` floats uniform in [0, max), drawn from rng in order: random pixels of a test map.
std::vector<float> random_pixels(size_t count, float max, std::mt19937_64& rng) {
  std::uniform_real_distribution<float> uniform(0.0f, max);
  std::vector<float> pixels(count);
  for (float& v : pixels) v = uniform(rng);
  return pixels;
}

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

// Σ_texels L y_lm Δμ written directly over the texels (the definition of sh()).
std::vector<double> brute_force_sh(const Environment& env, int order) {
  std::vector<double> out(3 * sh_count(order), 0.0);
  for (int64_t t = 0; t < env.texel_count(); ++t) {
    const std::vector<double> y = sh_basis(order, env.texel_direction(t));
    const glm::dvec3 l = env.texel_radiance(t) * env.texel_solid_angle(t);
    for (int i = 0; i < sh_count(order); ++i)
      for (int c = 0; c < 3; ++c) out[3 * i + c] += y[i] * l[c];
  }
  return out;
}

std::vector<double> band1_vector(const std::vector<double>& c, int channel) {
  // (L_11, L_1−1, L_10) ∝ (x, y, z) of the light's centroid (y_11 = √3 x, y_1−1 = √3 y, y_10 = √3 z).
  return {c[3 * sh_index(1, 1) + channel], c[3 * sh_index(1, -1) + channel], c[3 * sh_index(1, 0) + channel]};
}

glm::dvec3 normalized(const std::vector<double>& v) { return glm::normalize(glm::dvec3(v[0], v[1], v[2])); }

// A per-process scratch directory, removed at exit.
struct ScratchDirectory {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("sd_env_tests_" + std::to_string(::getpid()));
  ScratchDirectory() { std::filesystem::create_directories(path); }
  ~ScratchDirectory() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

std::string temp_path(const std::string& name) {
  static ScratchDirectory scratch;
  return (scratch.path / name).string();
}

template <typename T>
void write_image(const std::string& path, int width, int height, int channels, const std::vector<T>& data,
                 OIIO::TypeDesc type) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(width, height, channels, type);
  spec.attribute("oiio:UnassociatedAlpha", 1);  // store colour as given, not divided by alpha
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(type, data.data())) << out->geterror();
  ASSERT_TRUE(out->close());
}

bool have_blender_hdris() { return std::filesystem::exists(kBlenderWorlds + "sunset.exr"); }

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
    const glm::dvec3 d = normalized(band1_vector(env.sh(1), 0));
    const double tolerance = k.i == 0 ? 1.0 - std::cos(kPi / k.width) + kExact : kExact;
    EXPECT_GT(glm::dot(d, k.expected), 1.0 - tolerance) << "pixel (" << k.i << ", " << k.j << ")";
    EXPECT_FLOAT_EQ(static_cast<float>(env.radiance(k.expected).x), 100.0f);
  }
  // The top row looks at +Z, the bottom row at −Z.
  for (int row : {0, 32}) {
    std::vector<float> rgb(static_cast<size_t>(64) * 33 * 3, 0.0f);
    for (int i = 0; i < 64; ++i) rgb[3 * (static_cast<size_t>(row) * 64 + i)] = 1.0f;
    const Environment env = Environment::from_equirect_pixels(64, 33, rgb);
    const glm::dvec3 d = normalized(band1_vector(env.sh(1), 0));
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
// Projection

TEST(Environment, ProjectionEqualsTexelSum) {
  std::mt19937_64 rng(3);
  const Environment equirect = Environment::from_equirect_pixels(50, 27, random_pixels(50 * 27 * 3, 5.0f, rng));
  const Environment cube = Environment::from_cube_pixels(7, random_pixels(6 * 7 * 7 * 3, 5.0f, rng));
  for (const Environment* env : {&equirect, &cube}) {
    for (int order : {0, 3, 16}) {
      const std::vector<double> fast = env->sh(order), brute = brute_force_sh(*env, order);
      EXPECT_LT(max_abs_difference(fast, brute), kExact * max_abs(brute)) << "order " << order;
    }
  }
  EXPECT_THROW(equirect.sh(-1), std::invalid_argument);
  EXPECT_THROW(equirect.sh(17), std::invalid_argument);
}

TEST(Environment, ProjectionIsIndependentOfThreadCount) {
  std::mt19937_64 rng(4);
  const Environment env = Environment::from_equirect_pixels(257, 130, random_pixels(257 * 130 * 3, 3.0f, rng));
  const std::vector<double> one = env.sh(8, 1);
  EXPECT_EQ(env.sh(8, 2), one);  // bit-identical
  EXPECT_EQ(env.sh(8, 3), one);
  EXPECT_EQ(env.sh(8, 0), one);
  const Environment cube = Environment::from_cube_pixels(20, random_pixels(6 * 20 * 20 * 3, 3.0f, rng));
  EXPECT_EQ(cube.sh(6, 1), cube.sh(6, 2));
  EXPECT_EQ(cube.sh(6, 1), cube.sh(6, 5));
}

// Relative coefficient error of the projection of a sampled band-limited function.
double recovery_error(const BandLimited& f, const std::vector<double>& projected) {
  return max_abs_difference(projected, f.c) / max_abs(f.c);
}

TEST(Environment, RecoversBandLimitedFunctionWithinMidpointError) {
  const BandLimited f = random_band_limited(6, 11);
  const double coarse =
      recovery_error(f, Environment::from_equirect_pixels(128, 64, equirect_pixels(128, 64, f)).sh(6));
  const double fine =
      recovery_error(f, Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, f)).sh(6));
  // Midpoint rule in θ (the φ sums are exact for |m| < W): error ∝ 1/H², so ×16 from 64 to 256 rows.
  EXPECT_LT(fine, 3e-4);
  EXPECT_GT(coarse / fine, 8.0);
  EXPECT_LT(coarse / fine, 32.0);
}

TEST(Environment, CubeAndEquirectOfOneFunctionAgree) {
  const BandLimited f = random_band_limited(5, 12);
  const std::vector<double> equirect = Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, f)).sh(5);
  const Environment cube = Environment::from_cube_pixels(96, cube_pixels(96, f));
  const std::vector<double> cube_sh = cube.sh(5);
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
      Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, turned)).sh(4);
  const std::vector<double> of_map = Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, f)).sh(4);
  EXPECT_LT(max_abs_difference(rotated_sh(of_map, 4, g), of_turned_map) / max_abs(f.c), 5e-4);
  // Not the inverse: D(g) instead of D(gᵀ) is clearly wrong for a generic g.
  EXPECT_GT(max_abs_difference(rotated_sh(of_map, 4, glm::transpose(g)), of_turned_map) / max_abs(f.c), 1e-2);
  EXPECT_THROW(rotated_sh(f.c, 3, g), std::invalid_argument);
  EXPECT_THROW(rotated_sh(f.c, 4, 2.0 * g), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Data checks and loading

TEST(Environment, NegativePixelsAreClampedAndCounted) {
  std::vector<float> rgb(8 * 4 * 3, 1.0f);
  rgb[0] = -0.004f;           // pixel 0
  rgb[3 * 5 + 1] = -2.0f;     // pixel 5
  rgb[3 * 5 + 2] = -1.0f;     // pixel 5 again
  rgb[3 * 9] = -0.0f;         // not negative
  const Environment env = Environment::from_equirect_pixels(8, 4, rgb);
  EXPECT_EQ(env.clamped_negative_pixels(), 2);
  EXPECT_EQ(env.pixels()[0], 0.0f);
  EXPECT_EQ(env.pixels()[3 * 5 + 1], 0.0f);
  EXPECT_EQ(env.pixels()[3 * 5 + 2], 0.0f);
  for (float v : env.pixels()) EXPECT_GE(v, 0.0f);
}

TEST(Environment, BadPixelsThrowClearErrors) {
  std::vector<float> rgb(8 * 4 * 3, 1.0f);
  rgb[3 * (2 * 8 + 5) + 1] = NAN;
  try {
    Environment::from_equirect_pixels(8, 4, rgb);
    FAIL() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("NaN"), std::string::npos) << what;
    EXPECT_NE(what.find("x=5, y=2"), std::string::npos) << what;
  }
  rgb[3 * (2 * 8 + 5) + 1] = INFINITY;
  EXPECT_THROW(Environment::from_equirect_pixels(8, 4, rgb), std::invalid_argument);
  EXPECT_THROW(Environment::from_equirect_pixels(0, 0, {}), std::invalid_argument);
  EXPECT_THROW(Environment::from_equirect_pixels(8, 4, std::vector<float>(10, 1.0f)), std::invalid_argument);
  EXPECT_THROW(Environment::from_cube_pixels(0, {}), std::invalid_argument);
  EXPECT_THROW(Environment::from_cube_pixels(4, std::vector<float>(4 * 4 * 3, 1.0f)), std::invalid_argument);
}

TEST(EnvironmentFiles, MissingEmptyAndGarbageFilesThrowWithPath) {
  const std::string missing = temp_path("does_not_exist.exr");
  for (const std::string& path : {missing, temp_path("empty.exr"), temp_path("garbage.hdr")}) {
    if (path.find("empty") != std::string::npos) std::ofstream(path).close();
    if (path.find("garbage") != std::string::npos) std::ofstream(path) << "this is not an image";
    try {
      Environment::load(path);
      FAIL() << path << " loaded";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  std::array<std::string, 6> faces;
  faces.fill(missing);
  EXPECT_THROW(Environment::load_cube(faces), std::runtime_error);
}

TEST(EnvironmentFiles, FloatFilesRoundTripAndNaNFilesThrow) {
  std::mt19937_64 rng(8);
  std::vector<float> rgb = random_pixels(32 * 16 * 3, 40.0f, rng);
  rgb[7] = -0.5f;
  const std::string exr = temp_path("map.exr");
  write_image(exr, 32, 16, 3, rgb, OIIO::TypeDesc::FLOAT);
  const Environment env = Environment::load(exr);
  EXPECT_EQ(env.width(), 32);
  EXPECT_EQ(env.height(), 16);
  EXPECT_EQ(env.clamped_negative_pixels(), 1);
  for (size_t k = 0; k < rgb.size(); ++k) ASSERT_EQ(env.pixels()[k], std::max(rgb[k], 0.0f));  // linear, top row first
  // Radiance HDR (RGBE: 8-bit mantissas, about 1 % relative; no negatives).
  rgb[7] = 0.5f;
  const std::string hdr = temp_path("map.hdr");
  write_image(hdr, 32, 16, 3, rgb, OIIO::TypeDesc::FLOAT);
  const Environment from_hdr = Environment::load(hdr);
  for (size_t k = 0; k < rgb.size(); ++k) {
    const float expected = rgb[k];
    // RGBE shares one exponent per pixel: error up to 1/256 of the pixel's largest channel.
    const float scale = std::max({rgb[k / 3 * 3], rgb[k / 3 * 3 + 1], rgb[k / 3 * 3 + 2]});
    ASSERT_NEAR(from_hdr.pixels()[k], expected, scale / 128.0f + 1e-6f) << k;
  }
  // NaN in a file: invalid_argument naming the path.
  rgb[3 * (3 * 32 + 4) + 2] = NAN;
  const std::string bad = temp_path("nan.exr");
  write_image(bad, 32, 16, 3, rgb, OIIO::TypeDesc::FLOAT);
  try {
    Environment::load(bad);
    FAIL() << "NaN file loaded";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos) << e.what();
  }
}

TEST(EnvironmentFiles, EightBitImagesAreDecodedFromSrgb) {
  // RGB PNG: 188 -> ((188/255 + 0.055)/1.055)^2.4 ≈ 0.5029; 10 -> 10/255/12.92 (linear toe).
  std::vector<unsigned char> rgb(8 * 4 * 3, 188);
  rgb[0] = 10;
  rgb[1] = 255;
  rgb[2] = 0;
  const std::string png = temp_path("srgb.png");
  write_image(png, 8, 4, 3, rgb, OIIO::TypeDesc::UINT8);
  const Environment env = Environment::load(png);
  const double half = std::pow((188.0 / 255.0 + 0.055) / 1.055, 2.4);
  EXPECT_NEAR(half, 0.5, 0.004);
  EXPECT_NEAR(env.pixels()[5], half, 1e-6);
  EXPECT_NEAR(env.pixels()[0], 10.0 / 255.0 / 12.92, 1e-7);
  EXPECT_NEAR(env.pixels()[1], 1.0, 1e-6);
  EXPECT_EQ(env.pixels()[2], 0.0f);
  // Greyscale with alpha -> RGB, alpha ignored.
  std::vector<unsigned char> grey_alpha(8 * 4 * 2);
  for (size_t p = 0; p < 32; ++p) grey_alpha[2 * p] = 188, grey_alpha[2 * p + 1] = static_cast<unsigned char>(p);
  const std::string grey_png = temp_path("grey.png");
  write_image(grey_png, 8, 4, 2, grey_alpha, OIIO::TypeDesc::UINT8);
  const Environment grey = Environment::load(grey_png);
  for (float v : grey.pixels()) EXPECT_NEAR(v, half, 1e-6);
  // RGBA: alpha ignored.
  std::vector<unsigned char> rgba(8 * 4 * 4, 188);
  for (size_t p = 0; p < 32; ++p) rgba[4 * p + 3] = 0;
  const std::string rgba_png = temp_path("rgba.png");
  write_image(rgba_png, 8, 4, 4, rgba, OIIO::TypeDesc::UINT8);
  const Environment from_rgba = Environment::load(rgba_png);
  for (float v : from_rgba.pixels()) EXPECT_NEAR(v, half, 1e-6);
}

TEST(EnvironmentFiles, CubeMapFromSixFiles) {
  const BandLimited f = random_band_limited(3, 14);
  const int n = 24;
  const std::vector<float> all = cube_pixels(n, f);
  std::array<std::string, 6> paths;
  for (int face = 0; face < 6; ++face) {
    paths[face] = temp_path("face" + std::to_string(face) + ".exr");
    const std::vector<float> one(all.begin() + face * n * n * 3, all.begin() + (face + 1) * n * n * 3);
    write_image(paths[face], n, n, 3, one, OIIO::TypeDesc::FLOAT);
  }
  const Environment cube = Environment::load_cube(paths);
  EXPECT_EQ(cube.layout(), EnvironmentLayout::Cube);
  EXPECT_EQ(cube.width(), n);
  EXPECT_EQ(cube.pixels(), Environment::from_cube_pixels(n, all).pixels());
  EXPECT_LT(recovery_error(f, cube.sh(3)), 2e-3);
  // A face of another size, a non-square face.
  write_image(paths[3], n / 2, n / 2, 3, std::vector<float>(n * n * 3 / 4, 1.0f), OIIO::TypeDesc::FLOAT);
  EXPECT_THROW(Environment::load_cube(paths), std::invalid_argument);
  write_image(paths[3], n, n / 2, 3, std::vector<float>(n * n * 3 / 2, 1.0f), OIIO::TypeDesc::FLOAT);
  EXPECT_THROW(Environment::load_cube(paths), std::invalid_argument);
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

// ---------------------------------------------------------------------------------------------
// Band-limited maps and energies

// A sharp map: a small very bright disc (the sun) on a dim sky.
Radiance sun_map(const glm::dvec3& sun, double radius_degrees) {
  const double cos_radius = std::cos(radius_degrees * kPi / 180.0);
  return [=](const glm::dvec3& d) {
    const double sky = 0.2 + 0.1 * d.z;
    return glm::dot(d, sun) > cos_radius ? glm::dvec3(500.0, 400.0, 300.0) : glm::dvec3(sky, sky, 1.5 * sky);
  };
}

TEST(Environment, BandLimitedMatchesExpansionAndApproachesMap) {
  const glm::dvec3 axis = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
  const Radiance smooth = [&](const glm::dvec3& d) {
    const double v = std::exp(3.0 * glm::dot(d, axis));
    return glm::dvec3(v, 0.5 * v, 2.0);
  };
  const int w = 256, h = 128;
  const Environment env = Environment::from_equirect_pixels(w, h, equirect_pixels(w, h, smooth));
  // Values are the expansion at texel centres (float rounding only).
  const std::vector<float> l8 = env.band_limited(8, 64, 32);
  const std::vector<double> c8 = env.sh(8);
  for (int j = 0; j < 32; j += 3)
    for (int i = 0; i < 64; i += 5) {
      const glm::dvec3 expected = evaluate_sh_rgb(c8, 8, equirect_pixel_direction(i, j, 64, 32));
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(l8[3 * (j * 64 + i) + c], expected[c], 1e-6 * (1.0 + std::abs(expected[c])));
    }
  // Relative L²(dμ) distance to the map: falls with the order, small at 16 (exp(3t) has
  // coefficients ~ 1.5^l / l!).
  auto distance = [&](int order) {
    const std::vector<float> approx = env.band_limited(order, w, h);
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
  env.band_limited(16, 64, 32, RingingWindow::None, &report);
  EXPECT_EQ(report.negative_texels, 0);
  EXPECT_GT(report.min_value[0], 0.0);
  EXPECT_THROW(env.band_limited(65, 8, 4), std::invalid_argument);
  EXPECT_THROW(env.band_limited(4, 0, 4), std::invalid_argument);
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
  env.band_limited(8, 128, 64, RingingWindow::None, &none);
  env.band_limited(8, 128, 64, RingingWindow::Hanning, &hanning);
  env.band_limited(8, 128, 64, RingingWindow::Lanczos, &lanczos);
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
  const std::vector<double> e = env.band_energies(16);
  ASSERT_EQ(e.size(), 17u * 4);
  const std::vector<double> c = env.sh(16);
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
  EXPECT_NEAR(env.low_frequency_error(0, 0),
              std::sqrt(1.0 - env.mass(0) * env.mass(0) / env.norm_squared(0)), kExact);
  // ε(s) by Parseval against a direct texel sum of (L − L̃_s)² Δμ. They differ by the
  // non-orthogonality of the y_lm under the midpoint rule, O((s/H)²) of ‖L̃_s‖²: allow 1e-3.
  for (int s : {2, 4, 8}) {
    const std::vector<double> cs = env.sh(s);
    double num = 0.0;
    for (int64_t t = 0; t < env.texel_count(); ++t) {
      const double diff = env.texel_radiance(t).x - evaluate_sh_rgb(cs, s, env.texel_direction(t)).x;
      num += diff * diff * env.texel_solid_angle(t);
    }
    const double direct = std::sqrt(num / env.norm_squared(0));
    EXPECT_NEAR(env.low_frequency_error(s, 0), direct, 1e-3) << "s = " << s;
  }
  double previous = 2.0;
  for (int s = 0; s <= 64; ++s) {
    const double eps = env.low_frequency_error(s);
    EXPECT_LE(eps, previous);
    previous = eps;
  }
  EXPECT_THROW(env.band_energies(65), std::invalid_argument);
  EXPECT_THROW(env.low_frequency_error(2, 4), std::invalid_argument);
}

TEST(Environment, BandEnergiesAreRotationInvariant) {
  std::mt19937_64 rng(31);
  const glm::dmat3 g = random_rotation(rng);
  const BandLimited f = random_band_limited(6, 15);
  const Radiance turned = [&](const glm::dvec3& x) { return f(g * x); };
  const std::vector<double> a = Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, f)).band_energies(8);
  const std::vector<double> b =
      Environment::from_equirect_pixels(512, 256, equirect_pixels(512, 256, turned)).band_energies(8);
  for (int l = 1; l <= 6; ++l)
    for (int ch = 0; ch < 4; ++ch) EXPECT_NEAR(a[4 * l + ch], b[4 * l + ch], 2e-3 * a[4 * l + ch] + 1e-9 * a[ch]);
}

// ---------------------------------------------------------------------------------------------
// Lobe-filtered error

// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n, independent of the library's rules).
void gauss_legendre(int n, std::vector<double>& t, std::vector<double>& w) {
  t.assign(n, 0.0);
  w.assign(n, 0.0);
  for (int k = 0; k < n; ++k) {
    double x = std::cos(kPi * (k + 0.75) / (n + 0.5));
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = x;
      for (int l = 2; l <= n; ++l) {
        const double p2 = ((2.0 * l - 1.0) * x * p1 - (l - 1.0) * p0) / l;
        p0 = p1, p1 = p2;
      }
      const double dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) {
        w[k] = 2.0 / ((1.0 - x * x) * dp * dp);
        break;
      }
    }
    t[k] = x;
  }
}

// The product rule over axes or normals of the brute-force checks: gauss_legendre's n_t nodes in
// cos θ × n_phi equally spaced φ = 2π (p + 0.5) / n_phi, weights summing to 1 (exact to degree
// 2 n_t − 1 in cos θ).
SphereRule gauss_legendre_product_rule(int n_t, int n_phi) {
  std::vector<double> t, wt;
  gauss_legendre(n_t, t, wt);
  for (double& w : wt) w /= 2.0;
  return test::product_rule(t, wt, n_phi, 0.5);
}

// The relative RMS over axes a of B(a) − B̃_s(a), with B by brute force over the texels and the
// RMS by a product rule over axes (Gauss–Legendre in cos θ × equally spaced φ).
double brute_force_lobe_error(const Environment& env, const ZonalLobe& lobe, int s, int n_t, int n_phi) {
  const SphereRule axes = gauss_legendre_product_rule(n_t, n_phi);
  const std::vector<double> w = lobe.coefficients(s);
  const std::vector<double> c = env.sh(s);
  std::vector<double> ylum(sh_count(s));
  for (int i = 0; i < sh_count(s); ++i) ylum[i] = 0.2126 * c[3 * i] + 0.7152 * c[3 * i + 1] + 0.0722 * c[3 * i + 2];
  std::vector<glm::dvec3> dirs;
  std::vector<double> texel_weight;
  for (int64_t q = 0; q < env.texel_count(); ++q) {
    dirs.push_back(env.texel_direction(q));
    texel_weight.push_back(luminance(env.texel_radiance(q)) * env.texel_solid_angle(q));
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
  // B(a) = Σ_texels L w(a·d) Δμ has the midpoint coefficients of every order, so its RMS
  // truncation error is Σ_{l>s} ŵ_l² E_l exactly; the product rule over axes (degree 2 n_t − 1 in
  // cos θ) integrates (B − B̃)² up to B's tail beyond order ~n_t: a few 1e-3 relative.
  struct Case {
    ZonalLobe lobe;
    int s;
  };
  for (const Case& k : {Case{ZonalLobe::lambert(), 2}, Case{ZonalLobe::lambert(), 4}, Case{ZonalLobe::phong(8.0), 4},
                        Case{ZonalLobe::phong(32.0), 6}}) {
    const double formula = env.lobe_filtered_error(k.lobe, k.s);
    const double brute = brute_force_lobe_error(env, k.lobe, k.s, 48, 96);
    EXPECT_NEAR(formula, brute, 5e-3 * brute) << "sigma " << k.lobe.exponent << " s " << k.s;
  }
}

TEST(Environment, LobeFilteredErrorIsMonotoneAndSmallestOrderFindsIt) {
  const Environment env = Environment::from_equirect_pixels(128, 64, equirect_pixels(128, 64, sun_map({0.0, 0.0, 1.0}, 3.0)));
  for (const ZonalLobe& lobe : {ZonalLobe::lambert(), ZonalLobe::phong(8.0), ZonalLobe::phong(32.0)}) {
    double previous = 1.0 + kExact;
    for (int s = 0; s <= 64; ++s) {
      const double e = env.lobe_filtered_error(lobe, s);
      EXPECT_LE(e, previous) << "s = " << s;
      EXPECT_GE(e, 0.0);
      previous = e;
    }
    EXPECT_EQ(env.lobe_filtered_error(lobe, 64), 0.0);
    for (double target : {0.3, 0.05, 0.01}) {
      const int s = env.smallest_order(lobe, target, 64);
      ASSERT_GE(s, 0);
      EXPECT_LE(env.lobe_filtered_error(lobe, s), target);
      if (s > 0) EXPECT_GT(env.lobe_filtered_error(lobe, s - 1), target);
    }
  }
  // Narrower lobes need more bands.
  EXPECT_LT(env.smallest_order(ZonalLobe::lambert(), 0.02, 64), env.smallest_order(ZonalLobe::phong(32.0), 0.02, 64));
  EXPECT_EQ(env.smallest_order(ZonalLobe::phong(32.0), 1e-9, 4), -1);
  EXPECT_THROW(env.smallest_order(ZonalLobe::lambert(), -1.0, 4), std::invalid_argument);
  // A black map: nothing to miss.
  const Environment black = Environment::from_equirect_pixels(8, 4, std::vector<float>(96, 0.0f));
  EXPECT_EQ(black.lobe_filtered_error(ZonalLobe::lambert(), 2), 0.0);
  EXPECT_EQ(black.low_frequency_error(2), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Designs of a channel

TEST(Environment, ChannelDesignIsCertified) {
  const Environment env = Environment::from_equirect_pixels(256, 128, equirect_pixels(256, 128, sun_map({0.3, -0.4, 0.866}, 10.0)));
  const Environment copy = env.area_averaged(64, 32);
  for (int channel : {0, 2, kLuminance}) {
    const int degree = 6;
    const SphericalDesign design = env.channel_design(channel, degree);
    // Moments of the documented measure: texel centres of the 64 × 32 copy, weights L_c Δμ.
    std::vector<double> target(sh_count(degree), 0.0);
    double mass = 0.0;
    for (int64_t t = 0; t < copy.texel_count(); ++t) {
      const glm::dvec3 l = copy.texel_radiance(t);
      const double v = (channel == kLuminance ? luminance(l) : l[channel]) * copy.texel_solid_angle(t);
      const std::vector<double> y = sh_basis(degree, copy.texel_direction(t));
      for (int i = 0; i < sh_count(degree); ++i) target[i] += v * y[i];
      mass += v;
    }
    SphericalDesign checked = design;
    EXPECT_TRUE(certify_design(checked, target, mass)) << "residual " << checked.residual;
    EXPECT_LE(checked.residual, kDesignTolerance);
    EXPECT_LE(design.size(), sh_count(degree));
    for (double w : design.weights) EXPECT_GT(w, 0.0);
    EXPECT_NEAR(mass, env.mass(channel), 1e-6 * mass);
    // Against the full map's coefficients: the box filter's attenuation only (a few %).
    const std::vector<double> full = env.sh(degree);
    const std::vector<double> moments = design_moments(design.nodes, design.weights, degree);
    for (int i = 0; i < sh_count(degree); ++i) {
      const double f = channel == kLuminance ? 0.2126 * full[3 * i] + 0.7152 * full[3 * i + 1] + 0.0722 * full[3 * i + 2]
                                             : full[3 * i + channel];
      EXPECT_NEAR(moments[i], f, 0.03 * mass) << "index " << i;
    }
  }
  std::vector<float> red(64 * 32 * 3, 0.0f);
  for (size_t p = 0; p < 64 * 32; ++p) red[3 * p] = 1.0f;
  const Environment only_red = Environment::from_equirect_pixels(64, 32, red);
  EXPECT_THROW(only_red.channel_design(1, 4), std::invalid_argument);
  EXPECT_THROW(env.channel_design(4, 4), std::invalid_argument);
  EXPECT_THROW(env.channel_design(0, kMaxDesignDegree + 1), std::invalid_argument);
  // A cube map works too (18² faces).
  const Environment cube = Environment::from_cube_pixels(40, cube_pixels(40, sun_map({0.3, -0.4, 0.866}, 10.0)));
  const SphericalDesign cube_design = cube.channel_design(kLuminance, 4);
  double sum = 0.0;
  for (double w : cube_design.weights) sum += w;
  EXPECT_NEAR(sum, cube.mass(kLuminance), 1e-6 * sum);
}

// ---------------------------------------------------------------------------------------------
// Sampling

TEST(EnvironmentSampler, ProbabilitiesAndDensityIntegrateToOne) {
  const Environment env = Environment::from_equirect_pixels(64, 32, equirect_pixels(64, 32, sun_map({0.6, 0.0, 0.8}, 8.0)));
  const EnvironmentSampler sampler(env);
  double total = 0.0, min_probability = 1.0;
  for (int64_t t = 0; t < env.texel_count(); ++t) {
    total += sampler.texel_probability(t);
    min_probability = std::min(min_probability, sampler.texel_probability(t));
    // p_t = 0.99 Y_t Δμ_t / Σ Y Δμ + 0.01 Δμ_t.
    const double dmu = env.texel_solid_angle(t);
    EXPECT_NEAR(sampler.texel_probability(t),
                0.99 * luminance(env.texel_radiance(t)) * dmu / env.mass(kLuminance) + 0.01 * dmu, 1e-14);
  }
  EXPECT_NEAR(total, 1.0, kExact);
  EXPECT_GT(min_probability, 0.0);
  // ∫ pdf dμ over sub-cells (uniform in φ and cos θ) nested in the texels: pdf is constant on
  // each, so the sum is exact.
  const int sub = 3;
  double integral = 0.0;
  for (int j = 0; j < 32 * sub; ++j) {
    const double z0 = std::cos(kPi * j / (32 * sub)), z1 = std::cos(kPi * (j + 1) / (32 * sub));
    const double z = 0.5 * (z0 + z1), st = std::sqrt(1.0 - z * z);
    for (int i = 0; i < 64 * sub; ++i) {
      const double phi = kPi - 2.0 * kPi * (i + 0.5) / (64 * sub);
      integral += sampler.pdf({st * std::cos(phi), st * std::sin(phi), z}) * (z0 - z1) / (2.0 * 64 * sub);
    }
  }
  EXPECT_NEAR(integral, 1.0, kExact);
}

TEST(EnvironmentSampler, SamplesHaveTheirDensityAndUnbiasedEstimates) {
  const Environment equirect =
      Environment::from_equirect_pixels(64, 32, equirect_pixels(64, 32, sun_map({0.6, 0.0, 0.8}, 8.0)));
  const Environment cube = Environment::from_cube_pixels(12, cube_pixels(12, sun_map({0.6, 0.0, 0.8}, 8.0)));
  for (const Environment* env : {&equirect, &cube}) {
    const EnvironmentSampler sampler(*env);
    std::mt19937_64 rng(77);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const int n = 200000;
    // Estimates of ∫ 1 dμ = 1, ∫ L_r dμ = mass(0) and ∫ z² dμ = 1/3, with their standard errors.
    double sums[3] = {0, 0, 0}, squares[3] = {0, 0, 0};
    for (int k = 0; k < n; ++k) {
      double pdf = 0.0;
      const glm::dvec3 d = sampler.sample(uniform(rng), uniform(rng), &pdf);
      ASSERT_NEAR(glm::length(d), 1.0, kExact);
      ASSERT_NEAR(sampler.pdf(d), pdf, 1e-9 * pdf);
      const double values[3] = {1.0 / pdf, env->radiance(d).x / pdf, d.z * d.z / pdf};
      for (int q = 0; q < 3; ++q) sums[q] += values[q], squares[q] += values[q] * values[q];
    }
    const double expected[3] = {1.0, env->mass(0), 1.0 / 3.0};
    for (int q = 0; q < 3; ++q) {
      const double mean = sums[q] / n, sigma = std::sqrt((squares[q] / n - mean * mean) / n);
      EXPECT_NEAR(mean, expected[q], 5.0 * sigma + 1e-12) << "estimate " << q;
    }
  }
  // Importance: the sun's texels are sampled far more often than their solid angle.
  const EnvironmentSampler sampler(equirect);
  EXPECT_GT(sampler.pdf({0.6, 0.0, 0.8}), 50.0);
  // Cube density integrates to 1 (midpoint over 4×4 sub-cells per texel, exact sub-cell solid angles).
  const EnvironmentSampler cube_sampler(cube);
  double integral = 0.0;
  const int n = 12, sub = 4;
  const glm::dvec3 face_dirs[6][3] = {{{1, 0, 0}, {0, 0, -1}, {0, -1, 0}}, {{-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
                                      {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},  {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},
                                      {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}}, {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}}};
  auto f = [](double a, double b) { return std::atan2(a * b, std::sqrt(a * a + b * b + 1.0)); };
  const double h = 2.0 / (n * sub);
  for (int face = 0; face < 6; ++face)
    for (int p = 0; p < n * sub; ++p)
      for (int q = 0; q < n * sub; ++q) {
        const double a0 = -1.0 + p * h, b0 = -1.0 + q * h;
        const double omega = f(a0 + h, b0 + h) - f(a0, b0 + h) - f(a0 + h, b0) + f(a0, b0);
        const glm::dvec3 d = face_dirs[face][0] + (a0 + h / 2) * face_dirs[face][1] + (b0 + h / 2) * face_dirs[face][2];
        integral += cube_sampler.pdf(d) * omega / (4.0 * kPi);
      }
  EXPECT_NEAR(integral, 1.0, 1e-3);
}

// ---------------------------------------------------------------------------------------------
// Blender's HDRIs (datafiles/studiolights/world/*.exr)

TEST(EnvironmentBlender, UnshadowedLambertAtOrder8AgainstBruteForce) {
  if (!have_blender_hdris()) GTEST_SKIP() << "Blender's studio lights are not installed at " << kBlenderWorlds;
  // B(n) = Σ_texels L 4 max(0, n·d) Δμ over the HDRI's own pixels against B̃_8(n) = Σ_{l<=8} ŵ_l
  // L_lm y_lm(n), for 512 normals of a product rule (16 Gauss nodes in cos θ × 32 azimuths,
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
    const Environment env = Environment::load(kBlenderWorlds + name + ".exr");
    clamped += env.clamped_negative_pixels();
    const int64_t count = env.texel_count();
    std::vector<double> dx(count), dy(count), dz(count), lr(count), lg(count), lb(count);
    for (int64_t q = 0; q < count; ++q) {
      const glm::dvec3 d = env.texel_direction(q), l = env.texel_radiance(q) * env.texel_solid_angle(q);
      dx[q] = d.x, dy[q] = d.y, dz[q] = d.z, lr[q] = l.x, lg[q] = l.y, lb[q] = l.z;
    }
    const std::vector<double> c = env.sh(8);
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
    const double rms = std::sqrt(num / den), formula = env.lobe_filtered_error(ZonalLobe::lambert(), 8);
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
    const double v[4] = {env.lobe_filtered_error(ZonalLobe::lambert(), 4), env.lobe_filtered_error(ZonalLobe::phong(8), 4),
                         env.lobe_filtered_error(ZonalLobe::phong(32), 4), env.low_frequency_error(8)};
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
      const double a = env.lobe_filtered_error(lobe, 4), b = coarse.lobe_filtered_error(lobe, 4);
      EXPECT_NEAR(b, a, 0.03 * a) << name << " sigma " << lobe.exponent;
    }
  }
}

}  // namespace
}  // namespace sd
