#include "sdlighting/reference.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdtesting/meshes.h"
#include "sdtesting/sphere.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <random>
#include <vector>

namespace sd {
namespace {

// Monte Carlo checks: an estimate within this many of its standard errors.
constexpr double kSigmas = 4.0;

// An equirect map of a smooth positive band-limited function (order 2), and its coefficients.
Environment smooth_sky(std::vector<double>& coefficients) {
  coefficients.assign(3 * sh_count(2), 0.0);
  coefficients[0] = 2.0, coefficients[1] = 1.5, coefficients[2] = 1.0;              // y_00
  coefficients[3 * sh_index(1, 0)] = 0.8;                                          // y_10: a bright zenith
  coefficients[3 * sh_index(1, 1) + 1] = 0.4;                                      // y_11
  coefficients[3 * sh_index(2, 0) + 2] = 0.3;                                      // y_20
  const int width = 512, height = 256;
  std::vector<float> pixels;
  std::vector<double> y(sh_count(2));
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      sh_basis(2, test::equirect_pixel_direction(i, j, width, height), y.data());
      for (int c = 0; c < 3; ++c) {
        double value = 0.0;
        for (int k = 0; k < sh_count(2); ++k) value += coefficients[3 * k + c] * y[k];
        pixels.push_back(static_cast<float>(value));
      }
    }
  }
  return Environment::from_equirect_pixels(width, height, pixels);
}

TEST(Reference, ConstantSkyGivesItsRadianceForEveryLobe) {
  const Environment sky = Environment::from_equirect_pixels(8, 4, std::vector<float>(8 * 4 * 3, 0.75f));
  const std::vector<glm::dvec3> vertices = {{0, 0, 0}, {1, 2, 3}};
  const std::vector<glm::dvec3> normals = {{0, 0, 1}, glm::normalize(glm::dvec3(1, -1, 0.5))};
  const std::vector<glm::dvec3> views = {glm::normalize(glm::dvec3(0.3, 0, 1)), {0, 1, 0}};
  for (const Material material : {Material::lambert(), Material::phong(50.0)}) {
    ReferenceOptions options;
    options.samples = 2000;
    const ReferenceResult r = shade_reference(sky, glm::dmat3(1.0), vertices, normals, views, {}, material, options);
    for (size_t i = 0; i < r.radiance.size(); ++i) {
      EXPECT_NEAR(r.radiance[i], 0.75, kSigmas * r.standard_error[i] + 1e-12);
      EXPECT_LT(r.standard_error[i], 0.02);
    }
  }
}

TEST(Reference, UnoccludedSmoothSkyMatchesFunkHecke) {
  std::vector<double> coefficients;
  const Environment sky = smooth_sky(coefficients);
  const glm::dmat3 g = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, 1));  // 90° about z
  const std::vector<glm::dvec3> normals = {{0, 0, 1}, {1, 0, 0}, glm::normalize(glm::dvec3(0, -1, -1))};
  const std::vector<glm::dvec3> vertices(normals.size(), glm::dvec3(0.0));
  ReferenceOptions options;
  options.samples = 20000;
  const ReferenceResult r = shade_reference(sky, g, vertices, normals, {}, {}, Material::lambert(), options);
  // Σ ŵ_l L_lm(g) y_lm(n): exact for a band-limited sky, up to the map's pixelisation; the reference
  // turns directions, rotated_sh turns coefficients, and both must mean the same L(g x).
  const std::vector<double> rotated = rotated_sh(coefficients, 2, g);
  const auto w = ZonalLobe::lambert().coefficients(2);
  std::vector<double> y(sh_count(2));
  for (size_t p = 0; p < normals.size(); ++p) {
    sh_basis(2, normals[p], y.data());
    for (int c = 0; c < 3; ++c) {
      double expected = 0.0;
      for (int l = 0; l <= 2; ++l)
        for (int m = -l; m <= l; ++m) expected += w[l] * rotated[3 * sh_index(l, m) + c] * y[sh_index(l, m)];
      EXPECT_NEAR(r.radiance[3 * p + c], expected, kSigmas * r.standard_error[3 * p + c] + 2e-3 * expected)
          << "vertex " << p << " channel " << c;
    }
  }
}

