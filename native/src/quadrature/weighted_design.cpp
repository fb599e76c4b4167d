#include "sdlighting/weighted_design.h"

#include "quadrature/clustered_start.h"
#include "quadrature/design_fit.h"
#include "quadrature/nnls.h"
#include "sdlighting/spherical_harmonics.h"
#include "util/number_string.h"

#include <glm/geometric.hpp>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <numeric>
#include <stdexcept>

namespace sd {
namespace {

// Rank threshold of the weighted Vandermonde's QR, relative to its largest diagonal entry.
constexpr double kRankThreshold = 1e-11;
// A warm start needs the Gram matrix's LDLT to be trustworthy: its smallest pivot at least this
// fraction of the largest (condition 1e12 of the Gram matrix, 1e6 of the basis it gives). Below
// it the measure is (nearly) rank deficient and the QR of the cold builder decides the rank.
constexpr double kGramPivotFloor = 1e-12;
// Levenberg–Marquardt steps per refit: from a neighbour's design a fit that will certify does so
// in a few dozen; one that has not is cheaper to redo from scratch.
constexpr int kWarmIterations = 40;
// A start's node where this measure's Christoffel function, normalised to average 1 over the
// measure, exceeds this sits where the measure has (almost) no mass; it moves to the nearest
// sample direction before the refit.
constexpr double kOutsideSupport = 3.0;
// A refit with up to this many nodes more than it aimed at is kept without trying the clustered
// start: at degree 9 (bumpy sphere, 1024 rays) it and the compression ran for 54 such refits at
// ~38 ms each and saved 42 nodes in all.
constexpr int kSpareNodes = 2;
// A measure with up to this many points per moment is only compressed (weighted_design).
constexpr double kFewPoints = 1.1;
// A neighbour's design is turned towards this vertex's sky only where both have a mean direction
// (Σ w x / Σ w) at least this long (turned_to).
constexpr double kClearMean = 0.1;
// Without a neighbour to tell how many nodes to aim for, a clustered start has this many times
// the generic count: about the designs' count at degree 9 (43 of 34), and the refit prunes
// towards the generic count from there.
constexpr double kClusteredNodesPerGeneric = 1.3;
// When a refit stalls, up to kExchangeRounds times kExchangeNodes sample directions join it. A
// third round spares the compression (the costliest builder, with the largest designs) where the
// sky is thin: at degree 6 (bumpy sphere, 1024 rays) a vertex of 64 points for 49 moments got 23
// nodes instead of 36 from it, and over 512–2048 rays and degrees 5–9 no mean rose by more than
// 0.03 node, while the LM steps per vertex at degree 9 rose by 1 %.
constexpr int kExchangeRounds = 3;
constexpr int kExchangeNodes = 3;
// The moment residual at which a fit stops, relative to √mass (the norm of the target in a basis
// orthonormal for the measure): four orders below kDesignTolerance, and near the rounding of the
// sums, where design_fit's polishing stops a fit that no longer gains.
constexpr double kFitRelativeTolerance = 1e-14;
// Weights below this fraction of the largest are left out (validate).
constexpr double kNegligibleWeight = 1e-20;

double fit_tolerance_for(double mass) { return kFitRelativeTolerance * std::sqrt(mass); }

// The generic node count for `rank` moments: below it a design has fewer unknowns (3 per node)
// than moment equations.
int generic_count(int rank) { return std::max(1, (rank + 2) / 3); }

// A refit keeps nodes whose weight reaches 0 (they may regain it); they leave the design here.
void drop_zero_weights(SphericalDesign& design) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < design.nodes.size(); ++i) {
    if (design.weights[i] > 0.0) {
      design.nodes[kept] = design.nodes[i];
      design.weights[kept++] = design.weights[i];
    }
  }
  design.nodes.resize(kept);
  design.weights.resize(kept);
}

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

// The SH of degree `degree` at the measure's points, and its moments ∫ y dμ_w.
struct Samples {
  int degree = 0;
  Eigen::MatrixXd vandermonde;  // [points][sh_count(degree)]
  Eigen::VectorXd weights;
  Eigen::VectorXd moments;

