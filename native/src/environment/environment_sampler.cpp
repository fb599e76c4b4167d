// Importance sampling of an environment for the reference integrator (environment_sampler.h).
#include "sdlighting/environment_sampler.h"

#include "environment/texel_layout.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace sd {
namespace {

// Uniform share of the texel distribution: every direction keeps a positive density.
constexpr double kUniformShare = 0.01;

}  // namespace

EnvironmentSampler::EnvironmentSampler(const Environment& environment)
    : layout_(environment.layout()), width_(environment.width()), height_(environment.height()) {
  const bool equirect = layout_ == EnvironmentLayout::Equirect;
  rows_ = equirect ? height_ : 6 * width_;
  columns_ = width_;
  const int64_t texels = environment.texel_count();
  if (equirect) {
    row_solid_angle_.resize(height_);
    for (int j = 0; j < height_; ++j) row_solid_angle_[j] = equirect_row_solid_angle(j, width_, height_);
  }
  const double total_luminance = environment.mass(kLuminance);
  const double uniform = total_luminance > 0.0 ? kUniformShare : 1.0;
  probability_.resize(static_cast<size_t>(texels));
  double sum = 0.0;
  for (int64_t t = 0; t < texels; ++t) {
    const double dmu = equirect ? row_solid_angle_[t / width_] : environment.texel_solid_angle(t);
    const glm::dvec3 l = environment.texel_radiance(t);
    double p = uniform * dmu;
    if (uniform < 1.0) p += (1.0 - uniform) * luminance(l.x, l.y, l.z) * dmu / total_luminance;
    probability_[t] = p;
    sum += p;
  }
  for (double& p : probability_) p /= sum;  // Σ = 1 up to rounding
  row_cdf_.assign(rows_ + 1, 0.0);
  column_cdf_.resize(static_cast<size_t>(texels));
  for (int r = 0; r < rows_; ++r) {
    const size_t base = static_cast<size_t>(r) * columns_;
    double row = 0.0;
    for (int c = 0; c < columns_; ++c) {
      row += probability_[base + c];
      column_cdf_[base + c] = row;
    }
    for (int c = 0; c < columns_; ++c) column_cdf_[base + c] /= row;
    column_cdf_[base + columns_ - 1] = 1.0;
    row_cdf_[r + 1] = row_cdf_[r] + row;
  }
  const double total = row_cdf_[rows_];
  for (double& c : row_cdf_) c /= total;
  row_cdf_[rows_] = 1.0;
}

glm::dvec3 EnvironmentSampler::sample(double u1, double u2, double* pdf) const {
  constexpr double kBelowOne = 1.0 - std::numeric_limits<double>::epsilon() / 2;
  u1 = std::isfinite(u1) ? std::clamp(u1, 0.0, kBelowOne) : 0.0;
  u2 = std::isfinite(u2) ? std::clamp(u2, 0.0, kBelowOne) : 0.0;
  // Row by u1, column by u2; what is left of each (rescaled to [0, 1)) places the point inside.
  int r = static_cast<int>(std::upper_bound(row_cdf_.begin(), row_cdf_.end(), u1) - row_cdf_.begin()) - 1;
  r = std::clamp(r, 0, rows_ - 1);
  const double v1 = std::clamp((u1 - row_cdf_[r]) / (row_cdf_[r + 1] - row_cdf_[r]), 0.0, 1.0);
  const auto row_begin = column_cdf_.begin() + static_cast<size_t>(r) * columns_;
  int c = static_cast<int>(std::upper_bound(row_begin, row_begin + columns_, u2) - row_begin);
  c = std::clamp(c, 0, columns_ - 1);
  const double below = c > 0 ? row_begin[c - 1] : 0.0;
  const double v2 = std::clamp((u2 - below) / (row_begin[c] - below), 0.0, 1.0);
  const int64_t t = static_cast<int64_t>(r) * columns_ + c;

  glm::dvec3 dir;
  if (layout_ == EnvironmentLayout::Equirect) {
    // Uniform in cos θ and in φ inside the texel: uniform in solid angle.
    const double z_top = std::cos(kPi * r / height_), z_bottom = std::cos(kPi * (r + 1.0) / height_);
    const double z = std::clamp(z_top + v1 * (z_bottom - z_top), -1.0, 1.0);
    const double phi = kPi - 2.0 * kPi * (c + v2) / width_;
    const double s = std::sqrt(std::max(0.0, (1.0 - z) * (1.0 + z)));
    dir = glm::dvec3(s * std::cos(phi), s * std::sin(phi), z);
    if (pdf != nullptr) *pdf = density(t, 0.0, 0.0);
  } else {
    const int n = width_, face = r / n, j = r % n;
    const double a = cube_edge(c, n) + v2 * (2.0 / n), b = cube_edge(j, n) + v1 * (2.0 / n);
    dir = glm::normalize(cube_face_direction(face, a, b));
    if (pdf != nullptr) *pdf = density(t, a, b);
  }
  return dir;
}

double EnvironmentSampler::pdf(const glm::dvec3& dir) const {
  check_direction(dir);
  if (layout_ == EnvironmentLayout::Equirect) {
    const auto [j, i] = equirect_cell(dir, width_, height_);
    return density(static_cast<int64_t>(j) * width_ + i, 0.0, 0.0);
  }
  const FaceCoordinates f = cube_face_coordinates(dir);
  return density(cube_index(dir, width_), f.a, f.b);
}

double EnvironmentSampler::density(int64_t t, double a, double b) const {
  if (layout_ == EnvironmentLayout::Equirect) return probability_[static_cast<size_t>(t)] / row_solid_angle_[t / columns_];
  const double q = 1.0 + a * a + b * b;
  const double side = 2.0 / width_;
  return probability_[static_cast<size_t>(t)] * 4.0 * kPi * q * std::sqrt(q) / (side * side);
}

}  // namespace sd
