#include "quadrature/design_fit.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sd {

void tangent_frame(const glm::dvec3& dir, glm::dvec3& e1, glm::dvec3& e2) {
  const glm::dvec3 helper = std::abs(dir.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  e1 = glm::normalize(glm::cross(dir, helper));
  e2 = glm::cross(dir, e1);
}

namespace {

constexpr int kStallWindow = 10;
constexpr double kPolishZone = 1e3;

struct Linearisation {
  Eigen::VectorXd residual;
  Eigen::MatrixXd jacobian;  // columns per node: d/dλ, d/d(tangent 1), d/d(tangent 2)
  std::vector<glm::dvec3> e1, e2;
  Eigen::MatrixXd raw_jacobian;
};

int raw_size(const MomentSystem& system) { return system.transform.size() == 0 ? system.size : system.raw_size; }

// The basis from the raw functions: `raw` itself, or transform × raw.
template <typename Raw, typename Out>
void to_basis(const MomentSystem& system, const Raw& raw, Out& out) {
  if (system.transform.size() == 0) {
    out = raw;
  } else {
    out.noalias() = system.transform * raw;
  }
}

Eigen::VectorXd residual_of(const MomentSystem& system, const std::vector<glm::dvec3>& nodes,
                            const std::vector<double>& weights) {
  Eigen::VectorXd raw = Eigen::VectorXd::Zero(raw_size(system));
  Eigen::VectorXd values(raw.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    system.evaluate(nodes[i], values.data(), nullptr);
    raw += weights[i] * values;
  }
  raw -= system.target;
  Eigen::VectorXd r;
  to_basis(system, raw, r);
  return r;
}

void linearise(const MomentSystem& system, const std::vector<glm::dvec3>& nodes,
               const std::vector<double>& weights, Linearisation& lin) {
  const int k = raw_size(system);
  const int n = static_cast<int>(nodes.size());
  Eigen::VectorXd raw_sum = Eigen::VectorXd::Zero(k);
  lin.raw_jacobian.resize(k, 3 * n);
  lin.e1.resize(n);
  lin.e2.resize(n);
  Eigen::VectorXd values(k);
  Eigen::Matrix<double, 3, Eigen::Dynamic> gradients(3, k);
  for (int i = 0; i < n; ++i) {
    system.evaluate(nodes[i], values.data(), gradients.data());
    tangent_frame(nodes[i], lin.e1[i], lin.e2[i]);
    const Eigen::Vector3d e1(lin.e1[i].x, lin.e1[i].y, lin.e1[i].z);
    const Eigen::Vector3d e2(lin.e2[i].x, lin.e2[i].y, lin.e2[i].z);
    raw_sum += weights[i] * values;
    lin.raw_jacobian.col(3 * i) = values;
    lin.raw_jacobian.col(3 * i + 1) = weights[i] * (gradients.transpose() * e1);
    lin.raw_jacobian.col(3 * i + 2) = weights[i] * (gradients.transpose() * e2);
  }
  to_basis(system, lin.raw_jacobian, lin.jacobian);
  raw_sum -= system.target;
  to_basis(system, raw_sum, lin.residual);
}

}  // namespace

double fit_design(const MomentSystem& system, std::vector<glm::dvec3>& nodes,
                  std::vector<double>& weights, const FitOptions& options) {
  const double tolerance = options.tolerance;
  Linearisation lin;
  linearise(system, nodes, weights, lin);
  double cost = lin.residual.norm();
  double damping = 1e-3;
  double growth = 2.0;  // of μ after a rejected step, doubling while steps keep failing
  double cost_before = cost;  // kStallWindow iterations ago
  for (int iteration = 0; iteration < options.max_iterations && cost > tolerance && !nodes.empty(); ++iteration) {
    if (options.stop && options.stop()) throw DesignCancelled("the design fit was cancelled");
    if (options.stop_when_stalled && iteration > 0 && iteration % kStallWindow == 0) {
      if (cost > 0.5 * cost_before && cost > kPolishZone * tolerance) break;
      cost_before = cost;
    }
    const int n = static_cast<int>(nodes.size());
    // Marquardt's scaling keeps the step meaningful whatever the units of λ and of angles.
    Eigen::MatrixXd normal = lin.jacobian.transpose() * lin.jacobian;
    const Eigen::VectorXd scale = normal.diagonal().cwiseMax(1e-300);
    const Eigen::VectorXd gradient = lin.jacobian.transpose() * lin.residual;
    // Within kPolishZone of the tolerance, rounding starts to dominate E: a stallable fit stops at
    // the first step that fails or does not halve it, rather than growing μ for nothing.
    const bool polishing = options.stop_when_stalled && cost < kPolishZone * tolerance;
    bool accepted = false, converged = false;
    while (!accepted && damping < 1e12) {
      Eigen::MatrixXd damped = normal;
      damped.diagonal() += damping * scale;
      const Eigen::VectorXd step = -damped.ldlt().solve(gradient);
      // The decrease of ½E the linear model predicts: ½ hᵀ(μ D h − g).
      const double predicted = 0.5 * step.dot(damping * scale.cwiseProduct(step) - gradient);
      std::vector<glm::dvec3> trial_nodes(n);
      std::vector<double> trial_weights(n);
      for (int i = 0; i < n; ++i) {
        trial_weights[i] = std::max(weights[i] + step(3 * i), 0.0);  // projection onto λ >= 0
        trial_nodes[i] = glm::normalize(nodes[i] + step(3 * i + 1) * lin.e1[i] + step(3 * i + 2) * lin.e2[i]);
        if (system.project_to_support) trial_nodes[i] = system.project_to_support(trial_nodes[i]);
      }
      const double trial_cost = residual_of(system, trial_nodes, trial_weights).norm();
      if (std::isfinite(trial_cost) && trial_cost < cost) {
        accepted = true;
        nodes.clear();
        weights.clear();
        for (int i = 0; i < n; ++i) {
          if (trial_weights[i] > 0.0 || options.keep_zero_weights) {
            nodes.push_back(trial_nodes[i]);
            weights.push_back(trial_weights[i]);
          }
        }
        // Nielsen's update: shrink μ the more the model predicted the actual decrease.
        const double gain = 0.5 * (cost * cost - trial_cost * trial_cost) / std::max(predicted, 1e-300);
        damping = std::max(damping * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * gain - 1.0, 3)), 1e-15);
        growth = 2.0;
        converged = polishing && trial_cost > 0.5 * cost;
      } else if (polishing) {
        break;
      } else {
        damping *= growth;
        growth *= 2.0;
      }
    }
    if (!accepted) break;  // no descent at any damping: a local minimum with E > 0
    linearise(system, nodes, weights, lin);
    cost = lin.residual.norm();
    if (converged) break;
  }
  return cost;
}

SphericalDesign prune_design(const MomentSystem& system, SphericalDesign design, int target_size,
                             const std::function<bool(SphericalDesign&)>& certify, const FitOptions& options) {
  int step = std::max(1, design.size() - target_size);
  while (step >= 1 && design.size() - step >= std::max(target_size, 1)) {
    std::vector<int> order(design.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return design.weights[a] > design.weights[b]; });
    SphericalDesign candidate;
    candidate.degree = design.degree;
    candidate.method = "gradient";
    for (int j = 0; j < design.size() - step; ++j) {
      candidate.nodes.push_back(design.nodes[order[j]]);
      candidate.weights.push_back(design.weights[order[j]]);
    }
    fit_design(system, candidate.nodes, candidate.weights, options);
    if (certify(candidate)) {
      design = std::move(candidate);
      step = std::min(step, std::max(1, design.size() - target_size));
    } else {
      step /= 2;
    }
  }
  return design;
}

}  // namespace sd
