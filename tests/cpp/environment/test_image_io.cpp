// Tests of sdlighting/environment.h: pixel checks and image files. Two kinds of tolerance are kept apart: kExact (1e-12,
// results the code computes exactly up to rounding) and the quadrature / Monte Carlo tolerances,
// each derived where it is used.
#include "environment_test_support.h"
#include "sdlighting/environment.h"
#include "sdlighting/sh_projection.h"
#include "sdlighting/spherical_harmonics.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <glm/geometric.hpp>

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

TEST(EnvironmentFiles, DirectoriesFifosAndDevicesAreRefusedWithoutReading) {
  // Before the stat check a FIFO blocked in open() for a writer and /dev/zero was read forever.
  const std::string fifo = temp_path("pipe.exr");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::string directory = temp_path("folder.exr");
  std::filesystem::create_directory(directory);
  const std::pair<std::string, std::string> cases[] = {
      {fifo, "a FIFO"}, {"/dev/zero", "a device file"}, {directory, "a directory"}};
  for (const auto& [path, kind] : cases) {
    try {
      Environment::load(path);
      FAIL() << path << " loaded";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(kind), std::string::npos) << e.what();
    }
  }
}

TEST(EnvironmentFiles, TruncatedFilesThrow) {
  std::mt19937_64 rng(9);
  const std::vector<float> rgb = random_pixels(64 * 32 * 3, 4.0f, rng);
  const std::vector<unsigned char> bytes(64 * 32 * 3, 200);
  // A cut TIFF read "successfully" with its error only recorded, as a black lower half.
  const std::pair<const char*, bool> files[] = {
      {"cut.exr", true}, {"cut.hdr", true}, {"cut.tif", true}, {"cut.png", false}, {"cut.jpg", false}};
  for (const auto& [name, floats] : files) {
    const std::string path = temp_path(name);
    if (floats) {
      write_image(path, 64, 32, 3, rgb, OIIO::TypeDesc::FLOAT);
    } else {
      write_image(path, 64, 32, 3, bytes, OIIO::TypeDesc::UINT8);
    }
    std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
    EXPECT_THROW(Environment::load(path), std::runtime_error) << name;
  }
}

TEST(EnvironmentFiles, SixteenThousandWideEightBitJpegAndPngLoad) {
  constexpr int kWidth = 16384, kHeight = 8;
  const std::vector<unsigned char> rgb(static_cast<size_t>(kWidth) * kHeight * 3, 188);
  const double linear = std::pow((188.0 / 255.0 + 0.055) / 1.055, 2.4);
  for (const char* name : {"wide.jpg", "wide.png"}) {
    const std::string path = temp_path(name);
    write_image(path, kWidth, kHeight, 3, rgb, OIIO::TypeDesc::UINT8);
    const Environment env = Environment::load(path);
    EXPECT_EQ(env.width(), kWidth);
    EXPECT_EQ(env.height(), kHeight);
    // A flat JPEG decodes to within one level of 188: about 1 % in linear light.
    for (float v : env.pixels()) ASSERT_NEAR(v, linear, 0.012 * linear) << name;
    EXPECT_NEAR(sh(env, 4)[0], linear, 0.012 * linear) << name;
  }
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
  EXPECT_LT(recovery_error(f, sh(cube, 3)), 2e-3);
  // A face of another size, a non-square face.
  write_image(paths[3], n / 2, n / 2, 3, std::vector<float>(n * n * 3 / 4, 1.0f), OIIO::TypeDesc::FLOAT);
  EXPECT_THROW(Environment::load_cube(paths), std::invalid_argument);
  write_image(paths[3], n, n / 2, 3, std::vector<float>(n * n * 3 / 2, 1.0f), OIIO::TypeDesc::FLOAT);
  EXPECT_THROW(Environment::load_cube(paths), std::invalid_argument);
}

}  // namespace
}  // namespace sd
