// Weighted spherical designs for weights known only through samples: an environment channel,
// or a visibility function given by ray samples (Theorem 2.2, the seed's comment 3 and Table 2).
#pragma once

#include "sdlighting/spherical_design.h"
#include "sdlighting/spherical_harmonics.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <functional>
#include <vector>

namespace sd {

/// A design of `degree` (0..kMaxDesignDegree) for the discrete measure Σ_i weights_i δ(dirs_i),
/// its weights summing to that measure's mass, certified to kDesignTolerance.
///
/// Carathéodory–Tchakaloff compression (Sommariva–Vianello): in a basis orthonormal for the
/// measure (column-pivoting QR of the weighted SH Vandermonde, rank-truncated), NNLS picks at most
/// rank-many of the sample directions with positive weights and the same moments. Gradient
/// projection (eq. 14) then removes nodes while the design still certifies (where the measure
/// has more points than moments; with no more, the compression's nodes are kept).
///
/// With `starts`, certified designs of the same degree for nearby measures (neighbouring vertices'
/// visibility), it first turns each by the smallest rotation that takes its mean direction onto
/// this measure's (where both have a clear one), then refits the one whose moments lie closest to
/// this measure's in a basis orthonormal for the measure (through its Gram matrix, or the QR above
/// where that is too ill-conditioned), by gradient projection in that basis — a fraction of the
/// compression's cost, with that start's node count. Where that start is far, its refit fails or
/// needs more nodes, it refits a start clustered from the measure's own samples (method
/// "clustered", kept where it has fewer nodes), and compresses only when neither refit certifies.
/// Null, empty and other-degree starts are skipped; an empty `starts`, or a measure of at most
/// kFewPoints (weighted_design.cpp) points per moment, compresses at once.
///
/// `dirs` need not be unit length (they are normalised) but must be finite and non-zero;
/// weights must be finite and >= 0 with a positive sum that fits a double; any scale works
/// (1e-300..1e300, denormals: the fit runs on the weights divided by the largest). Throws
/// std::invalid_argument otherwise or when weighted_design_bytes exceeds kMaxCallBytes,
/// std::runtime_error if no certified design is found. `stop` is polled between the steps of the
/// fits (at high degree one design takes seconds); returning true throws DesignCancelled.
SphericalDesign weighted_design(const std::vector<glm::dvec3>& dirs, const std::vector<double>& weights,
                                int degree, const std::vector<const SphericalDesign*>& starts = {},
                                const std::function<bool()>& stop = {});

/// The bytes weighted_design allocates for `points` samples at `degree`: at most five dense
/// points × (degree+1)² matrices of doubles at once (the SH Vandermonde, and in the compression
/// the permuted Vandermonde the orthonormal basis at the samples is computed from, that basis, its
/// transpose and NNLS's copy). weighted_design refuses measures that would need more than
/// kMaxCallBytes.
inline double weighted_design_bytes(std::size_t points, int degree) {
  return 5.0 * sizeof(double) * static_cast<double>(points) * sh_count(degree);
}

}  // namespace sd
