// Compact bright sources split off a map (light_sources.h).
#include "sdlighting/light_sources.h"

#include "sdlighting/sh_projection.h"
#include "sdlighting/spherical_harmonics.h"

#include "environment/texel_layout.h"
#include "util/orthonormal_basis.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sd {
namespace {

constexpr double kThresholdStep = 1.4142135623730951;

/// A connected set of texels above a threshold, with what ranks and filters it.
struct Region {
  std::vector<int64_t> texels;
  double power = 0.0;   // ∫ (Y − t) dμ over it
  glm::dvec3 direction{0.0};
  double extent = 0.0;
};

/// The map's connected regions of luminance above t (eight neighbours, across the seam and the poles).
std::vector<Region> regions_above(const Environment& map, const std::vector<double>& luminance, double t) {
  const int width = map.width(), height = map.height();
  std::vector<char> seen(luminance.size(), 0);
  std::vector<Region> regions;
  std::vector<int64_t> stack;
  for (int64_t start = 0; start < static_cast<int64_t>(luminance.size()); ++start) {
    if (seen[start] || luminance[start] <= t) continue;
    Region region;
    seen[start] = 1;
    stack.assign(1, start);
    while (!stack.empty()) {
      const int64_t q = stack.back();
      stack.pop_back();
      region.texels.push_back(q);
      const int j = static_cast<int>(q / width), i = static_cast<int>(q % width);
      const auto visit = [&](int jj, int ii) {
        if (jj < 0 || jj >= height) {   // across the pole: the row itself, half a turn round
          jj = jj < 0 ? 0 : height - 1;
          ii += width / 2;
        }
        ii = ((ii % width) + width) % width;
        const int64_t n = static_cast<int64_t>(jj) * width + ii;
        if (!seen[n] && luminance[n] > t) {
          seen[n] = 1;
          stack.push_back(n);
        }
      };
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di)
          if (dj != 0 || di != 0) visit(j + dj, i + di);
    }
    for (const int64_t q : region.texels) {
      const double w = (luminance[q] - t) * map.texel_solid_angle(q);
      region.power += w;
      region.direction += w * map.texel_direction(q);
    }
    // a region whose directions cancel (a ring round the sphere) has no direction: no source
    const double length = glm::length(region.direction);
    if (!(length > 1e-12 * region.power)) {
      region.extent = kPi;
    } else {
      region.direction /= length;
      for (const int64_t q : region.texels)
        region.extent = std::max(region.extent, std::acos(std::clamp(glm::dot(region.direction, map.texel_direction(q)), -1.0, 1.0)));
    }
    regions.push_back(std::move(region));
  }
  std::sort(regions.begin(), regions.end(), [](const Region& a, const Region& b) { return a.power > b.power; });
  return regions;
}

/// The regions a threshold takes out: the brightest compact ones carrying at least
/// kMinSourceShare of the map's luminance mass, at most max_sources.
std::vector<Region> sources_at(const Environment& map, const std::vector<double>& luminance, double t,
                               int max_sources) {
  std::vector<Region> kept;
  const double least = kMinSourceShare * map.mass(kLuminance);
  for (Region& region : regions_above(map, luminance, t)) {
    if (region.power < least || static_cast<int>(kept.size()) == max_sources) break;
    if (region.extent <= kMaxSourceExtent) kept.push_back(std::move(region));
  }
  return kept;
}

/// The map with the regions' texels clipped to luminance t (their colour kept).
Environment clipped(const Environment& map, const std::vector<double>& luminance, double t, const std::vector<Region>& regions) {
  std::vector<float> rgb = map.pixels();
  for (const Region& region : regions)
    for (const int64_t q : region.texels) {
      const double scale = t / luminance[q];
      for (int c = 0; c < 3; ++c) rgb[3 * q + c] = static_cast<float>(rgb[3 * q + c] * scale);
    }
  return Environment::from_equirect_pixels(map.width(), map.height(), std::move(rgb));
}