  Samples(const CleanMeasure& measure, int degree) : degree(degree) {
    const int points = static_cast<int>(measure.dirs.size());
    const int k = sh_count(degree);
    vandermonde.resize(points, k);
    std::vector<double> y(k);
    for (int i = 0; i < points; ++i) {
      sh_basis(degree, measure.dirs[i], y.data());
      vandermonde.row(i) = Eigen::Map<const Eigen::RowVectorXd>(y.data(), k);
    }
    weights = Eigen::Map<const Eigen::VectorXd>(measure.weights.data(), points);
    moments = vandermonde.transpose() * weights;
  }

  std::vector<double> moment_vector() const { return {moments.data(), moments.data() + moments.size()}; }
};

// φ(x) = T y(x): functions of degree <= `degree` orthonormal for the measure (rank-many of them).
struct OrthonormalBasis {
  int degree = 0;
  BasisTransform transform;  // T, [rank][sh_count(degree)]

  int rank() const { return transform.size(); }

  MomentSystem system(const Eigen::VectorXd& moments) const {
    MomentSystem s;
    s.size = rank();
    s.raw_size = sh_count(degree);
    s.transform = transform;
    s.target = moments;
    s.evaluate = [d = degree](const glm::dvec3& x, double* values, double* gradients) {
      if (gradients) {
        sh_basis_with_gradient(d, x, values, gradients);
      } else {
        sh_basis(d, x, values);
      }
    };
    return s;
  }
};

// The basis from the Gram matrix G = Σ w y yᵀ: with P G Pᵀ = L D Lᵀ (pivoted LDLT),
// T = D^{-1/2} L⁻¹ P gives T G Tᵀ = I, lower triangular after the permutation P. k³ work after
// e k² for G, against e k² with a much larger constant for the QR of the e × k Vandermonde — but
// only where G is well conditioned.
std::optional<OrthonormalBasis> gram_basis(const Samples& samples) {
  const int k = static_cast<int>(samples.vandermonde.cols());
  const Eigen::MatrixXd weighted = samples.weights.cwiseSqrt().asDiagonal() * samples.vandermonde;
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(k, k);
  gram.selfadjointView<Eigen::Lower>().rankUpdate(weighted.transpose());
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(gram);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXd pivots = ldlt.vectorD();
  if (!(pivots.minCoeff() > kGramPivotFloor * pivots.maxCoeff())) return std::nullopt;
  OrthonormalBasis basis;
  basis.degree = samples.degree;
  const Eigen::VectorXi order = ldlt.transpositionsP() * Eigen::VectorXi::LinSpaced(k, 0, k - 1);
  basis.transform.rows.assign(order.data(), order.data() + k);
  basis.transform.lower = Eigen::MatrixXd::Identity(k, k);
  ldlt.matrixL().solveInPlace(basis.transform.lower);
  basis.transform.lower = pivots.cwiseSqrt().cwiseInverse().asDiagonal() * basis.transform.lower;
  return basis;
}

// A neighbour's nodes where this measure has no mass (a direction the neighbour sees and this
// vertex does not) cost the most in the orthonormal basis, whose functions grow fast away from
// the measure's support, and the fit rarely moves them out: they start at the nearest sample
// direction instead (at degree 9, with the closest start chosen as well, failed refits fell from
// 305 to 145 of 621).
void move_into_support(const CleanMeasure& measure, const OrthonormalBasis& basis, SphericalDesign& design) {
  const double normalisation = measure.mass / static_cast<double>(basis.rank());
  Eigen::VectorXd y(sh_count(basis.degree)), phi;
  for (glm::dvec3& node : design.nodes) {
    sh_basis(basis.degree, node, y.data());
    basis.transform.apply(y, phi);
    if (phi.squaredNorm() * normalisation > kOutsideSupport) {
      node = measure.dirs[nearest_direction(node, measure.dirs)];
    }
  }
}

