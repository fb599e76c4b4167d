#include "sdlighting/visibility.h"

#include "util/parallel_for.h"
#include "sdlighting/spherical_design.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/weighted_design.h"

#include "bake/embree_scene.h"
#include "bake/traced_scene.h"
#include "bake/vertex_walk.h"

#include <Eigen/Core>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <string>
#include <utility>

namespace sd {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Most vertices a worker takes per grab of the shared counter, and the rays a chunk aims at.
constexpr std::size_t kChunk = 8;
constexpr std::size_t kChunkRays = 8 * 1024;
// Rays per trace_occlusion call (bounds the scratch memory for huge ray counts).
constexpr int kStreamBlock = 1024;
// Vertices per group of a bake with designs (bake/vertex_walk.h): one cold design per group, so
// larger groups refit more, at the price of coarser progress and load balance.
constexpr std::size_t kDesignGroup = 32;

// ---- random rotations ----

std::uint64_t splitmix64_mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() { return splitmix64_mix(state += 0x9e3779b97f4a7c15ULL); }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

// ---- validation ----

// An order of the bake's options: in [0, max_order], or -1 (not requested).
void check_requested_order(const char* name, int order, int max_order) {
  if (order != -1) check_order(std::string(name) + " (-1: not requested)", order, max_order);
}

// Both orders of a pair requested, or neither.
void check_pair(const char* name, int s, int s_prime) {
  if ((s < 0) != (s_prime < 0)) {
    throw std::invalid_argument(std::string(name) + " needs both orders s and s' (or neither), got s = " +
                                std::to_string(s) + ", s' = " + std::to_string(s_prime));
  }
}

// The bytes a bake allocates: per vertex its results (designs counted at their most nodes,
// (degree+1)², held twice while flattened) and the recorded rays; per thread the SH values at the
// escaping rays and a design's matrices (weighted_design_bytes); once the ray set and its SH values.
double bake_bytes(const TransferOptions& o, std::size_t vertices) {
  auto count = [](int order) { return order < 0 ? 0.0 : double(sh_count(order)); };
  const double rays = o.rays;
  const int degree = o.design_order < 0 ? -1 : o.design_order + o.design_visibility_order;
  const double per_vertex = 8.0 * (4 + count(o.visibility_order) + count(o.product_order) * count(o.product_visibility_order) +
                                   count(o.transfer_order) + 2) +
                            2.0 * 32.0 * count(degree) + (o.record_rays ? rays : 0.0);
  const int basis = std::max({o.visibility_order, o.product_order, o.product_visibility_order, o.transfer_order});
  const double per_thread = rays * (8.0 * count(basis) + 32.0) + (degree < 0 ? 0.0 : weighted_design_bytes(o.rays, degree));
  const int threads = o.threads > 0 ? o.threads : default_thread_count();
  return vertices * per_vertex + threads * per_thread + rays * (24.0 + 8.0 * count(basis));
}

// ---- the per-vertex work ----

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Plan {
  int rays = 0;
  int basis_order = -1;  // SH order of the sums over the rays (-1: none)
  int visibility_order = -1, product_order = -1, product_visibility_order = -1, transfer_order = -1;
  int visibility_count = 0, product_rows = 0, product_cols = 0, transfer_count = 0;
  int design_degree = -1;
  bool record_rays = false;
  bool common_rotation = false;
  bool horizon = false;  // TransferOptions::horizon
  std::uint64_t seed = 0;
  const std::vector<glm::dvec3>* fibonacci = nullptr;
  const RowMatrix* basis = nullptr;  // the SH to basis_order at the unrotated ray set, a row per ray
  const EulerShRotation* turn = nullptr;  // to basis_order
};

struct Scratch {
  std::vector<RTCRay> stream;          // one block of rays for trace_occlusion
  std::vector<glm::dvec3> directions;  // their directions in double
  std::vector<int> traced;             // their indices in the ray set
  std::vector<glm::dvec3> escaped;
  std::vector<int> escaped_rays;       // their indices in the ray set
  std::vector<double> weights;
  std::vector<const SphericalDesign*> starts;  // the walk's candidates' designs (weighted_design)
  RowMatrix y;           // [escaping rays][the product's larger count], at the unrotated rays
  RowMatrix product;
  Eigen::VectorXd vector;
};

struct Outputs {
  TransferBake* bake;
  std::vector<SphericalDesign>* designs;
};

// s.starts: candidate designs to refit for this vertex's (Theorem 2.2), possibly none. Returns
// false, the vertex unfinished, when `stopping` interrupted its design.
bool bake_vertex(RTCScene scene, const Plan& plan, const glm::dvec3& origin, const glm::dvec3& n, std::size_t v,
                 const StopQuery& stopping, Scratch& s, const Outputs& out) {
  const glm::dmat3 rotation = vertex_ray_rotation(plan.seed, plan.common_rotation ? 0 : v);
  const std::vector<glm::dvec3>& base = *plan.fibonacci;
  const int rays = plan.rays;
  std::uint8_t* record = plan.record_rays ? out.bake->ray_visibility.data() + v * static_cast<std::size_t>(rays)
                                          : nullptr;

  // Rays go to Embree in blocks of up to kStreamBlock, one origin each (trace_occlusion).
  s.escaped.clear();
  s.escaped_rays.clear();
  for (int start = 0; start < rays; start += kStreamBlock) {
    const int count = std::min(kStreamBlock, rays - start);
    s.directions.clear();
    s.stream.clear();
    s.traced.clear();
    for (int i = 0; i < count; ++i) {
      const glm::dvec3 x = rotation * base[start + i];
      if (plan.horizon && glm::dot(n, x) <= 0.0) {  // blocked by the surface closed below
        if (record) record[start + i] = 0;
        continue;
      }
      s.directions.push_back(x);
      s.stream.push_back(occlusion_ray(origin, x));
      s.traced.push_back(start + i);
    }
    if (s.stream.empty()) continue;
    trace_occlusion(scene, s.stream.data(), static_cast<unsigned>(s.stream.size()));
    for (std::size_t k = 0; k < s.stream.size(); ++k) {
      const bool escapes = !is_occluded(s.stream[k]);
      if (escapes) {
        s.escaped.push_back(s.directions[k]);
        s.escaped_rays.push_back(s.traced[k]);
      }
      if (record) record[s.traced[k]] = escapes ? 1 : 0;
    }
  }

  const int e = static_cast<int>(s.escaped.size());
  const double inv_rays = 1.0 / rays;
  TransferBake& bake = *out.bake;
  bake.ambient_occlusion[v] = e * inv_rays;

  // The sums over the rays run in the unrotated ray set, whose SH values are computed once per bake,
  // and only their results turn with the vertex: y(R x) = D(R) y(x) (sh_rotation.h). Evaluating the
  // basis at every rotated ray instead took most of a bake's time at orders 5 and over.
  const auto ray_sh = [&](int r) { return plan.basis->row(s.escaped_rays[r]); };
  if (plan.visibility_count > 0) {
    s.vector.setZero(plan.visibility_count);
    for (int r = 0; r < e; ++r) s.vector += ray_sh(r).head(plan.visibility_count).transpose();
    s.vector *= inv_rays;
    plan.turn->apply(rotation, s.vector.data(), 1, plan.visibility_order);
    std::copy(s.vector.data(), s.vector.data() + plan.visibility_count,
              bake.visibility.data() + v * static_cast<std::size_t>(plan.visibility_count));
  }
  if (plan.product_rows > 0) {
    const int rows = plan.product_rows, cols = plan.product_cols;
    const int count = std::max(rows, cols);  // s' may exceed s
    s.y.resize(e, count);
    for (int r = 0; r < e; ++r) s.y.row(r) = ray_sh(r).head(count);
    s.product.noalias() = s.y.leftCols(rows).transpose() * s.y.leftCols(cols) * inv_rays;
    plan.turn->apply(rotation, s.product.data(), cols, plan.product_order);  // D_s P: turns the rows
    s.product.transposeInPlace();
    plan.turn->apply(rotation, s.product.data(), rows, plan.product_visibility_order);  // (P D_s'ᵀ)ᵀ
    s.product.transposeInPlace();
    std::copy(s.product.data(), s.product.data() + rows * cols,
              bake.product_matrices.data() + v * static_cast<std::size_t>(rows) * cols);
  }
  if (plan.transfer_count > 0) {
    s.vector.setZero(plan.transfer_count);
    for (int r = 0; r < e; ++r) {
      const double cosine = 4.0 * std::max(0.0, glm::dot(n, s.escaped[r]));
      s.vector += cosine * ray_sh(r).head(plan.transfer_count).transpose();
    }
    s.vector *= inv_rays;
    plan.turn->apply(rotation, s.vector.data(), 1, plan.transfer_order);
    std::copy(s.vector.data(), s.vector.data() + plan.transfer_count,
              bake.transfer.data() + v * static_cast<std::size_t>(plan.transfer_count));
  }
  if (plan.design_degree >= 0 && e > 0) {
    s.weights.assign(e, inv_rays);
    try {
      (*out.designs)[v] = weighted_design(s.escaped, s.weights, plan.design_degree, s.starts, stopping);
    } catch (const DesignCancelled&) {
      return false;
    } catch (const std::exception& error) {
      throw std::runtime_error("the visibility design of degree " + std::to_string(plan.design_degree) +
                               " for vertex " + std::to_string(v) + " (" + std::to_string(e) + " of " +
                               std::to_string(rays) + " rays escaping) failed: " + error.what());
    }
  }
  return true;
}

}  // namespace