/// The luminance's SH coefficients to order s.
std::vector<double> luminance_sh(const Environment& map, int order) {
  const std::vector<double> c = sh(map, order);
  std::vector<double> y(sh_count(order));
  for (int i = 0; i < sh_count(order); ++i) y[i] = luminance(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
  return y;
}

/// ‖P_{>s} R‖ on luminance from ‖R‖² and R's coefficients to order s (Parseval).
double energy_above(double norm_squared, const std::vector<double>& coefficients) {
  double low = 0.0;
  for (const double c : coefficients) low += c * c;
  return std::sqrt(std::max(norm_squared - low, 0.0));
}

/// energy_above of the map clipped to t within `regions`, from the map's own norm and coefficients:
/// the part taken out (luminance Y − t on each of their texels) changes them there only (its y_lm
/// at the texel centres: its texels are far smaller than order s's detail). Candidates of the
/// ladder are measured so; the chosen one's remainder exactly.
double clipped_energy_above(const Environment& map, const std::vector<double>& luminance, double norm_squared,
                            std::vector<double> coefficients, double t, const std::vector<Region>& regions, int order) {
  std::vector<double> basis(coefficients.size());
  for (const Region& region : regions)
    for (const int64_t q : region.texels) {
      const double area = map.texel_solid_angle(q), y = luminance[q];
      norm_squared -= (y * y - t * t) * area;
      sh_basis(order, map.texel_direction(q), basis.data());
      for (size_t i = 0; i < basis.size(); ++i) coefficients[i] -= (y - t) * area * basis[i];
    }
  return energy_above(norm_squared, coefficients);
}

/// A region's description (light_sources.h): its power per channel from the map and the remainder.
LightSource describe(const Environment& map, const Environment& remainder, const Region& region) {
  LightSource s;
  s.direction = region.direction;
  s.extent = region.extent;
  s.texels = static_cast<int64_t>(region.texels.size());
  glm::dvec3 t1, t2;
  orthonormal_basis(s.direction, t1, t2);
  double weight = 0.0, xx = 0.0, xy = 0.0, yy = 0.0;
  for (const int64_t q : region.texels) {
    const double area = map.texel_solid_angle(q);
    const glm::dvec3 excess = map.texel_radiance(q) - remainder.texel_radiance(q);
    s.power += area * excess;
    s.solid_angle += area;
    const double w = area * luminance(excess.x, excess.y, excess.z);
    // the texel's place in the tangent plane (gnomonic), and its own spread: a square of its area
    const glm::dvec3 d = map.texel_direction(q);
    const double x = glm::dot(d, t1) / glm::dot(d, s.direction), y = glm::dot(d, t2) / glm::dot(d, s.direction);
    const double own = 4.0 * kPi * area / 12.0;
    weight += w;
    xx += w * (x * x + own), xy += w * x * y, yy += w * (y * y + own);
  }
  xx /= weight, xy /= weight, yy /= weight;
  // the eigenvalues of [[xx, xy], [xy, yy]] and the major one's axis
  const double mean = 0.5 * (xx + yy), spread = std::sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy);
  const double major = mean + spread, minor = std::max(mean - spread, 0.0);
  const double angle = 0.5 * std::atan2(2.0 * xy, xx - yy);
  s.major_axis = glm::normalize(std::cos(angle) * t1 + std::sin(angle) * t2);
  // a uniform disc of radius ρ has the second moment ρ²/4 about each axis
  s.major_radius = 2.0 * std::sqrt(major);
  s.minor_radius = 2.0 * std::sqrt(minor);
  return s;
}

}  // namespace

SourceSplit extract_light_sources(const Environment& environment, int order, int max_sources) {
  if (environment.layout() != EnvironmentLayout::Equirect)
    throw std::invalid_argument("extract_light_sources: an equirect map is needed (a cube map was given)");
  if (order < 0 || order > 32) throw std::invalid_argument("extract_light_sources: order must be in [0, 32], got " + std::to_string(order));
  if (max_sources < 1 || max_sources > 16)
    throw std::invalid_argument("extract_light_sources: max_sources must be in [1, 16], got " + std::to_string(max_sources));
  const double norm_squared = environment.norm_squared(kLuminance), norm = std::sqrt(norm_squared);
  const std::vector<double> coefficients = luminance_sh(environment, order);
  const double before = norm > 0.0 ? energy_above(norm_squared, coefficients) / norm : 0.0;
  SourceSplit split{{}, environment, 0.0, before, before};
  if (norm == 0.0) return split;

  std::vector<double> luminance(environment.texel_count());
  for (int64_t q = 0; q < environment.texel_count(); ++q) {
    const glm::dvec3 l = environment.texel_radiance(q);
    luminance[q] = sd::luminance(l.x, l.y, l.z);
  }
  // The ladder: from the brightest texel down to the map's mean luminance
  struct Candidate {
    double threshold, error;
    std::vector<Region> regions;
  };
  std::vector<Candidate> ladder;
  const double mean = environment.mass(kLuminance);
  for (double t = *std::max_element(luminance.begin(), luminance.end()) / kThresholdStep; t > mean; t /= kThresholdStep) {
    std::vector<Region> regions = sources_at(environment, luminance, t, max_sources);
    if (regions.empty()) continue;
    const double error =
        clipped_energy_above(environment, luminance, norm_squared, coefficients, t, regions, order) / norm;
    ladder.push_back({t, error, std::move(regions)});
  }
  if (ladder.empty()) return split;
  const double least = std::min_element(ladder.begin(), ladder.end(), [](const Candidate& a, const Candidate& b) {
                         return a.error < b.error;
                       })->error;
  if (least * least >= 0.5 * before * before) return split;
  const Candidate& chosen =
      *std::find_if(ladder.begin(), ladder.end(), [&](const Candidate& c) { return c.error <= kSourceErrorSlack * least; });
  split.remainder = clipped(environment, luminance, chosen.threshold, chosen.regions);
  split.threshold = chosen.threshold;
  split.error_after = energy_above(split.remainder.norm_squared(kLuminance), luminance_sh(split.remainder, order)) / norm;
  for (const Region& region : chosen.regions) split.sources.push_back(describe(environment, split.remainder, region));
  return split;
}

}  // namespace sd
