// Helpers shared by the C++ tests (header-only, namespace sd::test): random directions and
// rotations, equirect pixel centres, and product quadrature rules on the unit sphere, written out
// by hand so that tests can use them as references.
#pragma once

#include "sdlighting/gauss_quadrature.h"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace sd::test {

// A direction uniform on the unit sphere: a normalised Gaussian vector drawn with the caller's
// distribution. For tests that draw other Gaussian numbers from the same `normal` and rng, so that
// sharing the distribution keeps their random stream.
inline glm::dvec3 random_direction(std::mt19937_64& rng, std::normal_distribution<double>& normal) {
  return glm::normalize(glm::dvec3(normal(rng), normal(rng), normal(rng)));
}

// A direction uniform on the unit sphere, from a fresh Gaussian distribution on each call.
inline glm::dvec3 random_direction(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  return random_direction(rng, normal);
}

// `count` directions uniform on the unit sphere, all drawn with one Gaussian distribution.
inline std::vector<glm::dvec3> random_directions(int count, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::vector<glm::dvec3> dirs(count);
  for (auto& d : dirs) d = random_direction(rng, normal);
  return dirs;
}

// A rotation uniform on SO(3): a normalised Gaussian quaternion, turned into a matrix by hand so
// that tests do not rely on glm's quaternion conventions.
inline glm::dmat3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  double w = normal(rng), x = normal(rng), y = normal(rng), z = normal(rng);
  const double norm = std::sqrt(w * w + x * x + y * y + z * z);
  w /= norm, x /= norm, y /= norm, z /= norm;
  const double m[3][3] = {  // m[row][col]
      {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
      {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
      {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  glm::dmat3 r;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) r[col][row] = m[row][col];
  return r;
}

// Pixel centre of row j (from the top), column i of a width × height equirect map:
// θ = π (j+0.5)/height, φ = π − 2π (i+0.5)/width (the layout of sdlighting/environment.h).
inline glm::dvec3 equirect_pixel_direction(int i, int j, int width, int height) {
  const double theta = M_PI * (j + 0.5) / height, phi = M_PI - 2.0 * M_PI * (i + 0.5) / width;
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// A quadrature rule on the unit sphere for the normalised measure dμ = dω/4π (weights sum to 1).
struct SphereRule {
  std::vector<glm::dvec3> dirs;
  std::vector<double> weights;
};

// Product rule: a rule in z = cos θ (nodes in [−1, 1], weights summing to 1) times `azimuths`
// equally spaced φ = 2π (j + phi_offset) / azimuths. Points run over the z nodes, then over φ.
inline SphereRule product_rule(const std::vector<double>& z, const std::vector<double>& z_weights, int azimuths,
                               double phi_offset) {
  SphereRule rule;
  for (size_t i = 0; i < z.size(); ++i) {
    const double r = std::sqrt(std::max(0.0, 1.0 - z[i] * z[i]));
    for (int j = 0; j < azimuths; ++j) {
      const double phi = 2.0 * M_PI * (j + phi_offset) / azimuths;
      rule.dirs.push_back({r * std::cos(phi), r * std::sin(phi), z[i]});
      rule.weights.push_back(z_weights[i] / azimuths);
    }
  }
  return rule;
}

// Product rule exact for polynomials of the given degree: Gauss–Legendre in z (degree/2 + 1 nodes,
// from the library's gauss_rule) × degree + 1 equally spaced azimuths starting at phi_offset.
inline SphereRule product_rule(int degree, double phi_offset) {
  const int n = degree / 2 + 1;
  const Rule1D legendre_rule = gauss_rule(jacobi_recurrence_unit_interval(0.0, n), n);
  std::vector<double> z(n);
  for (int i = 0; i < n; ++i) z[i] = 1.0 - 2.0 * legendre_rule.nodes[i];
  return product_rule(z, legendre_rule.weights, degree + 1, phi_offset);
}

}  // namespace sd::test
