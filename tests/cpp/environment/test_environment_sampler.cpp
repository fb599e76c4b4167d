// Tests of sdlighting/environment.h: importance sampling (environment_sampler.h). Two kinds of tolerance are kept apart: kExact (1e-12,
// results the code computes exactly up to rounding) and the quadrature / Monte Carlo tolerances,
// each derived where it is used.
#include "environment_test_support.h"
#include "sdlighting/environment.h"
#include "sdlighting/environment_sampler.h"
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

}  // namespace
}  // namespace sd
