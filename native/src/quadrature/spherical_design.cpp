#include "sdlighting/spherical_design.h"

#include "sdlighting/spherical_harmonics.h"

#include <algorithm>
#include <cmath>

namespace sd {

std::vector<double> design_moments(const std::vector<glm::dvec3>& nodes,
                                   const std::vector<double>& weights, int degree) {
  const int k = sh_count(degree);
  std::vector<double> moments(k, 0.0), y(k);
  for (size_t i = 0; i < nodes.size(); ++i) {
    sh_basis(degree, nodes[i], y.data());
    for (int j = 0; j < k; ++j) moments[j] += weights[i] * y[j];
  }
  return moments;
}

double design_residual(const std::vector<glm::dvec3>& nodes, const std::vector<double>& weights,
                       int degree, const std::vector<double>& target_moments, double mass) {
  const std::vector<double> moments = design_moments(nodes, weights, degree);
  double sum = 0.0;
  for (size_t j = 0; j < moments.size(); ++j) {
    const double d = moments[j] - target_moments[j];
    sum += d * d;
  }
  return std::sqrt(sum) / mass;
}

bool certify_design(SphericalDesign& design, const std::vector<double>& target_moments, double mass) {
  design.residual = design_residual(design.nodes, design.weights, design.degree, target_moments, mass);
  return design.size() > 0 && design.residual <= kDesignTolerance &&
         std::all_of(design.weights.begin(), design.weights.end(), [](double w) { return w > 0.0; });
}

}  // namespace sd
