// The texel layouts of environment maps (environment.h states them): where a texel looks, its
// exact solid angle and which texel holds a direction, for equirect and cube maps. Private to the
// environment files.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>

namespace sd {

constexpr double kPi = 3.14159265358979323846;

// cos a − cos b = 2 sin((a+b)/2) sin((b−a)/2), without the cancellation near the poles.
inline double cos_difference(double a, double b) { return 2.0 * std::sin(0.5 * (a + b)) * std::sin(0.5 * (b - a)); }

// ---- equirect geometry (environment.h: θ = π (j+0.5)/H, φ = π − 2π (i+0.5)/W) ----

// θ of the centres of row j (from the top).
inline double equirect_theta(int j, int height) { return kPi * (j + 0.5) / height; }

// π (W − 2i − 1)/W: an integer numerator, so the centre column of an odd width is exactly φ = 0.
inline double equirect_phi(int i, int width) { return kPi * static_cast<double>(width - 2 * i - 1) / width; }

// Δμ of every texel of row j: (2π/W)(cos θ_top − cos θ_bottom)/(4π).
inline double equirect_row_solid_angle(int j, int width, int height) {
  return cos_difference(kPi * j / height, kPi * (j + 1.0) / height) / (2.0 * width);
}

// The unit vector of polar angle θ (from +Z) and azimuth φ (from +X towards +Y).
inline glm::dvec3 spherical_direction(double theta, double phi) {
  const double st = std::sin(theta);
  return {st * std::cos(phi), st * std::sin(phi), std::cos(theta)};
}

// Throws std::invalid_argument for a zero or non-finite direction (lookups take any length).
inline void check_direction(const glm::dvec3& d) {
  if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z)) {
    throw std::invalid_argument("direction contains NaN or infinity");
  }
  if (d.x == 0.0 && d.y == 0.0 && d.z == 0.0) throw std::invalid_argument("direction is the zero vector");
}

// (row, column) of the equirect texel holding d (any length > 0).
inline std::pair<int, int> equirect_cell(const glm::dvec3& d, int width, int height) {
  const double phi = std::atan2(d.y, d.x);
  const double u = 0.5 - phi / (2.0 * kPi);  // in [0, 1]
  int i = static_cast<int>(std::floor(u * width));
  if (i >= width) i -= width;
  i = std::clamp(i, 0, width - 1);
  const double theta = std::atan2(std::hypot(d.x, d.y), d.z);  // in [0, π]
  const int j = std::clamp(static_cast<int>(std::floor(theta / kPi * height)), 0, height - 1);
  return {j, i};
}

// ---- cube geometry (environment.h: the OpenGL face table on Blender's axes) ----

// The (unnormalised) direction of face coordinates (a, b) = (sc, tc) in [−1, 1]² on face f.
inline glm::dvec3 cube_face_direction(int face, double a, double b) {
  switch (face) {
    case 0: return {1.0, -b, -a};
    case 1: return {-1.0, -b, a};
    case 2: return {a, 1.0, b};
    case 3: return {a, -1.0, -b};
    case 4: return {a, -b, 1.0};
    default: return {-a, -b, -1.0};
  }
}

struct FaceCoordinates {
  int face;
  double a, b;  // sc/|ma|, tc/|ma| in [−1, 1]
};

// The face whose major axis d points along, and d's face coordinates on it.
inline FaceCoordinates cube_face_coordinates(const glm::dvec3& d) {
  const double ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
  if (ax >= ay && ax >= az) {
    return d.x > 0.0 ? FaceCoordinates{0, -d.z / ax, -d.y / ax} : FaceCoordinates{1, d.z / ax, -d.y / ax};
  }
  if (ay >= az) {
    return d.y > 0.0 ? FaceCoordinates{2, d.x / ay, d.z / ay} : FaceCoordinates{3, d.x / ay, -d.z / ay};
  }
  return d.z > 0.0 ? FaceCoordinates{4, d.x / az, -d.y / az} : FaceCoordinates{5, -d.x / az, -d.y / az};
}

// Face coordinate of grid line k of an n-texel face: 2k/n − 1.
inline double cube_edge(int k, int n) { return 2.0 * k / n - 1.0; }

// Solid angle (steradians) of the face-coordinate rectangle [a0, a1] × [b0, b1]:
// ∫∫ da db / (1 + a² + b²)^{3/2} = F(a1,b1) − F(a0,b1) − F(a1,b0) + F(a0,b0), F = atan2(a b, √(a²+b²+1)).
inline double cube_rectangle_solid_angle(double a0, double a1, double b0, double b1) {
  auto f = [](double a, double b) { return std::atan2(a * b, std::sqrt(a * a + b * b + 1.0)); };
  return f(a1, b1) - f(a0, b1) - f(a1, b0) + f(a0, b0);
}

// Δμ of texel (i, j) of an n × n face (the same on every face).
inline double cube_texel_solid_angle(int i, int j, int n) {
  return cube_rectangle_solid_angle(cube_edge(i, n), cube_edge(i + 1, n), cube_edge(j, n), cube_edge(j + 1, n)) /
         (4.0 * kPi);
}

// The unit centre direction of texel (i, j) of face f.
inline glm::dvec3 cube_texel_direction(int face, int i, int j, int n) {
  return glm::normalize(cube_face_direction(face, (2.0 * i + 1.0) / n - 1.0, (2.0 * j + 1.0) / n - 1.0));
}

// Texel index t = (f n + j) n + i of the cube texel holding d.
inline int64_t cube_index(const glm::dvec3& d, int n) {
  const FaceCoordinates c = cube_face_coordinates(d);
  const int i = std::clamp(static_cast<int>(std::floor((c.a + 1.0) * 0.5 * n)), 0, n - 1);
  const int j = std::clamp(static_cast<int>(std::floor((c.b + 1.0) * 0.5 * n)), 0, n - 1);
  return (static_cast<int64_t>(c.face) * n + j) * n + i;
}
}  // namespace sd
