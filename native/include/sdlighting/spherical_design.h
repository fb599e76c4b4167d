// Weighted spherical designs (eq. 11): nodes x_ν ∈ S² and weights λ_ν > 0 with
// ∫ f w dμ = Σ λ_ν f(x_ν) for every polynomial f of degree <= k.
#pragma once

#include "sdlighting/limits.h"

#include <glm/vec3.hpp>

#include <stdexcept>
#include <string>
#include <vector>

namespace sd {

/// Thrown by a design builder whose `stop` callback returned true: nothing is returned.
class DesignCancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A design is certified when its moment residual is at most this fraction of the mass.
constexpr double kDesignTolerance = 1e-10;

/// A weighted spherical design with the evidence that it is one.
struct SphericalDesign {
  std::vector<glm::dvec3> nodes;
  std::vector<double> weights;  // all strictly positive; they sum to the weight's mass
  int degree = 0;
  /// ‖Σ_ν λ_ν y(x_ν) − ∫ y w dμ‖₂ / mass over all real SH y_lm with l <= degree.
  double residual = 0.0;
  /// How it was built: "gauss", "gauss-radau", "gradient", "tchakaloff", "refit" (from a
  /// nearby measure's design, weighted_design.h) or "clustered" (refitted from clusters of the
  /// measure's samples, quadrature/clustered_start.h).
  std::string method;
  int size() const { return static_cast<int>(nodes.size()); }
};

/// Lower bound (⌊k/2⌋+1)² on the size of any positive rule of degree k for a weight with
/// interior support (msd-notes, "Facts worth knowing").
constexpr int design_lower_bound(int degree) { return (degree / 2 + 1) * (degree / 2 + 1); }

/// Σ_ν λ_ν y_lm(x_ν) for all l <= degree (flat SH index).
std::vector<double> design_moments(const std::vector<glm::dvec3>& nodes,
                                   const std::vector<double>& weights, int degree);

/// ‖design_moments − target_moments‖₂ / mass.
double design_residual(const std::vector<glm::dvec3>& nodes, const std::vector<double>& weights,
                       int degree, const std::vector<double>& target_moments, double mass);

/// Sets design.residual against the weight's moments and tells whether the design is certified:
/// non-empty, every weight > 0, residual <= kDesignTolerance.
bool certify_design(SphericalDesign& design, const std::vector<double>& target_moments, double mass);

}  // namespace sd