TEST(Reference, AClosedBoxIsDark) {
  const Environment sky = Environment::from_equirect_pixels(8, 4, std::vector<float>(8 * 4 * 3, 1.0f));
  ReferenceOptions options;
  options.samples = 500;
  const ReferenceResult r = shade_reference(sky, glm::dmat3(1.0), {{0.1, 0.2, 0.0}}, {{0, 0, 1}}, {}, {},
                                            Material::lambert(), options, test::box(1.0));
  for (double v : r.radiance) EXPECT_EQ(v, 0.0);
}

TEST(Reference, RejectsBadInput) {
  const Environment sky = Environment::from_equirect_pixels(8, 4, std::vector<float>(8 * 4 * 3, 1.0f));
  ReferenceOptions options;
  options.samples = 0;
  EXPECT_THROW(shade_reference(sky, glm::dmat3(1.0), {{0, 0, 0}}, {{0, 0, 1}}, {}, {}, Material::lambert(), options),
               std::invalid_argument);
  options.samples = 10;
  EXPECT_THROW(shade_reference(sky, glm::dmat3(1.0), {{0, 0, 0}}, {{0, 0, 1}, {0, 0, 1}}, {}, {}, Material::lambert(),
                               options),
               std::invalid_argument);
  // A zero normal gets the bake's fallback (+Z for a vertex without faces), as in bake_transfer.
  EXPECT_NO_THROW(shade_reference(sky, glm::dmat3(1.0), {{0, 0, 0}}, {{0, 0, 0}}, {}, {}, Material::lambert(), options));
  EXPECT_THROW(shade_reference(sky, glm::dmat3(1.0), {{0, 0, 0}}, {{0, 0, 1}}, {}, {}, Material::phong(8.0), options),
               std::invalid_argument);
}

TEST(Reference, RefusesZeroViewsAndMatricesThatAreNoRotation) {
  // Found by tests/fuzz/fuzz_reference: these gave NaN (a zero or NaN view) or silently wrong
  // radiance (a matrix that is no rotation) instead of an error.
  const Environment sky = Environment::from_equirect_pixels(8, 4, std::vector<float>(8 * 4 * 3, 1.0f));
  ReferenceOptions options;
  options.samples = 16;
  const Material phong = Material::phong(20.0);
  for (const glm::dvec3& view : {glm::dvec3(0.0), glm::dvec3(std::nan(""), 0.0, 1.0)}) {
    EXPECT_THROW(shade_reference(sky, glm::dmat3(1.0), {{0, 0, 0}}, {{0, 0, 1}}, {view}, {}, phong, options),
                 std::invalid_argument);
  }
  glm::dmat3 sheared(1.0), mirror(1.0), singular(0.72);
  sheared[1][0] = 0.3;
  mirror[2][2] = -1.0;
  for (const glm::dmat3& matrix : {sheared, mirror, singular, 2.0 * glm::dmat3(1.0)}) {
    EXPECT_THROW(shade_reference(sky, matrix, {{0, 0, 0}}, {{0, 0, 1}}, {{0, 0, 1}}, {}, phong, options),
                 std::invalid_argument);
  }
  // A float32 rotation is a rotation; an unnormalised view is normalised.
  std::mt19937_64 rng(3);
  glm::dmat3 float32 = test::random_rotation(rng);
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) float32[col][row] = static_cast<float>(float32[col][row]);
  const ReferenceResult r = shade_reference(sky, float32, {{0, 0, 0}}, {{0, 0, 1}}, {{0, 0, 5}}, {}, phong, options);
  for (double v : r.radiance) EXPECT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace sd