// Σ w x / Σ w, as a unit direction where that mean is at least kClearMean long (a sky with a
// direction: a hemisphere's is 0.5 long), else zero (a band, two opposite caps: no direction to
// turn by). Divided by Σ w first, so that weights of any scale neither overflow nor vanish.
glm::dvec3 mean_direction(const std::vector<glm::dvec3>& points, const std::vector<double>& weights) {
  double mass = 0.0;
  for (double w : weights) mass += w;
  glm::dvec3 mean(0.0);
  for (std::size_t i = 0; i < points.size(); ++i) mean += (weights[i] / mass) * points[i];
  const double length = glm::length(mean);
  return length >= kClearMean ? mean / length : glm::dvec3(0.0);
}

// A neighbour's design turned towards this vertex's sky, whose mean direction is `sky`: by the
// smallest rotation that takes its own mean direction onto it (a design of degree >= 1 has its
// measure's first moments). Where the surface bends, the sky a vertex sees turns with its normal:
// at degree 9 (bumpy sphere, 1024 rays) the chosen starts' distances fell from a median of 0.97
// to 0.78, and LM steps from 73.3 to 68.1 per vertex. Fitting the whole rotation to the moments
// as well took them to 0.69 and 67, at the price of the rotation's own fit.
SphericalDesign turned_to(const glm::dvec3& sky, SphericalDesign design) {
  if (design.degree < 1) return design;
  const glm::dvec3 from = mean_direction(design.nodes, design.weights);
  const glm::dvec3 axis = glm::cross(from, sky);
  const double sine = glm::length(axis), cosine = glm::dot(from, sky);
  // Aligned, without a clear mean direction, or opposite: no smallest rotation, and any half turn
  // would be a guess.
  if (!(sine > 1e-12)) return design;
  const glm::dvec3 k = axis / sine;
  for (glm::dvec3& x : design.nodes) {
    x = glm::normalize(x * cosine + glm::cross(k, x) * sine + k * glm::dot(k, x) * (1.0 - cosine));
  }
  return design;
}

// `start` as a refit begins from it: its weights scaled to the measure's mass (a neighbour sees
// more or less sky, and a design's weights sum to its measure's mass), its nodes moved into the
// support.
SphericalDesign prepared_start(const CleanMeasure& measure, const OrthonormalBasis& basis, SphericalDesign start) {
  double start_mass = 0.0;
  for (double w : start.weights) start_mass += w;
  for (double& w : start.weights) w *= measure.mass / start_mass;
  move_into_support(measure, basis, start);
  return start;
}

// Σ w φ(x) − ∫ φ dμ: a design's moment residual in `basis`, taken against the raw moments first.
Eigen::VectorXd basis_residual(const Samples& samples, const OrthonormalBasis& basis, const SphericalDesign& design) {
  const std::vector<double> moments = design_moments(design.nodes, design.weights, samples.degree);
  Eigen::VectorXd residual;
  basis.transform.apply(Eigen::Map<const Eigen::VectorXd>(moments.data(), samples.moments.size()) - samples.moments,
                        residual);
  return residual;
}

// How far a refit from a prepared start has to go: its moment residual in `basis`, relative to
// √mass. NaN for a start without mass, which is then never chosen. Measured after the move into
// the support: before it, 138 of 621 neighbours' designs at degree 9 lay beyond 10³, all within 3
// after it.
double start_distance(const CleanMeasure& measure, const Samples& samples, const OrthonormalBasis& basis,
                      const SphericalDesign& start) {
  return basis_residual(samples, basis, start).norm() / std::sqrt(measure.mass);
}

