// Weighted designs of an environment's channel (channel_design.h): the measure L_c dμ of an
// area-averaged copy, handed to weighted_design.
#include "sdlighting/channel_design.h"

#include "environment/environment_detail.h"
#include "sdlighting/limits.h"
#include "sdlighting/weighted_design.h"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace sd {
namespace {

// channel_design's area-averaged copy.
constexpr int kDesignEquirectWidth = 64;
constexpr int kDesignEquirectHeight = 32;
constexpr int kDesignCubeFace = 18;

}  // namespace

SphericalDesign channel_design(const Environment& environment, int channel, int degree) {
  check_channel("Environment::channel_design", channel);
  check_order("Environment::channel_design: degree", degree, kMaxDesignDegree);
  if (!(environment.mass(channel) > 0.0)) {
    throw std::invalid_argument("Environment::channel_design: channel " + std::to_string(channel) +
                                " is black everywhere: its measure L dμ is empty");
  }
  const int width = environment.width(), height = environment.height();
  const Environment* source = &environment;
  std::optional<Environment> reduced;
  if (environment.layout() == EnvironmentLayout::Equirect &&
      (width > kDesignEquirectWidth || height > kDesignEquirectHeight)) {
    reduced = environment.area_averaged(std::min(width, kDesignEquirectWidth), std::min(height, kDesignEquirectHeight));
    source = &*reduced;
  } else if (environment.layout() == EnvironmentLayout::Cube && width > kDesignCubeFace) {
    reduced = environment.area_averaged(kDesignCubeFace, kDesignCubeFace);
    source = &*reduced;
  }
  std::vector<glm::dvec3> dirs;
  std::vector<double> weights;
  for (int64_t t = 0; t < source->texel_count(); ++t) {
    const glm::dvec3 l = source->texel_radiance(t);
    const double value = channel == kLuminance ? luminance(l.x, l.y, l.z) : l[channel];
    if (!(value > 0.0)) continue;
    dirs.push_back(source->texel_direction(t));
    weights.push_back(value * source->texel_solid_angle(t));
  }
  return weighted_design(dirs, weights, degree);
}

}  // namespace sd