std::vector<glm::dvec3> spherical_fibonacci(int count) {
  if (count < 1) throw std::invalid_argument("spherical_fibonacci needs count >= 1, got " + std::to_string(count));
  const double golden_fraction = 0.5 * (std::sqrt(5.0) - 1.0);  // 1/φ
  std::vector<glm::dvec3> points(count);
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double r = std::sqrt((1.0 - z) * (1.0 + z));
    const double turns = i * golden_fraction;
    const double phi = 2.0 * kPi * (turns - std::floor(turns));
    points[i] = glm::dvec3(r * std::cos(phi), r * std::sin(phi), z);
  }
  return points;
}

glm::dmat3 vertex_ray_rotation(std::uint64_t seed, std::size_t vertex) {
  SplitMix64 rng{splitmix64_mix(seed) ^ static_cast<std::uint64_t>(vertex)};
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  // Shoemake: a uniformly distributed unit quaternion (w, x, y, z).
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  const double x = a * std::sin(2.0 * kPi * u2), y = a * std::cos(2.0 * kPi * u2);
  const double z = b * std::sin(2.0 * kPi * u3), w = b * std::cos(2.0 * kPi * u3);
  glm::dmat3 m;  // column-major: m[column][row]
  m[0][0] = 1.0 - 2.0 * (y * y + z * z);
  m[0][1] = 2.0 * (x * y + w * z);
  m[0][2] = 2.0 * (x * z - w * y);
  m[1][0] = 2.0 * (x * y - w * z);
  m[1][1] = 1.0 - 2.0 * (x * x + z * z);
  m[1][2] = 2.0 * (y * z + w * x);
  m[2][0] = 2.0 * (x * z + w * y);
  m[2][1] = 2.0 * (y * z - w * x);
  m[2][2] = 1.0 - 2.0 * (x * x + y * y);
  return m;
}

