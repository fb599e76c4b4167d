#include "quadrature/clustered_start.h"

#include <glm/geometric.hpp>

#include <algorithm>

namespace sd {
namespace {

// The refit does the real work; a few iterations only even out the clusters' sizes, and the
// seeds already spread the nodes over the support.
constexpr int kLloydIterations = 5;

}  // namespace

int nearest_direction(const glm::dvec3& dir, const std::vector<glm::dvec3>& dirs) {
  int nearest = 0;
  double nearest_cosine = -2.0;
  for (int i = 0; i < static_cast<int>(dirs.size()); ++i) {
    const double cosine = glm::dot(dir, dirs[i]);
    if (cosine > nearest_cosine) {
      nearest_cosine = cosine;
      nearest = i;
    }
  }
  return nearest;
}

SphericalDesign clustered_start(const std::vector<glm::dvec3>& dirs, const std::vector<double>& weights, int count,
                                int degree) {
  const int points = static_cast<int>(dirs.size());
  count = std::clamp(count, 1, std::max(points, 1));
  SphericalDesign design;
  design.degree = degree;
  design.method = "clustered";
  if (points == 0) return design;

  // Farthest-point seeds: each next seed is the direction farthest from all seeds so far.
  std::vector<glm::dvec3> centres;
  std::vector<double> closeness(points, -2.0);  // cosine to the nearest seed so far
  int farthest = 0;
  while (static_cast<int>(centres.size()) < count) {
    centres.push_back(dirs[farthest]);
    farthest = 0;
    for (int i = 0; i < points; ++i) {
      closeness[i] = std::max(closeness[i], glm::dot(dirs[i], centres.back()));
      if (closeness[i] < closeness[farthest]) farthest = i;
    }
  }

  std::vector<glm::dvec3> sums(count);
  std::vector<double> masses(count);
  for (int iteration = 0; iteration < kLloydIterations; ++iteration) {
    std::fill(sums.begin(), sums.end(), glm::dvec3(0.0));
    std::fill(masses.begin(), masses.end(), 0.0);
    for (int i = 0; i < points; ++i) {
      const int c = nearest_direction(dirs[i], centres);
      sums[c] += weights[i] * dirs[i];
      masses[c] += weights[i];
    }
    for (int c = 0; c < count; ++c) {
      if (masses[c] > 0.0 && glm::length(sums[c]) > 0.0) centres[c] = glm::normalize(sums[c]);
    }
  }
  for (int c = 0; c < count; ++c) {
    if (masses[c] > 0.0) {
      design.nodes.push_back(centres[c]);
      design.weights.push_back(masses[c]);
    }
  }
  return design;
}

}  // namespace sd
