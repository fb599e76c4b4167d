// Environment maps: construction (from files or pixels), their texels' radiance, masses and norms.
// The layouts are in texel_layout.cpp, the SH side in projection.cpp. Conventions and equations:
// environment.h and msd-notes.
#include "sdlighting/environment.h"

#include "environment/environment_detail.h"
#include "environment/image_io.h"

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sd {

void check_channel(const char* what, int channel) {
  if (channel < 0 || channel > kLuminance) {
    throw std::invalid_argument(std::string(what) + ": channel must be 0, 1, 2 (R, G, B) or 3 (luminance), got " +
                                std::to_string(channel));
  }
}

Environment Environment::from_texels(EnvironmentLayout layout, int width, int height, std::vector<float> rgb,
                                     const std::string& origin) {
  const int64_t texels = layout == EnvironmentLayout::Equirect ? static_cast<int64_t>(width) * height
                                                                : int64_t(6) * width * width;
  check_image_size(width, height, texels, origin);
  if (layout == EnvironmentLayout::Cube && width != height) {
    throw std::invalid_argument(origin + ": cube faces must be square, got " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  if (rgb.size() != static_cast<size_t>(texels) * 3) {
    throw std::invalid_argument(origin + ": expected " + std::to_string(texels * 3) + " floats (" +
                                (layout == EnvironmentLayout::Cube ? "6 x " : "") + std::to_string(width) + " x " +
                                std::to_string(height) + " x 3), got " + std::to_string(rgb.size()));
  }
  check_finite_pixels(rgb, width, height, origin);

  Environment env;
  env.layout_ = layout;
  env.width_ = width;
  env.height_ = height;
  env.rgb_ = std::move(rgb);
  for (int64_t t = 0; t < texels; ++t) {
    float* px = env.rgb_.data() + 3 * t;
    bool negative = false;
    for (int c = 0; c < 3; ++c) {
      if (px[c] < 0.0f) {
        px[c] = 0.0f;
        negative = true;
      }
    }
    env.clamped_negative_pixels_ += negative ? 1 : 0;
  }
  // Masses and norms (sequential: deterministic).
  for (int64_t t = 0; t < texels; ++t) {
    const double dmu = env.texel_solid_angle(t);
    const float* px = env.rgb_.data() + 3 * t;
    const double v[4] = {px[0], px[1], px[2], luminance(px[0], px[1], px[2])};
    for (int c = 0; c < 4; ++c) {
      env.mass_[c] += v[c] * dmu;
      env.norm_squared_[c] += v[c] * v[c] * dmu;
    }
  }
  env.reference_ = std::make_shared<ReferenceProjection>();
  return env;
}

Environment Environment::from_equirect_pixels(int width, int height, std::vector<float> rgb) {
  return from_texels(EnvironmentLayout::Equirect, width, height, std::move(rgb), "equirect pixels");
}

Environment Environment::from_cube_pixels(int face_size, std::vector<float> rgb) {
  return from_texels(EnvironmentLayout::Cube, face_size, face_size, std::move(rgb), "cube pixels");
}

glm::dvec3 Environment::texel_radiance(int64_t t) const {
  const float* px = rgb_.data() + 3 * t;
  return {px[0], px[1], px[2]};
}

double Environment::mass(int channel) const {
  check_channel("mass", channel);
  return mass_[channel];
}

double Environment::norm_squared(int channel) const {
  check_channel("norm_squared", channel);
  return norm_squared_[channel];
}

}  // namespace sd
