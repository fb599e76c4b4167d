// Importance sampling of an environment map (environment.h) for the Monte Carlo reference
// integrator of eq. (1) (reference.h).
#pragma once

#include "sdlighting/environment.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace sd {

/// Importance sampling of an environment for Monte Carlo reference integrators.
///
/// A texel t is chosen with probability p_t = 0.99 Y_t Δμ_t / Σ Y Δμ + 0.01 Δμ_t (luminance ×
/// solid angle, mixed with 1 % proportional to solid angle so that every texel — and every
/// direction — has a positive density; a black map is sampled ∝ solid angle), then a point
/// uniformly inside the texel: uniform in φ and in cos θ inside an equirect texel (exactly
/// uniform in solid angle), uniform in the face coordinates inside a cube texel. Densities are
/// with respect to dμ = dx/4π, so E[f(x)/pdf(x)] = ∫ f dμ: pdf = p_t / Δμ_t (equirect) and
/// p_t 4π (1 + a² + b²)^{3/2} / (Δa Δb) (cube, face coordinates a, b in [−1, 1]).
/// Holds its own copy of the geometry and the tables (no reference to the Environment).
class EnvironmentSampler {
 public:
  /// Builds the tables: O(texels), 16 bytes per texel.
  explicit EnvironmentSampler(const Environment& environment);

  /// Maps (u1, u2) ∈ [0, 1)² (values outside are clamped) to a unit direction; writes its
  /// density w.r.t. dμ to *pdf if non-null (the same value pdf(direction) returns).
  glm::dvec3 sample(double u1, double u2, double* pdf = nullptr) const;

  /// The density w.r.t. dμ of sample() at direction `dir` (finite, non-zero).
  double pdf(const glm::dvec3& dir) const;

  /// Probability of choosing texel t (they sum to 1).
  double texel_probability(int64_t t) const { return probability_[static_cast<size_t>(t)]; }

 private:
  /// The density w.r.t. dμ at a point of texel t (the class comment): p_t / Δμ_t in an equirect
  /// texel (a, b ignored); p_t 4π (1 + a² + b²)^{3/2} / (Δa Δb) at face coordinates (a, b) in a cube's.
  double density(int64_t t, double a, double b) const;

  EnvironmentLayout layout_;
  int width_;
  int height_;
  int rows_;     // equirect: height; cube: 6 × face size
  int columns_;  // equirect: width; cube: face size
  std::vector<double> probability_;      // per texel
  std::vector<double> row_solid_angle_;  // equirect: Δμ of each row's texels; empty for cubes
  std::vector<double> row_cdf_;      // rows_ + 1 entries, row_cdf_[0] = 0, row_cdf_[rows_] = 1
  std::vector<double> column_cdf_;   // per texel: cumulative probability within its row, ending at 1
};

}  // namespace sd