// Theorem 2.2 from `start`, a prepared design of a nearby measure (a neighbouring vertex's):
// nodes and weights refitted by gradient projection (eq. 14) in `basis` (gram_basis's, or
// qr_basis's where the Gram matrix is ill-conditioned). Neighbours see nearly the same sky, so
// most refits certify with start's node count. A refit that stalls gains the sample directions
// along which added weight lowers E fastest (the entering variables of an active-set step), and is
// pruned back to the generic count after it certifies. Returns nothing when it does not certify.
std::optional<SphericalDesign> refit(const CleanMeasure& measure, const Samples& samples, const OrthonormalBasis& basis,
                                     const SphericalDesign& start, const std::function<bool()>& stop) {
  const MomentSystem system = basis.system(samples.moments);
  const FitOptions options{fit_tolerance_for(measure.mass), kWarmIterations, true, true, true, stop};
  const std::vector<double> moments = samples.moment_vector();
  auto certified = [&](SphericalDesign& design) { return certify_design(design, moments, measure.mass); };

  SphericalDesign design = start;
  fit_design(system, design.nodes, design.weights, options);
  drop_zero_weights(design);
  for (int round = 0; !certified(design) && round < kExchangeRounds; ++round) {
    const Eigen::VectorXd residual = basis_residual(samples, basis, design);
    // dE/dλ at a new node x is 2 φ(x)·residual: the most negative ones enter.
    const Eigen::VectorXd slope = samples.vandermonde * basis.transform.transpose_apply(residual, system.raw_size);
    std::vector<int> order(static_cast<std::size_t>(slope.size()));
    std::iota(order.begin(), order.end(), 0);
    const int entering = std::min<int>(kExchangeNodes, static_cast<int>(order.size()));
    std::partial_sort(order.begin(), order.begin() + entering, order.end(),
                      [&](int a, int b) { return slope(a) < slope(b); });
    for (int j = 0; j < entering && slope(order[j]) < 0.0; ++j) {
      design.nodes.push_back(measure.dirs[order[j]]);
      design.weights.push_back(-slope(order[j]) / system.size);
    }
    fit_design(system, design.nodes, design.weights, options);
    drop_zero_weights(design);
  }
  if (!certified(design)) return std::nullopt;
  const int generic = generic_count(system.size);
  if (design.size() > generic) {
    design = prune_design(system, std::move(design), generic, certified,
                          FitOptions{options.tolerance, kWarmIterations, true, false, true, stop}, PruneOptions{true});
  }
  design.method = "refit";
  return design;
}

// The basis from the column-pivoted QR of the weighted Vandermonde, which decides the rank where
// the Gram matrix is too ill-conditioned for gram_basis.
OrthonormalBasis qr_basis(const Samples& samples) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  qr.setThreshold(kRankThreshold);
  qr.compute(samples.weights.cwiseSqrt().asDiagonal() * samples.vandermonde);
  const int rank = static_cast<int>(qr.rank());

  // Only the kept columns enter T = R11⁻ᵀ (the pivoted columns' selection).
  OrthonormalBasis basis;
  basis.degree = samples.degree;
  const auto& pivots = qr.colsPermutation().indices();
  basis.transform.rows.assign(pivots.data(), pivots.data() + rank);
  basis.transform.lower = qr.matrixR().topLeftCorner(rank, rank).triangularView<Eigen::Upper>().solve(
      Eigen::MatrixXd::Identity(rank, rank)).transpose();
  return basis;
}

// Carathéodory–Tchakaloff compression in qr_basis's `basis`, then pruning by gradient projection
// where the measure has more points than moments. With no more, the compression keeps about all of
// them (rank-many), and their pruning rarely certifies: at degree 9 (bumpy sphere, 1024 rays) it
// saved nodes at 3 of the 30 such vertices, in 6 failed fits (~12 ms) each.
SphericalDesign compress(const CleanMeasure& measure, const Samples& samples, const OrthonormalBasis& basis,
                         const std::function<bool()>& stop) {
  const int points = static_cast<int>(measure.dirs.size());
  const int rank = basis.rank();
  Eigen::MatrixXd phi_transposed;
  basis.transform.apply(samples.vandermonde.transpose(), phi_transposed);
  const Eigen::MatrixXd phi = phi_transposed.transpose();  // orthonormal for the measure
  const Eigen::VectorXd target = phi.transpose() * samples.weights;
  const std::vector<double> moments = samples.moment_vector();
  auto certified = [&](SphericalDesign& design) { return certify_design(design, moments, measure.mass); };

  // A basic NNLS solution keeps at most `rank` samples.
  const Eigen::VectorXd u = nnls(phi.transpose(), target, 4 * rank + 10, stop);
  SphericalDesign best;
  best.degree = samples.degree;
  best.method = "tchakaloff";
  for (int i = 0; i < points; ++i) {
    if (u(i) > 0.0) {
      best.nodes.push_back(measure.dirs[i]);
      best.weights.push_back(u(i));
    }
  }
  if (!certified(best)) {
    throw std::runtime_error("Tchakaloff compression of degree " + std::to_string(samples.degree) +
                             " failed certification: residual " + number_string(best.residual));
  }

  if (points <= static_cast<int>(samples.moments.size())) return best;
  // Without backtracking (FitOptions::backtrack): with it, one vertex's pruning at degree 6 ended
  // at 36 nodes, the largest design (20 without, as many as the refits'). At degree 9 it took
  // 39.00 → 39.43 nodes on average, within the noise in time.
  const int generic = generic_count(rank);
  return prune_design(basis.system(samples.moments), std::move(best), generic, certified,
                      FitOptions{fit_tolerance_for(measure.mass), 100, true, false, false, stop}, PruneOptions{true});
}

}  // namespace

