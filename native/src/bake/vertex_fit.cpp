#include "sdlighting/vertex_fit.h"

#include "util/parallel_for.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sd {
namespace {

constexpr double kSingular = 1e-12;   // a pivot below this share of its diagonal entry is zero

void check_index(const char* what, std::int64_t index, std::size_t vertex_count) {
  if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count) {
    throw std::invalid_argument(std::string(what) + " index " + std::to_string(index) + " is outside [0, " +
                                std::to_string(vertex_count) + ")");
  }
}

void check_input(std::size_t vertex_count, const MeshSamples& samples, const double* values, std::size_t value_count,
                 std::size_t channels, const std::vector<PenaltyRow>& penalties, double smoothness) {
  const std::size_t count = samples.triangles.size();
  if (samples.barycentric.size() != count || samples.weights.size() != count) {
    throw std::invalid_argument("samples: " + std::to_string(count) + " triangles, " +
                                std::to_string(samples.barycentric.size()) + " barycentric coordinates and " +
                                std::to_string(samples.weights.size()) + " weights");
  }
  if (value_count != count * channels) {
    throw std::invalid_argument("values: " + std::to_string(value_count) + " numbers for " + std::to_string(count) +
                                " samples of " + std::to_string(channels) + " channels");
  }
  for (std::size_t s = 0; s < count; ++s) {
    for (int k = 0; k < 3; ++k) check_index("sample triangle", samples.triangles[s][k], vertex_count);
    const glm::dvec3& b = samples.barycentric[s];
    if (!std::isfinite(b.x) || !std::isfinite(b.y) || !std::isfinite(b.z)) {
      throw std::invalid_argument("sample " + std::to_string(s) + " has non-finite barycentric coordinates");
    }
    if (!(samples.weights[s] >= 0.0) || !std::isfinite(samples.weights[s])) {
      throw std::invalid_argument("sample " + std::to_string(s) + " has weight " + std::to_string(samples.weights[s]) +
                                  " (finite and >= 0 needed)");
    }
  }
  if (!std::all_of(values, values + value_count, [](double v) { return std::isfinite(v); })) {
    throw std::invalid_argument("values must be finite");
  }
  for (const PenaltyRow& row : penalties) {
    for (int k = 0; k < 4; ++k) {
      if (!std::isfinite(row.coefficients[k])) throw std::invalid_argument("penalty coefficients must be finite");
      if (row.coefficients[k] != 0.0) check_index("penalty", row.vertices[k], vertex_count);
    }
  }
  if (!(smoothness >= 0.0) || !std::isfinite(smoothness)) {
    throw std::invalid_argument("smoothness must be finite and >= 0, got " + std::to_string(smoothness));
  }
}

}  // namespace