std::vector<glm::dvec3> vertex_ray_directions(int rays, std::uint64_t seed, std::size_t vertex) {
  std::vector<glm::dvec3> dirs = spherical_fibonacci(rays);
  const glm::dmat3 rotation = vertex_ray_rotation(seed, vertex);
  for (auto& d : dirs) d = rotation * d;
  return dirs;
}

TransferBake bake_transfer(const std::vector<glm::dvec3>& vertices, const std::vector<glm::dvec3>& normals,
                           const std::vector<Triangle>& triangles, const TransferOptions& options,
                           const OccluderMesh& occluders) {
  const auto start = std::chrono::steady_clock::now();

  // ---- validation ----
  if (vertices.empty()) throw std::invalid_argument("the mesh has no vertices");
  if (normals.size() != vertices.size()) {
    throw std::invalid_argument("normals must match vertices: " + std::to_string(normals.size()) + " normals for " +
                                std::to_string(vertices.size()) + " vertices");
  }
  check_range("rays", options.rays, 1, kMaxRaysPerVertex);
  if (options.threads < 0) throw std::invalid_argument("threads must be >= 0 (0: all), got " + std::to_string(options.threads));
  check_requested_order("visibility_order s'", options.visibility_order, kMaxVisibilityOrder);
  check_requested_order("product_order s", options.product_order, kMaxTransferOrder);
  check_requested_order("product_visibility_order s'", options.product_visibility_order, kMaxVisibilityOrder);
  check_pair("the product matrix", options.product_order, options.product_visibility_order);
  check_requested_order("transfer_order s", options.transfer_order, kMaxTransferOrder);
  check_requested_order("design_order s", options.design_order, kMaxTransferOrder);
  check_requested_order("design_visibility_order s'", options.design_visibility_order, kMaxVisibilityOrder);
  check_pair("the design", options.design_order, options.design_visibility_order);
  if (options.design_order >= 0) {
    check_order("design degree s + s'", options.design_order + options.design_visibility_order, kMaxDesignDegree);
  }
  check_allocation("a bake of " + std::to_string(vertices.size()) + " vertices x " + std::to_string(options.rays) + " rays",
                   bake_bytes(options, vertices.size()));
  check_points("vertices", vertices);
  check_triangles("triangles", triangles, vertices.size(), "vertices");
  std::vector<std::int64_t> fallback_normals;
  const std::vector<glm::dvec3> units = unit_normals(normals, vertices, triangles, &fallback_normals);
  check_points("occluder vertices", occluders.vertices);
  check_triangles("occluder triangles", occluders.triangles, occluders.vertices.size(), "occluder vertices");
  if (vertices.size() > std::numeric_limits<unsigned>::max() ||
      occluders.vertices.size() > std::numeric_limits<unsigned>::max()) {
    throw std::invalid_argument("Embree indexes vertices with 32 bits: too many vertices");
  }

  // ---- the plan and the result arrays ----
  const std::size_t n = vertices.size();
  const std::vector<glm::dvec3> fibonacci = spherical_fibonacci(options.rays);
  Plan plan;
  plan.rays = options.rays;
  plan.seed = options.seed;
  plan.fibonacci = &fibonacci;
  plan.record_rays = options.record_rays;
  plan.common_rotation = options.common_rotation;
  plan.horizon = options.horizon;
  plan.basis_order = std::max({options.visibility_order, options.product_order, options.product_visibility_order,
                               options.transfer_order});
  RowMatrix basis;
  std::optional<EulerShRotation> turn;
  if (plan.basis_order >= 0) {
    basis.resize(options.rays, sh_count(plan.basis_order));
    for (int r = 0; r < options.rays; ++r) sh_basis(plan.basis_order, fibonacci[r], basis.row(r).data());
    plan.basis = &basis;
    turn.emplace(plan.basis_order);
    plan.turn = &*turn;
  }
  plan.visibility_order = options.visibility_order;
  plan.product_order = options.product_order;
  plan.product_visibility_order = options.product_visibility_order;
  plan.transfer_order = options.transfer_order;
  if (options.visibility_order >= 0) plan.visibility_count = sh_count(options.visibility_order);
  if (options.product_order >= 0) {
    plan.product_rows = sh_count(options.product_order);
    plan.product_cols = sh_count(options.product_visibility_order);
  }
  if (options.transfer_order >= 0) plan.transfer_count = sh_count(options.transfer_order);
  if (options.design_order >= 0) plan.design_degree = options.design_order + options.design_visibility_order;

  TransferBake bake;
  bake.vertex_count = n;
  bake.rays = options.rays;
  bake.seed = options.seed;
  bake.visibility_order = options.visibility_order;
  bake.product_order = options.product_order;
  bake.product_visibility_order = options.product_visibility_order;
  bake.transfer_order = options.transfer_order;
  bake.design_degree = plan.design_degree;
  bake.fallback_normals = std::move(fallback_normals);
  bake.normals = units;
  bake.ambient_occlusion.assign(n, 0.0);
  bake.visibility.assign(n * plan.visibility_count, 0.0);
  bake.product_matrices.assign(n * plan.product_rows * plan.product_cols, 0.0);
  bake.transfer.assign(n * plan.transfer_count, 0.0);
  if (plan.record_rays) bake.ray_visibility.assign(n * static_cast<std::size_t>(options.rays), 0);
  std::vector<SphericalDesign> designs(plan.design_degree >= 0 ? n : 0);
  const Outputs outputs{&bake, &designs};

  // ---- the scene and the ray origins: the first phase, reported as (0, 0) (TransferOptions::progress) ----
  ParallelOptions parallel(options.threads);
  parallel.cancel = options.cancel;
  if (options.progress) parallel.progress = [&](std::size_t, std::size_t) { return options.progress(0, 0); };
  const TracedScene traced(vertices, units, triangles, occluders, parallel, options.offset_origins);
  bake.ray_origins = traced.object_space_origins();
  bake.setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // ---- the workers; with a progress callback the calling thread only reports ----
  parallel.progress = options.progress;
  // Without designs, chunks of about kChunkRays rays (at most kChunk vertices) in index order keep a
  // cancel prompt for any ray count. With designs, a chunk is a group of the vertex walk, so that
  // each design can start from a neighbour's built by the same worker; the workers poll for a
  // cancel between vertices.
  VertexWalk walk;
  if (plan.design_degree >= 0) {
    walk = vertex_walk(n, triangles, options.warm_start_designs ? kDesignGroup : 1);
  } else {
    walk.group = std::clamp<std::size_t>(kChunkRays / options.rays, 1, kChunk);
  }
  const ParallelOutcome outcome = parallel_for(
      n, walk.group,
      [&, scratch = Scratch()](std::size_t begin, std::size_t end, const StopQuery& stopping) mutable {
        for (std::size_t i = begin; i < end && !stopping(); ++i) {
          const std::size_t v = walk.order.empty() ? i : walk.order[i];
          scratch.starts.clear();
          if (!walk.order.empty()) {
            for (std::size_t j = walk.first_source[i]; j < walk.first_source[i + 1]; ++j) {
              scratch.starts.push_back(&designs[walk.order[walk.sources[j]]]);
            }
          }
          if (!bake_vertex(traced.scene().scene(), plan, traced.origin(v), units[v], v, stopping, scratch, outputs)) return;
        }
      },
      parallel);
  if (!outcome.completed) {
    throw BakeCancelled("bake cancelled after " + std::to_string(outcome.done) + " of " + std::to_string(n) +
                        " vertices");
  }

  // ---- flatten the designs ----
  if (plan.design_degree >= 0) {
    bake.design_offsets.assign(n + 1, 0);
    bake.design_residuals.assign(n, 0.0);
    std::size_t total = 0;
    for (std::size_t v = 0; v < n; ++v) {
      total += designs[v].nodes.size();
      bake.design_offsets[v + 1] = static_cast<std::int64_t>(total);
      bake.design_residuals[v] = designs[v].residual;
    }
    bake.design_nodes.reserve(total);
    bake.design_weights.reserve(total);
    for (auto& d : designs) {
      bake.design_nodes.insert(bake.design_nodes.end(), d.nodes.begin(), d.nodes.end());
      bake.design_weights.insert(bake.design_weights.end(), d.weights.begin(), d.weights.end());
    }
  }
  bake.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return bake;
}

std::vector<double> bake_visibility(const std::vector<glm::dvec3>& vertices, const std::vector<glm::dvec3>& normals,
                                    const std::vector<Triangle>& triangles, int order, int rays, std::uint64_t seed,
                                    const OccluderMesh& occluders,
                                    std::function<bool(std::size_t, std::size_t)> progress) {
  check_order("visibility order", order, kMaxVisibilityOrder);
  TransferOptions options;
  options.rays = rays;
  options.seed = seed;
  options.visibility_order = order;
  options.progress = std::move(progress);
  return bake_transfer(vertices, normals, triangles, options, occluders).visibility;
}

}  // namespace sd
