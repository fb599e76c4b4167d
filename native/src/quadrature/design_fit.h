// Gradient projection for weighted designs (eq. 14), shared by the zonal and the tabulated
// builders. Private to the library.
#pragma once

#include "sdlighting/spherical_design.h"

#include <glm/vec3.hpp>

#include <Eigen/Dense>

#include <functional>
#include <vector>

namespace sd {

/// A basis of functions as T F(x), F the raw functions: T = L S, where S picks the raw functions
/// at `rows` (in that order) and L is lower triangular, as both of weighted_design's orthonormal
/// bases come out (an LDLT's L⁻¹, a QR's R⁻ᵀ). A triangular product costs half a dense one, and
/// T times a step's Jacobian is a fifth of a degree-9 per-vertex design's time.
struct BasisTransform {
  std::vector<int> rows;
  Eigen::MatrixXd lower;  ///< [rows.size()][rows.size()], read on and below the diagonal only

  bool identity() const { return rows.empty(); }
  int size() const { return static_cast<int>(rows.size()); }

  /// T raw, for a vector or matrix with the raw functions along its rows.
  template <typename Raw, typename Out>
  void apply(const Raw& raw, Out& out) const {
    out.noalias() = lower.triangularView<Eigen::Lower>() * raw(rows, Eigen::all);
  }

  /// Tᵀ v, a vector over `raw_size` raw functions.
  Eigen::VectorXd transpose_apply(const Eigen::VectorXd& v, int raw_size) const {
    const Eigen::VectorXd picked = lower.triangularView<Eigen::Lower>().transpose() * v;
    Eigen::VectorXd out = Eigen::VectorXd::Zero(raw_size);
    out(rows) = picked;
    return out;
  }
};

/// The moment equations of one weight, in a basis chosen by the caller to be (near) orthonormal
/// for that weight, so that the system stays well conditioned even for narrow lobes
/// (msd-notes: the raw SH Vandermonde reaches condition 1e15).
struct MomentSystem {
  int size = 0;
  /// Writes `raw_size` function values at a unit direction and, when `gradients` is not null,
  /// their ambient gradients (3 doubles per function; only the tangential part is used). The
  /// basis is those functions themselves, or `transform` times them.
  std::function<void(const glm::dvec3& dir, double* values, double* gradients)> evaluate;
  int raw_size = 0;
  /// Identity (empty; raw_size = size) or size rows. Applied once per step to the whole Jacobian
  /// rather than per node: one matrix product instead of one per node.
  BasisTransform transform;
  /// ∫ raw functions · w dμ: the residual is taken against it before the transform, where the
  /// certification measures it, so a large transform does not amplify the rounding of the sums.
  Eigen::VectorXd target;
  /// Optional projection of a unit direction onto the weight's support, applied after every step
  /// so that nodes stay where the weight lives (a lobe's nodes above its horizon).
  std::function<glm::dvec3(const glm::dvec3& dir)> project_to_support;
};

/// When to stop a fit.
struct FitOptions {
  double tolerance = 0.0;   ///< stop once √E <= tolerance
  int max_iterations = 300;
  /// Give up once E stops halving over 10 iterations, and near the tolerance at the first step
  /// that fails (design_fit.cpp, kPolishZone and kConvergingZone): cheap for the many small
  /// per-vertex designs of a bake (and the lobes' thinning), while one-off lobe designs are worth
  /// the slow phases some fits go through.
  bool stop_when_stalled = false;
  /// Keep nodes whose weight reaches 0 (they may regain weight later) instead of removing them.
  bool keep_zero_weights = false;
  /// Halve a rejected step before raising μ (design_fit.cpp, kBacktracks): fewer factorisations
  /// for the per-vertex designs of a bake; with it the lobes' continuation at degree 10 kept one
  /// node more (42 against 41).
  bool backtrack = false;
  /// Polled before every step; returning true throws DesignCancelled.
  std::function<bool()> stop;
};

/// Minimises E = ‖Σ_ν λ_ν F(x_ν) − target‖² over x_ν ∈ S², λ_ν >= 0 (eq. 14) by projected
/// Levenberg–Marquardt steps: each step moves nodes in their tangent planes, then projects back
/// onto the sphere (and the system's support, if it has one) and λ onto λ >= 0. Nodes whose weight reaches 0 are removed. Returns √E.
double fit_design(const MomentSystem& system, std::vector<glm::dvec3>& nodes,
                  std::vector<double>& weights, const FitOptions& options);

/// Which nodes prune_design drops first.
struct PruneOptions {
  /// Drop the nodes with the smallest moments w‖F(x)‖ in the system's basis, rather than the
  /// lightest. A pruned fit starts at the dropped nodes' moment residual Σ w F(x), and in a basis
  /// orthonormal for a measure the two orders differ where the measure thins out: for the
  /// per-vertex designs of V at degree 9 (bumpy sphere, 1024 rays) smallest moments first took
  /// 18.2 → 16.0 ms per vertex and 41.22 → 39.92 nodes; for the lobes' continuation at degree 10 it
  /// kept one node more (42 against 41), so they drop the lightest.
  bool smallest_moments_first = false;
};

/// Gradient projection used to remove nodes: drops the `step` first nodes of a certified design
/// (PruneOptions), refits, keeps the result if `certify` accepts it (it sets the residual), and
/// halves the step after a failure; the first step aims at `target_size`, below which it never
/// goes (the generic count: fewer nodes have fewer unknowns than moment equations). Returns the
/// smallest design found.
SphericalDesign prune_design(const MomentSystem& system, SphericalDesign design, int target_size,
                             const std::function<bool(SphericalDesign&)>& certify, const FitOptions& options,
                             const PruneOptions& pruning = {});

}  // namespace sd