std::vector<double> fit_vertex_values(std::size_t vertex_count, const MeshSamples& samples, const double* values,
                                      std::size_t value_count, std::size_t channels,
                                      const std::vector<PenaltyRow>& penalties, double smoothness, int threads,
                                      const std::function<bool(std::size_t, std::size_t)>& progress) {
  check_input(vertex_count, samples, values, value_count, channels, penalties, smoothness);
  if (vertex_count == 0 || channels == 0) return std::vector<double>(vertex_count * channels, 0.0);
  constexpr std::size_t kBlock = 8;  // channels per right-hand side block (see the solve below)
  const std::size_t blocks = (channels + kBlock - 1) / kBlock;
  if (progress && !progress(0, blocks)) throw BakeCancelled("the least-squares fit was cancelled");
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor>;
  using Triplet = Eigen::Triplet<double>;
  const auto n = static_cast<Eigen::Index>(vertex_count);

  // The normal matrix of the samples: N = A^T W A (A: a sample's barycentric row).
  std::vector<Triplet> entries;
  entries.reserve(9 * samples.triangles.size() + 16 * penalties.size());
  std::vector<double> diagonal(vertex_count, 0.0);
  for (std::size_t s = 0; s < samples.triangles.size(); ++s) {
    const double w = samples.weights[s];
    if (w == 0.0) continue;
    const Triangle& t = samples.triangles[s];
    const glm::dvec3& b = samples.barycentric[s];
    for (int i = 0; i < 3; ++i) {
      if (b[i] == 0.0) continue;
      for (int j = 0; j < 3; ++j) {
        if (b[j] != 0.0) entries.emplace_back(t[i], t[j], w * b[i] * b[j]);
      }
      diagonal[t[i]] += w * b[i] * b[i];
    }
  }
  double mean_diagonal = 0.0;
  for (double d : diagonal) mean_diagonal += d / static_cast<double>(vertex_count);
  const double lambda = smoothness * mean_diagonal;
  std::vector<bool> reached(vertex_count);
  for (std::size_t v = 0; v < vertex_count; ++v) reached[v] = diagonal[v] > 0.0;
  if (lambda > 0.0) {
    for (const PenaltyRow& row : penalties) {
      for (int i = 0; i < 4; ++i) {
        if (row.coefficients[i] == 0.0) continue;
        for (int j = 0; j < 4; ++j) {
          if (row.coefficients[j] != 0.0) {
            entries.emplace_back(row.vertices[i], row.vertices[j], lambda * row.coefficients[i] * row.coefficients[j]);
          }
        }
        reached[row.vertices[i]] = true;
      }
    }
  }
  const std::size_t unreached = static_cast<std::size_t>(std::count(reached.begin(), reached.end(), false));
  if (unreached > 0) {
    throw std::runtime_error(std::to_string(unreached) + " of " + std::to_string(vertex_count) +
                             " vertices are reached by no sample of positive weight and no penalty: their values "
                             "are undetermined");
  }
  Eigen::SparseMatrix<double> normal(n, n);
  normal.setFromTriplets(entries.begin(), entries.end());

  // A part of the mesh that only penalties reach stays singular (what they leave free is free):
  // the factorization then has a pivot that vanishes against its row's diagonal entry (each
  // pivot of an LDL^T factorization is at most that entry, the rest being what the row shares).
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> cholesky(normal);
  if (cholesky.info() != Eigen::Success) {
    throw std::runtime_error("the least-squares system of " + std::to_string(vertex_count) +
                             " vertices could not be factorized");
  }
  const Eigen::VectorXd diagonal_entries = cholesky.permutationP() * normal.diagonal();
  if ((cholesky.vectorD().array() <= kSingular * diagonal_entries.array()).any()) {
    throw std::runtime_error("the least-squares system of " + std::to_string(vertex_count) +
                             " vertices is singular: a part of the mesh has no sample of positive weight");
  }
  // The channels are independent right-hand sides R = A^T W F of one factorization: formed and
  // solved a block of kBlock at a time (the memory beyond the output stays a few blocks' worth,
  // however many channels), the blocks in parallel.
  std::vector<double> out(vertex_count * channels);
  ParallelOptions parallel(threads);
  parallel.progress = progress;
  const ParallelOutcome outcome = parallel_for(blocks, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t block = begin; block < end; ++block) {
      const std::size_t first = block * kBlock, width = std::min(kBlock, channels - first);
      Matrix rhs = Matrix::Zero(n, static_cast<Eigen::Index>(width));
      for (std::size_t s = 0; s < samples.triangles.size(); ++s) {
        const double w = samples.weights[s];
        const glm::dvec3& b = samples.barycentric[s];
        for (int i = 0; i < 3; ++i) {
          if (w == 0.0 || b[i] == 0.0) continue;
          for (std::size_t c = 0; c < width; ++c) {
            rhs(samples.triangles[s][i], static_cast<Eigen::Index>(c)) += w * b[i] * values[s * channels + first + c];
          }
        }
      }
      const Matrix solution = cholesky.solve(rhs);
      for (std::size_t v = 0; v < vertex_count; ++v) {
        for (std::size_t c = 0; c < width; ++c) out[v * channels + first + c] = solution(v, c);
      }
    }
  }, parallel);
  if (!outcome.completed) {
    throw BakeCancelled("the least-squares fit was cancelled after " + std::to_string(outcome.done) + " of " +
                        std::to_string(blocks) + " blocks of channels");
  }
  return out;
}

}  // namespace sd
