// Least-squares vertex values (issue 8, item 2): per-vertex data whose linear interpolation over
// the triangles best matches samples spread over them, after Kavan, Bargteil and Sloan, "Least
// Squares Vertex Baking", EGSR 2011. The live shading interpolates per-vertex values linearly;
// values taken at the vertices alone put a whole face's error where its corners are (a corner in
// a concave crease darkens the face it shares with a lit plate), the fit spreads it.
#pragma once

#include "sdlighting/mesh.h"
#include "sdlighting/visibility.h"

#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace sd {

/// Samples of a signal over a triangle mesh: each a point of one triangle.
struct MeshSamples {
  std::vector<Triangle> triangles;      ///< [S] the vertices of the sample's triangle
  std::vector<glm::dvec3> barycentric;  ///< [S] its barycentric coordinates there (finite)
  std::vector<double> weights;          ///< [S] its weight >= 0: the surface area it stands for
};

/// A regulariser term: a linear combination of up to four vertices' values that should be zero
/// (unused slots: coefficient 0), e.g. the jump of the interpolant's gradient across an edge.
struct PenaltyRow {
  std::array<std::int64_t, 4> vertices;
  std::array<double, 4> coefficients;
};

/// The vertex values X [vertex_count x channels, row-major] minimizing
///   sum_s w_s |sum_k b_sk X[t_sk] - F_s|^2 + smoothness * mean_diagonal * sum_r |sum_k c_rk X[v_rk]|^2
/// over the samples s (triangle t_s, barycentric b_s, weight w_s) with values F [S x channels,
/// row-major] and the penalty rows r (Kavan et al.'s regulariser against banding; mean_diagonal,
/// the mean of the first sum's normal-matrix diagonal, makes `smoothness` a relative weight). The
/// normal equations are solved by a sparse Cholesky factorization (Eigen's SimplicialLDLT), the
/// channels on `threads` threads (0: every hardware thread). Throws std::invalid_argument for
/// malformed input (indices out of range, non-finite numbers, negative weights or smoothness) and
/// std::runtime_error when a vertex is reached by no sample of positive weight and no penalty, or
/// the system is singular. `progress`, as TransferOptions::progress, counts the blocks of channels
/// solved (with none done before the factorization, which cannot be interrupted, and again as the
/// solves start); returning false throws BakeCancelled.
/// F is read in place: `values` points at `value_count` numbers (a caller's array, not copied).
std::vector<double> fit_vertex_values(std::size_t vertex_count, const MeshSamples& samples, const double* values,
                                      std::size_t value_count, std::size_t channels,
                                      const std::vector<PenaltyRow>& penalties, double smoothness,
                                      int threads = 0,
                                      const std::function<bool(std::size_t done, std::size_t total)>& progress = {});

/// fit_vertex_values of the values in a vector.
inline std::vector<double> fit_vertex_values(std::size_t vertex_count, const MeshSamples& samples,
                                             const std::vector<double>& values, std::size_t channels,
                                             const std::vector<PenaltyRow>& penalties, double smoothness,
                                             int threads = 0,
                                             const std::function<bool(std::size_t, std::size_t)>& progress = {}) {
  return fit_vertex_values(vertex_count, samples, values.data(), values.size(), channels, penalties, smoothness,
                           threads, progress);
}

}  // namespace sd