SphericalDesign weighted_design(const std::vector<glm::dvec3>& dirs, const std::vector<double>& weights,
                                int degree, const std::vector<const SphericalDesign*>& starts,
                                const std::function<bool()>& stop) {
  const CleanMeasure measure = validate(dirs, weights, degree);
  const Samples samples(measure, degree);
  std::optional<SphericalDesign> design;
  std::optional<OrthonormalBasis> qr;
  // A measure of no more points than moments has a rank of at most its point count, and the
  // compression keeps at most that many: at degree 9 (30 vertices of 50–99 points) refits from a
  // neighbour's design never did better, at ~20 ms each. Nor did they with up to a tenth more
  // points (kFewPoints): 10 vertices of 101–110, at ~15 ms each.
  const bool few_points =
      static_cast<double>(measure.dirs.size()) <= kFewPoints * static_cast<double>(samples.moments.size());
  if (!starts.empty() && !few_points) {
    std::optional<OrthonormalBasis> basis = gram_basis(samples);
    if (!basis) basis = qr = qr_basis(samples);
    std::optional<SphericalDesign> start;
    double closest = std::numeric_limits<double>::infinity();
    const glm::dvec3 sky = mean_direction(measure.dirs, measure.weights);
    for (const SphericalDesign* candidate : starts) {
      if (candidate == nullptr || candidate->degree != degree || candidate->size() == 0) continue;
      SphericalDesign prepared = prepared_start(measure, *basis, turned_to(sky, *candidate));
      const double distance = start_distance(measure, samples, *basis, prepared);
      if (distance < closest) {
        closest = distance;
        start = std::move(prepared);
      }
    }
    const int rank = basis->rank();
    // The count to aim at: the start's, or without one the clustered start's.
    const int aim = start ? start->size() : static_cast<int>(std::ceil(kClusteredNodesPerGeneric * generic_count(rank)));
    // The largest count kept without trying the clustered start; never more than the
    // compression's bound, the rank.
    const int most = std::min(aim + kSpareNodes, rank);
    if (start) design = refit(measure, samples, *basis, *start, stop);
    // At degree 9 the refit of a clustered start certifies about twice as often as it fails, at
    // a third of the compression's cost.
    if (!design || design->size() > most) {
      const SphericalDesign clustered_nodes = clustered_start(measure.dirs, measure.weights, aim, degree);
      std::optional<SphericalDesign> clustered =
          refit(measure, samples, *basis, prepared_start(measure, *basis, clustered_nodes), stop);
      if (clustered && (!design || clustered->size() < design->size())) {
        design = std::move(clustered);
        design->method = "clustered";
      }
    }
  }
  // The compression runs only where no refit certified. After a refit with more nodes than
  // `most` it saved 0.08 nodes per vertex at degree 9 (51 in all), and took 12 % of the LM steps.
  if (!design) {
    if (!qr) qr = qr_basis(samples);
    design = compress(measure, samples, *qr, stop);
  }
  for (double& w : design->weights) w *= measure.scale;
  return std::move(*design);
}

}  // namespace sd
