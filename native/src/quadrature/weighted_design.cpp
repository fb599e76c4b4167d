#include "sdlighting/weighted_design.h"

#include "quadrature/design_fit.h"
#include "quadrature/nnls.h"
#include "sdlighting/spherical_harmonics.h"
#include "util/number_string.h"

#include <glm/geometric.hpp>

#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sd {
namespace {

// Rank threshold of the weighted Vandermonde's QR, relative to its largest diagonal entry.
constexpr double kRankThreshold = 1e-11;
// Weights below this fraction of the largest are left out (validate).
constexpr double kNegligibleWeight = 1e-20;

struct CleanMeasure {
  std::vector<glm::dvec3> dirs;
  std::vector<double> weights;  // divided by `scale`
  double mass = 0.0;            // of the divided weights
  double scale = 1.0;           // the largest weight
};

CleanMeasure validate(const std::vector<glm::dvec3>& dirs, const std::vector<double>& weights, int degree) {
  check_order("design degree", degree, kMaxDesignDegree);
  if (dirs.size() != weights.size()) throw std::invalid_argument("dirs and weights differ in length");
  check_allocation("a weighted design of degree " + std::to_string(degree) + " from " + std::to_string(dirs.size()) +
                       " directions",
                   weighted_design_bytes(dirs.size(), degree));
  CleanMeasure measure;
  for (size_t i = 0; i < dirs.size(); ++i) {
    const glm::dvec3& d = dirs[i];
    if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z)) throw std::invalid_argument("dirs contain NaN or infinity");
    if (!std::isfinite(weights[i])) throw std::invalid_argument("weights contain NaN or infinity");
    if (weights[i] < 0.0) throw std::invalid_argument("weights must be non-negative");
    const double length = glm::length(d);
    if (!(length > 0.0)) throw std::invalid_argument("dirs contain a zero vector");
    if (weights[i] == 0.0) continue;
    measure.dirs.push_back(d / length);
    measure.weights.push_back(weights[i]);
  }
  if (measure.weights.empty()) throw std::invalid_argument("weights sum to zero: the measure is empty");
  // Weights near 1e300 overflow the moments' squares and denormal ones vanish under the fit's
  // tolerances: the fit sees the weights divided by the largest, weighted_design scales back.
  // Weights below kNegligibleWeight of the largest are left out: kMaxCallBytes admits at most
  // ~1e8 / (k+1)² points, so together they move no moment by more than 1e8 × kNegligibleWeight ×
  // √(2k+1) / (k+1)² < 1e-11 of the mass (below kDesignTolerance), but they would make the weighted
  // Vandermonde's QR keep columns known only to 1e-30.
  measure.scale = *std::max_element(measure.weights.begin(), measure.weights.end());
  size_t kept = 0;
  for (size_t i = 0; i < measure.weights.size(); ++i) {
    const double w = measure.weights[i] / measure.scale;
    if (w < kNegligibleWeight) continue;
    measure.dirs[kept] = measure.dirs[i];
    measure.weights[kept++] = w;
    measure.mass += w;
  }
  measure.dirs.resize(kept);
  measure.weights.resize(kept);
  if (!std::isfinite(measure.mass * measure.scale)) {
    throw std::invalid_argument("weights sum beyond the double range (largest " + number_string(measure.scale) + ")");
  }
  return measure;
}

// φ(x) = R11⁻ᵀ y_P(x): the SH columns the pivoted QR kept, made orthonormal for the measure.
struct OrthonormalBasis {
  int degree = 0;
  std::vector<int> columns;  // SH indices kept, in pivot order
  Eigen::MatrixXd inverse_r;  // R11⁻¹, upper triangular

  MomentSystem system(const Eigen::VectorXd& target) const {
    MomentSystem s;
    s.size = static_cast<int>(columns.size());
    s.target = target;
    s.evaluate = [this](const glm::dvec3& d, double* values, double* gradients) {
      const int k = sh_count(degree);
      thread_local std::vector<double> y, dy;
      y.resize(k);
      dy.resize(3 * k);
      if (gradients) {
        sh_basis_with_gradient(degree, d, y.data(), dy.data());
      } else {
        sh_basis(degree, d, y.data());
      }
      const int r = static_cast<int>(columns.size());
      Eigen::VectorXd kept(r);
      Eigen::Matrix<double, 3, Eigen::Dynamic> kept_gradient(3, r);
      for (int j = 0; j < r; ++j) {
        kept(j) = y[columns[j]];
        if (gradients) kept_gradient.col(j) = Eigen::Map<const Eigen::Vector3d>(&dy[3 * columns[j]]);
      }
      Eigen::Map<Eigen::VectorXd>(values, r) = inverse_r.transpose() * kept;
      if (gradients) Eigen::Map<Eigen::MatrixXd>(gradients, 3, r) = kept_gradient * inverse_r;
    };
    return s;
  }
};

}  // namespace

SphericalDesign weighted_design(const std::vector<glm::dvec3>& dirs, const std::vector<double>& weights,
                                int degree) {
  const CleanMeasure measure = validate(dirs, weights, degree);
  const int points = static_cast<int>(measure.dirs.size());
  const int k = sh_count(degree);

  std::vector<double> moments(k, 0.0), y(k);
  Eigen::MatrixXd vandermonde(points, k);
  for (int i = 0; i < points; ++i) {
    sh_basis(degree, measure.dirs[i], y.data());
    for (int j = 0; j < k; ++j) {
      vandermonde(i, j) = y[j];
      moments[j] += measure.weights[i] * y[j];
    }
  }
  const Eigen::Map<const Eigen::VectorXd> w(measure.weights.data(), points);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  qr.setThreshold(kRankThreshold);
  qr.compute(w.cwiseSqrt().asDiagonal() * vandermonde);
  const int rank = static_cast<int>(qr.rank());

  OrthonormalBasis basis;
  basis.degree = degree;
  for (int j = 0; j < rank; ++j) basis.columns.push_back(qr.colsPermutation().indices()(j));
  basis.inverse_r = qr.matrixR().topLeftCorner(rank, rank).triangularView<Eigen::Upper>().solve(
      Eigen::MatrixXd::Identity(rank, rank));
  Eigen::MatrixXd kept(points, rank);
  for (int j = 0; j < rank; ++j) kept.col(j) = vandermonde.col(basis.columns[j]);
  const Eigen::MatrixXd phi = kept * basis.inverse_r;  // φ at the samples, orthonormal for the measure
  const Eigen::VectorXd target = phi.transpose() * w;

  auto certified = [&](SphericalDesign& design) { return certify_design(design, moments, measure.mass); };

  // Carathéodory–Tchakaloff: a basic NNLS solution keeps at most `rank` samples.
  const Eigen::VectorXd u = nnls(phi.transpose(), target, 4 * rank + 10);
  SphericalDesign best;
  best.degree = degree;
  best.method = "tchakaloff";
  for (int i = 0; i < points; ++i) {
    if (u(i) > 0.0) {
      best.nodes.push_back(measure.dirs[i]);
      best.weights.push_back(u(i));
    }
  }
  if (!certified(best)) {
    throw std::runtime_error("Tchakaloff compression of degree " + std::to_string(degree) +
                             " failed certification: residual " + number_string(best.residual));
  }

  const int generic = std::max(1, (rank + 2) / 3);
  SphericalDesign design = prune_design(basis.system(target), std::move(best), generic, certified,
                                       FitOptions{1e-15 * std::sqrt(measure.mass), 100, true});
  for (double& w : design.weights) w *= measure.scale;
  return design;
}

}  // namespace sd
