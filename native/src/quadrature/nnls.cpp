#include "quadrature/nnls.h"

#include "sdlighting/spherical_design.h"

#include <limits>
#include <vector>

namespace sd {
namespace {

Eigen::VectorXd solve_passive(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                              const std::vector<int>& passive) {
  Eigen::MatrixXd sub(a.rows(), passive.size());
  for (size_t j = 0; j < passive.size(); ++j) sub.col(j) = a.col(passive[j]);
  return sub.colPivHouseholderQr().solve(b);
}

}  // namespace

Eigen::VectorXd nnls(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, int max_iterations,
                     const std::function<bool()>& stop) {
  const int n = static_cast<int>(a.cols());
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  std::vector<bool> in_passive(n, false);
  std::vector<int> passive;
  const double tolerance = 10.0 * std::numeric_limits<double>::epsilon() * a.norm() * std::max<int>(n, a.rows());
  for (int outer = 0; outer < max_iterations; ++outer) {
    if (stop && stop()) throw DesignCancelled("the design's NNLS was cancelled");
    const Eigen::VectorXd gradient = a.transpose() * (b - a * u);
    int entering = -1;
    double best = tolerance;
    for (int j = 0; j < n; ++j) {
      if (!in_passive[j] && gradient(j) > best) {
        best = gradient(j);
        entering = j;
      }
    }
    if (entering < 0) break;  // Kuhn–Tucker conditions hold
    in_passive[entering] = true;
    passive.push_back(entering);
    for (int inner = 0; inner < 3 * n; ++inner) {
      const Eigen::VectorXd z = solve_passive(a, b, passive);
      bool feasible = true;
      for (Eigen::Index j = 0; j < z.size(); ++j) feasible = feasible && z(j) > 0.0;
      if (feasible) {
        for (size_t j = 0; j < passive.size(); ++j) u(passive[j]) = z(j);
        break;
      }
      // Step from u towards z as far as feasibility allows, then drop the variables that hit 0.
      double alpha = 1.0;
      size_t limiting = 0;
      for (size_t j = 0; j < passive.size(); ++j) {
        if (z(j) <= 0.0) {
          const double uj = u(passive[j]);
          const double candidate = uj / (uj - z(j));
          if (candidate < alpha) {
            alpha = candidate;
            limiting = j;
          }
        }
      }
      std::vector<int> kept;
      for (size_t j = 0; j < passive.size(); ++j) {
        const int index = passive[j];
        u(index) += alpha * (z(j) - u(index));
        if (j == limiting || u(index) <= 0.0) {
          u(index) = 0.0;
          in_passive[index] = false;
        } else {
          kept.push_back(index);
        }
      }
      passive.swap(kept);
      if (passive.empty()) break;
    }
  }
  return u;
}

}  // namespace sd
