#include "quadrature/design_fit.h"

#include "util/orthonormal_basis.h"

#include <glm/geometric.hpp>

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sd {

namespace {

constexpr int kStallWindow = 10;
constexpr double kPolishZone = 1e3;
// Nielsen's update shrinks μ by at most 3× per accepted step. After a rejected step has raised μ
// by 10² or more, the refits' steps are predicted well (actual decrease ≈ predicted) for many
// iterations, and at 3× per step they crawl: at degree 9 (bumpy sphere, 1024 rays) 10× per step
// took 22.6 → 20.5 ms per vertex and 43.01 → 41.30 nodes, as more fits certified (30× and 100×
// did no better within the noise).
constexpr double kLargestDampingDecrease = 10.0;
// With FitOptions::backtrack, a rejected step is halved up to this many times before μ rises: a
// halved step costs one evaluation of E, a new μ a factorisation as well. At degree 9 (bumpy
// sphere, 1024 rays) the fits took 84k factorisations instead of 116k, in 57.8k steps, not 60.2k.
constexpr int kBacktracks = 2;
// Once √E is within this factor of the tolerance (1e-4 √mass for the per-vertex designs), a
// stallable fit ends at a step that fails at its μ (and at its backtracks), rather than raising μ
// until a step descends. At degree 9, 1,730 fits had spent ~20 trials each raising μ to 10¹² and
// ended there all the same, at √E of 1e-13..1e-5 √mass, most at 1e-12..1e-9 (the rounding of E):
// 75.8k → 53.7k factorisations. A factorisation that fails is no such evidence: μ rises.
constexpr double kConvergingZone = 1e10;

// The buffers of one fit, sized once per node count rather than once per step or trial.
struct Linearisation {
  Eigen::VectorXd residual, residual_trial;
  // Columns per node: d/dλ, d/d(tangent 1), d/d(tangent 2); DampedSystem scales them in place.
  Eigen::MatrixXd jacobian;
  std::vector<glm::dvec3> e1, e2;
  Eigen::MatrixXd raw_jacobian;
  Eigen::VectorXd raw_sum, values;
  Eigen::Matrix<double, 3, Eigen::Dynamic> gradients;
};

int raw_size(const MomentSystem& system) { return system.transform.identity() ? system.size : system.raw_size; }

// The basis from the raw functions: `raw` itself, or transform × raw.
template <typename Raw, typename Out>
void to_basis(const MomentSystem& system, const Raw& raw, Out& out) {
  if (system.transform.identity()) {
    out = raw;
  } else {
    system.transform.apply(raw, out);
  }
}

double cost_of(const MomentSystem& system, const std::vector<glm::dvec3>& nodes, const std::vector<double>& weights,
               Linearisation& lin) {
  lin.raw_sum.setZero(raw_size(system));
  lin.values.resize(lin.raw_sum.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    system.evaluate(nodes[i], lin.values.data(), nullptr);
    lin.raw_sum += weights[i] * lin.values;
  }
  lin.raw_sum -= system.target;
  to_basis(system, lin.raw_sum, lin.residual_trial);
  return lin.residual_trial.norm();
}

void linearise(const MomentSystem& system, const std::vector<glm::dvec3>& nodes,
               const std::vector<double>& weights, Linearisation& lin) {
  const int k = raw_size(system);
  const int n = static_cast<int>(nodes.size());
  lin.raw_sum.setZero(k);
  lin.raw_jacobian.resize(k, 3 * n);
  lin.e1.resize(n);
  lin.e2.resize(n);
  lin.values.resize(k);
  lin.gradients.resize(3, k);
  for (int i = 0; i < n; ++i) {
    system.evaluate(nodes[i], lin.values.data(), lin.gradients.data());
    orthonormal_basis(nodes[i], lin.e1[i], lin.e2[i]);
    const Eigen::Vector3d e1(lin.e1[i].x, lin.e1[i].y, lin.e1[i].z);
    const Eigen::Vector3d e2(lin.e2[i].x, lin.e2[i].y, lin.e2[i].z);
    lin.raw_sum += weights[i] * lin.values;
    lin.raw_jacobian.col(3 * i) = lin.values;
    lin.raw_jacobian.col(3 * i + 1).noalias() = weights[i] * (lin.gradients.transpose() * e1);
    lin.raw_jacobian.col(3 * i + 2).noalias() = weights[i] * (lin.gradients.transpose() * e2);
  }
  to_basis(system, lin.raw_jacobian, lin.jacobian);
  lin.raw_sum -= system.target;
  to_basis(system, lin.raw_sum, lin.residual);
}

// One Levenberg–Marquardt system with Marquardt's scaling, (JᵀJ + μ diag(JᵀJ)) h = −Jᵀr, in the
// columns-normalised form J_s = J D^{-1/2}: h = D^{-1/2} z, (J_sᵀJ_s + μI) z = −J_sᵀr. Where J has
// more columns than rows (a design above the generic count, as when pruning a Tchakaloff rule of
// ~k nodes: 3k unknowns) it is solved through the k × k system, z = −J_sᵀ (J_s J_sᵀ + μI)⁻¹ r.
// Either matrix is positive definite for μ > 0, so a Cholesky factorisation does (cheaper than a
// pivoted LDLT), and it is formed once per step for all the dampings tried. A node at weight 0
// whose weight the gradient pushes below 0 is held there (its λ column left out: an active bound
// of the projection, whose clipped step the model would otherwise mispredict at every step).
// One per fit, set up again at every step: its buffers keep their allocation across steps.
class DampedSystem {
 public:
  /// The system at `lin`'s nodes; scales lin.jacobian's columns in place into J_s, which it keeps
  /// using until the next linearise.
  void set_up(Linearisation& lin, const std::vector<double>& weights) {
    residual_ = &lin.residual;
    scaled_ = &lin.jacobian;
    Eigen::MatrixXd& scaled = lin.jacobian;
    inverse_root_ = scaled.colwise().squaredNorm().transpose().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    scaled *= inverse_root_.asDiagonal();
    for (std::size_t i = 0; i < weights.size(); ++i) {
      if (weights[i] <= 0.0 && scaled.col(3 * i).dot(lin.residual) > 0.0) scaled.col(3 * i).setZero();
    }
    scaled_gradient_.noalias() = scaled.transpose() * lin.residual;
    wide_ = scaled.cols() > scaled.rows();
    const Eigen::Index size = wide_ ? scaled.rows() : scaled.cols();
    gram_.setZero(size, size);
    if (wide_) {
      gram_.selfadjointView<Eigen::Lower>().rankUpdate(scaled);
    } else {
      gram_.selfadjointView<Eigen::Lower>().rankUpdate(scaled.transpose());
    }
  }

  /// The step h at damping μ and the decrease of ½E the linear model predicts for it,
  /// ½ hᵀ(μ D h − g) = ½ zᵀ(μ z − J_sᵀr); false where the factorisation fails to rounding.
  bool solve(double damping, Eigen::VectorXd& step, double& predicted) {
    damped_ = gram_;
    damped_.diagonal().array() += damping;
    // Eigen's LLT factorises in panels of 8 columns at these sizes (k = 100 at degree 9), 1.4×
    // slower than its unblocked kernel, which it uses below 32.
    if (Eigen::internal::llt_inplace<double, Eigen::Lower>::unblocked(damped_) >= 0) return false;
    const auto factor = damped_.triangularView<Eigen::Lower>();
    solution_ = wide_ ? *residual_ : scaled_gradient_;
    factor.solveInPlace(solution_);
    factor.adjoint().solveInPlace(solution_);
    if (wide_) {
      step.noalias() = -(scaled_->transpose() * solution_);
    } else {
      step = -solution_;
    }
    predicted = 0.5 * step.dot(damping * step - scaled_gradient_);
    step.array() *= inverse_root_.array();
    return true;
  }

 private:
  const Eigen::VectorXd* residual_ = nullptr;
  const Eigen::MatrixXd* scaled_ = nullptr;  // J_s
  Eigen::VectorXd inverse_root_, scaled_gradient_, solution_;
  Eigen::MatrixXd gram_, damped_;
  bool wide_ = false;
};

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
  Eigen::VectorXd step;
  DampedSystem system_at_nodes;
  std::vector<glm::dvec3> trial_nodes;
  std::vector<double> trial_weights;
  for (int iteration = 0; iteration < options.max_iterations && cost > tolerance && !nodes.empty(); ++iteration) {
    if (options.stop && options.stop()) throw DesignCancelled("the design fit was cancelled");
    if (options.stop_when_stalled && iteration > 0 && iteration % kStallWindow == 0) {
      if (cost > 0.5 * cost_before && cost > kPolishZone * tolerance) break;
      cost_before = cost;
    }
    const int n = static_cast<int>(nodes.size());
    system_at_nodes.set_up(lin, weights);
    // Within kPolishZone of the tolerance, rounding starts to dominate E: a stallable fit stops at
    // the first step that fails or does not halve it, rather than growing μ for nothing.
    const bool polishing = options.stop_when_stalled && cost < kPolishZone * tolerance;
    const bool converging = options.stop_when_stalled && cost < kConvergingZone * tolerance;
    bool accepted = false, converged = false;
    trial_nodes.resize(n);
    trial_weights.resize(n);
    int backtracks = 0;  // of the step solved at this μ
    while (!accepted && damping < 1e12) {
      double predicted = 0.0;
      double trial_cost = cost;
      bool solved = true;
      if (backtracks > 0) {
        step *= 0.5;
      } else {
        solved = system_at_nodes.solve(damping, step, predicted);
      }
      if (solved) {
        for (int i = 0; i < n; ++i) {
          trial_weights[i] = std::max(weights[i] + step(3 * i), 0.0);  // projection onto λ >= 0
          trial_nodes[i] = glm::normalize(nodes[i] + step(3 * i + 1) * lin.e1[i] + step(3 * i + 2) * lin.e2[i]);
          if (system.project_to_support) trial_nodes[i] = system.project_to_support(trial_nodes[i]);
        }
        trial_cost = cost_of(system, trial_nodes, trial_weights, lin);
      }
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
        if (backtracks > 0) {
          damping *= std::pow(2.0, backtracks);  // the step was too long for this μ
        } else {
          // Nielsen's update: shrink μ the more the model predicted the actual decrease.
          const double gain = 0.5 * (cost * cost - trial_cost * trial_cost) / std::max(predicted, 1e-300);
          damping = std::max(
              damping * std::max(1.0 / kLargestDampingDecrease, 1.0 - std::pow(2.0 * gain - 1.0, 3)), 1e-15);
        }
        growth = 2.0;
        converged = polishing && trial_cost > 0.5 * cost;
      } else if (polishing) {
        break;
      } else if (solved && options.backtrack && backtracks < kBacktracks) {
        ++backtracks;
      } else if (solved && converging) {
        break;
      } else {
        damping *= growth;
        growth *= 2.0;
        backtracks = 0;
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
                             const std::function<bool(SphericalDesign&)>& certify, const FitOptions& options,
                             const PruneOptions& pruning) {
  int step = std::max(1, design.size() - target_size);
  Eigen::VectorXd values(raw_size(system)), in_basis;
  std::vector<double> size;  // what orders the nodes to keep: w, or w‖F(x)‖
  while (step >= 1 && design.size() - step >= std::max(target_size, 1)) {
    size = design.weights;
    if (pruning.smallest_moments_first) {
      for (int j = 0; j < design.size(); ++j) {
        system.evaluate(design.nodes[j], values.data(), nullptr);
        to_basis(system, values, in_basis);
        size[j] *= in_basis.norm();
      }
    }
    std::vector<int> order(design.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return size[a] > size[b]; });
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
