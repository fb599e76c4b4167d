#include "sdlighting/gauss_quadrature.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <stdexcept>

namespace sd {

Recurrence jacobi_recurrence_unit_interval(double exponent, int n) {
  if (!(exponent >= 0.0)) throw std::invalid_argument("Jacobi exponent must be >= 0");
  const double a = exponent;
  Recurrence r;
  r.alpha.resize(n);
  r.beta.resize(n);
  for (int k = 0; k < n; ++k) {
    // Jacobi(α = a, β = 0) on u ∈ [-1, 1] shifted by s = (1 + u)/2: alpha_s = (1 + alpha_u)/2 and
    // beta_s = beta_u/4, with 1 + alpha_u expanded so that no cancellation occurs for large a.
    const double two_k_a = 2.0 * k + a;
    if (k == 0) {
      r.alpha[k] = 1.0 / (a + 2.0);
      r.beta[k] = 1.0 / (a + 1.0);
    } else {
      r.alpha[k] = (2.0 * k * k + 2.0 * k * a + 2.0 * k + a) / (two_k_a * (two_k_a + 2.0));
      const double kk = k, ka = k + a;
      r.beta[k] = (kk * ka) * (kk * ka) / (two_k_a * two_k_a * (two_k_a + 1.0) * (two_k_a - 1.0));
    }
  }
  return r;
}

Recurrence discrete_recurrence(const std::vector<double>& nodes, const std::vector<double>& weights,
                               int n) {
  const int m = static_cast<int>(nodes.size());
  if (static_cast<int>(weights.size()) != m) throw std::invalid_argument("nodes/weights size mismatch");
  int positive = 0;
  for (double w : weights) positive += w > 0.0;
  if (n > positive) throw std::invalid_argument("discrete measure has too few points for the recurrence");
  // Lanczos on diag(nodes) started from sqrt(weights): the Lanczos vectors are the orthonormal
  // polynomials sampled at the nodes. Full re-orthogonalisation (done twice, "twice is enough")
  // makes it as stable as Gragg–Harrod's rotations at O(m n²) cost, for any number of points.
  const Eigen::Map<const Eigen::VectorXd> x(nodes.data(), m);
  Eigen::MatrixXd basis(m, n);
  Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(weights.data(), m).cwiseMax(0.0).cwiseSqrt();
  Recurrence r;
  r.alpha.resize(n);
  r.beta.resize(n);
  r.beta[0] = q.squaredNorm();
  q /= std::sqrt(r.beta[0]);
  for (int k = 0; k < n; ++k) {
    basis.col(k) = q;
    Eigen::VectorXd v = x.cwiseProduct(q);
    r.alpha[k] = q.dot(v);
    if (k + 1 == n) break;
    for (int pass = 0; pass < 2; ++pass) {
      v -= basis.leftCols(k + 1) * (basis.leftCols(k + 1).transpose() * v);
    }
    r.beta[k + 1] = v.squaredNorm();
    q = v / std::sqrt(r.beta[k + 1]);
  }
  return r;
}

namespace {

Rule1D rule_from_jacobi_matrix(const Eigen::VectorXd& diag, const Eigen::VectorXd& offdiag, double mass) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver;
  solver.computeFromTridiagonal(diag, offdiag, Eigen::ComputeEigenvectors);
  if (solver.info() != Eigen::Success) throw std::runtime_error("Golub–Welsch eigensolver failed");
  const int n = static_cast<int>(diag.size());
  Rule1D rule;
  rule.nodes.resize(n);
  rule.weights.resize(n);
  for (int i = 0; i < n; ++i) {
    rule.nodes[i] = solver.eigenvalues()(i);
    const double v = solver.eigenvectors()(0, i);
    rule.weights[i] = mass * v * v;
  }
  return rule;
}

}  // namespace

Rule1D gauss_rule(const Recurrence& recurrence, int n) {
  if (n < 1 || n > recurrence.size()) throw std::invalid_argument("gauss_rule: not enough recurrence coefficients");
  Eigen::VectorXd diag(n), off(std::max(n - 1, 0));
  for (int k = 0; k < n; ++k) diag(k) = recurrence.alpha[k];
  for (int k = 1; k < n; ++k) off(k - 1) = std::sqrt(recurrence.beta[k]);
  return rule_from_jacobi_matrix(diag, off, recurrence.beta[0]);
}

Rule1D gauss_radau_rule(const Recurrence& recurrence, int n, double fixed_node) {
  if (n < 1 || n > recurrence.size()) throw std::invalid_argument("gauss_radau_rule: not enough recurrence coefficients");
  if (n == 1) return Rule1D{{fixed_node}, {recurrence.beta[0]}};
  // Golub (1973): replace the last diagonal entry so that `fixed_node` becomes an eigenvalue:
  // alpha'_{n-1} = a + beta_{n-1} p_{n-2}(a)/p_{n-1}(a), evaluated with the ratio recurrence
  // r_k = p_k(a)/p_{k-1}(a), which neither overflows nor underflows.
  const double a = fixed_node;
  double ratio = a - recurrence.alpha[0];  // p_1/p_0
  for (int k = 1; k < n - 1; ++k) ratio = (a - recurrence.alpha[k]) - recurrence.beta[k] / ratio;
  Eigen::VectorXd diag(n), off(n - 1);
  for (int k = 0; k < n - 1; ++k) diag(k) = recurrence.alpha[k];
  for (int k = 1; k < n; ++k) off(k - 1) = std::sqrt(recurrence.beta[k]);
  diag(n - 1) = a - recurrence.beta[n - 1] / ratio;
  Rule1D rule = rule_from_jacobi_matrix(diag, off, recurrence.beta[0]);
  // The eigenvalue that stands for the fixed node is exact only to rounding; pin it.
  int closest = 0;
  for (int i = 1; i < n; ++i)
    if (std::abs(rule.nodes[i] - a) < std::abs(rule.nodes[closest] - a)) closest = i;
  rule.nodes[closest] = a;
  return rule;
}

void orthonormal_polynomials(const Recurrence& recurrence, int n, double x, double* values,
                             double* derivatives) {
  // Orthonormal form: sqrt(beta_{k+1}) q_{k+1} = (x - alpha_k) q_k - sqrt(beta_k) q_{k-1}.
  double q_prev = 0.0, q = 1.0 / std::sqrt(recurrence.beta[0]);
  double dq_prev = 0.0, dq = 0.0;
  for (int k = 0; k < n; ++k) {
    values[k] = q;
    if (derivatives) derivatives[k] = dq;
    if (k + 1 == n) break;
    const double b_next = std::sqrt(recurrence.beta[k + 1]);
    const double b_here = k > 0 ? std::sqrt(recurrence.beta[k]) : 0.0;
    const double q_next = ((x - recurrence.alpha[k]) * q - b_here * q_prev) / b_next;
    const double dq_next = (q + (x - recurrence.alpha[k]) * dq - b_here * dq_prev) / b_next;
    q_prev = q;
    q = q_next;
    dq_prev = dq;
    dq = dq_next;
  }
}

}  // namespace sd
