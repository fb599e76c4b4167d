// Tests of sdlighting/channel_design.h: the weighted designs of a channel. Two kinds of tolerance are kept apart: kExact (1e-12,
// results the code computes exactly up to rounding) and the quadrature / Monte Carlo tolerances,
// each derived where it is used.
#include "environment_test_support.h"
#include "sdlighting/channel_design.h"
#include "sdlighting/environment.h"
#include "sdlighting/sh_projection.h"
#include "sdlighting/spherical_design.h"
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
// Designs of a channel

TEST(Environment, ChannelDesignIsCertified) {
  const Environment env = Environment::from_equirect_pixels(256, 128, equirect_pixels(256, 128, sun_map({0.3, -0.4, 0.866}, 10.0)));
  const Environment copy = env.area_averaged(64, 32);
  for (int channel : {0, 2, kLuminance}) {
    const int degree = 6;
    const SphericalDesign design = channel_design(env, channel, degree);
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
    const std::vector<double> full = sh(env, degree);
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
  EXPECT_THROW(channel_design(only_red, 1, 4), std::invalid_argument);
  EXPECT_THROW(channel_design(env, 4, 4), std::invalid_argument);
  EXPECT_THROW(channel_design(env, 0, kMaxDesignDegree + 1), std::invalid_argument);
  // A cube map works too (18² faces).
  const Environment cube = Environment::from_cube_pixels(40, cube_pixels(40, sun_map({0.3, -0.4, 0.866}, 10.0)));
  const SphericalDesign cube_design = channel_design(cube, kLuminance, 4);
  double sum = 0.0;
  for (double w : cube_design.weights) sum += w;
  EXPECT_NEAR(sum, cube.mass(kLuminance), 1e-6 * sum);
}

}  // namespace
}  // namespace sd
