// Per-vertex visibility and transfer precompute with Embree 3 (msd-notes: eq. (1), PRT (2) and
// (8)-(9), Theorem 2.2).
//
// For every vertex p with unit normal n, R rays x_1 .. x_R cover the WHOLE sphere (rays into the
// surface are blocked by the surface itself) and start at an origin q next to p in free space
// (off the walls at concave edges, above a floor the object stands on: src/bake/traced_scene.h), tnear
// = 0, tfar = ∞. V_r = 1 when
// ray r escapes the scene, else 0. The scene is one Embree scene of the object's triangles plus
// optional occluder triangles (two-sided, float32, RTC_SCENE_FLAG_ROBUST, high build quality),
// traced in blocks of each vertex's rays (Embree 3's streams; one call per ray on Embree 4). The directions are a spherical Fibonacci set of R points (an equal-weight rule, weights 1/R) turned
// by a uniformly random rotation drawn per vertex from splitmix64 seeded with
// splitmix64_mix(seed) ⊕ vertex index, so results depend on (seed, vertex) only: deterministic
// and independent of the thread count. With dμ = dx/4π and the SH y_lm of spherical_harmonics.h:
//
//   ambient occlusion  AO  = (1/R) Σ_r V_r                      (= Ṽ_00, the fraction of escaping rays)
//   visibility         Ṽ_lm = (1/R) Σ_r V_r y_lm(x_r),                          l  <= s'
//   product matrix     M_{lm,l'm'} = (1/R) Σ_r V_r y_lm(x_r) y_l'm'(x_r),        l <= s, l' <= s'
//   diffuse transfer   T_lm = (1/R) Σ_r V_r 4 max(0, n·x_r) y_lm(x_r),           l <= s   (PRT (2))
//   design             sd::weighted_design({x_r : V_r = 1}, 1/R each, s + s')     (Theorem 2.2)
//
// The sums run over the unturned Fibonacci set, whose y_lm are evaluated once per bake, and are then
// turned with the vertex's rotation R (y(R x) = D(R) y(x): EulerShRotation, sh_rotation.h).
//
// The design is a positive rule for the discrete measure of V: Σ_ν λ_ν f(x_ν) = (1/R) Σ_r V_r f(x_r)
// for every polynomial f of degree <= s + s', its weights summing to AO. A vertex none of whose rays
// escapes gets an EMPTY design (0 nodes): its B of (13) is 0. Each design is refitted from an
// earlier neighbour's in the same group of the bake's vertex walk (src/bake/vertex_walk.h) where
// that certifies, so a design depends on the mesh's connectivity as well — still not on the threads.
//
#pragma once

#include "sdlighting/limits.h"
#include "sdlighting/mesh.h"

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <vector>

namespace sd {

/// Thrown by a bake stopped through its progress callback or cancel flag. Nothing is returned.
class BakeCancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What to bake. An order of -1 (the default) means "not requested"; AO is always computed.
struct TransferOptions {
  int rays = 1024;          ///< R >= 1 rays per vertex
  std::uint64_t seed = 0;   ///< seeds the per-vertex rotations of the Fibonacci set
  int visibility_order = -1;  ///< s' of Ṽ, in [0, kMaxVisibilityOrder]
  int product_order = -1;     ///< s of M (rows), in [0, kMaxTransferOrder]; needs product_visibility_order
  int product_visibility_order = -1;  ///< s' of M (columns), in [0, kMaxVisibilityOrder]
  int transfer_order = -1;    ///< s of T, in [0, kMaxTransferOrder]
  int design_order = -1;             ///< s of the design (degree s + s'), in [0, kMaxTransferOrder]
  int design_visibility_order = -1;  ///< s' of the design, in [0, kMaxVisibilityOrder]
  int threads = 0;            ///< worker threads; 0 = every hardware thread
  bool record_rays = false;   ///< test hook: keep every V_r in TransferBake::ray_visibility
  /// Every vertex traces vertex 0's rotation of the ray set (common random numbers): where two
  /// vertices' visibility and normals agree, so do their results, and a difference between
  /// vertices measures how the signal changes, not ray noise. For comparing neighbouring points
  /// (the add-on's refinement, bake/refine.py); a bake to store keeps independent rotations.
  bool common_rotation = false;
  /// Refit each vertex's design from an already-built neighbour's (weighted_design's `starts`)
  /// instead of compressing every one from scratch: the same certification at a fraction of the
  /// time. false is the benchmarks' baseline. Either way the result depends on the mesh, the
  /// options and the seed only, not on the thread count.
  bool warm_start_designs = true;
  /// false: every vertex's rays start at p + ηn as a vertex without faces' do (traced_scene.h:
  /// a fixed fraction of the bounding-box diagonal, above float rounding), which is how origins
  /// were chosen before they moved into the faces. For measuring what that move gains (blender_tests/benchmark_refine.py);
  /// a bake to store keeps true.
  bool offset_origins = true;
  /// true: rays below the vertex's horizon (n·x <= 0) are not traced and count as blocked. The
  /// transfer T is the same (its cosine weight is 0 there) for about half the rays; ambient
  /// occlusion, V~, M and the designs become those of a surface closed below, so a bake that
  /// stores only T (PRT eq. 2) is the one to use it.
  bool horizon = false;
  /// Called from the calling thread only (which then bakes no vertex itself), about every 50 ms:
  /// with (0, 0) while the scene and the ray origins are built, then once before the first vertex,
  /// every 50 ms and once more after the last with (vertices done, vertex count) - the first call
  /// with the count is where the rays' time starts (plan/bake_time.py bounds a bake's time from
  /// it). Returning false cancels the bake (BakeCancelled). An exception it throws cancels the
  /// bake and propagates once the workers have stopped.
  std::function<bool(std::size_t done, std::size_t total)> progress;
  /// Polled by the workers before every few vertices and by the calling thread; true cancels the
  /// bake (BakeCancelled).
  const std::atomic<bool>* cancel = nullptr;
};

/// Results of bake_transfer; arrays are per vertex, row-major, empty when not requested.
struct TransferBake {
  std::size_t vertex_count = 0;
  /// Vertices whose normal was zero or not finite, in increasing order: they were baked with the
  /// area-weighted normal of their faces (+Z without faces) instead of failing the bake.
  std::vector<std::int64_t> fallback_normals;
  /// [N] the unit normals the vertices were baked with (the fallbacks above included), for the
  /// caller to store with the results.
  std::vector<glm::dvec3> normals;
  int rays = 0;
  std::uint64_t seed = 0;
  std::vector<glm::dvec3> ray_origins;  ///< [N] where each vertex's rays start, object space
  double seconds = 0.0;  ///< wall time of the whole bake (scene build included)
  /// Of `seconds`, the part before the rays: the checks, the Embree scene of the object and its
  /// occluders, which faces bound a solid, the ray origins. A bake of a few vertices against a
  /// large mesh spends nearly all its time here (the add-on's bake-time prediction).
  double setup_seconds = 0.0;

  std::vector<double> ambient_occlusion;  ///< [N]

  int visibility_order = -1;
  std::vector<double> visibility;  ///< [N][(s'+1)²]

  int product_order = -1, product_visibility_order = -1;
  std::vector<double> product_matrices;  ///< [N][(s+1)²][(s'+1)²]

  int transfer_order = -1;
  std::vector<double> transfer;  ///< [N][(s+1)²]

  int design_degree = -1;  ///< s + s', or -1
  /// Vertex i's design is nodes/weights [design_offsets[i], design_offsets[i+1]); empty when no
  /// ray of the vertex escapes.
  std::vector<std::int64_t> design_offsets;  ///< [N+1]
  std::vector<glm::dvec3> design_nodes;
  std::vector<double> design_weights;
  std::vector<double> design_residuals;  ///< [N] certified moment residual / mass (0 when empty)

  std::vector<std::uint8_t> ray_visibility;  ///< [N][R] V_r, only with record_rays
};

/// Bakes the requested outputs for every vertex of a triangle mesh.
///
/// vertices/normals: N >= 1 finite points and their normals (normalised here; a zero or non-finite
/// normal gets a fallback from the vertex's faces, listed in TransferBake::fallback_normals).
/// triangles: indices into vertices (may be empty: the vertices are then probes; degenerate
/// triangles are fine). occluders: extra blocking triangles, indices into occluders.vertices.
/// Throws std::invalid_argument on bad input (NaN/inf positions, index out of range, orders out
/// of range, rays < 1, no vertices) and, before allocating, when the results and the workers'
/// matrices would exceed kMaxCallBytes, BakeCancelled when cancelled, std::runtime_error naming the
/// vertex when its design cannot be certified or Embree fails. Runs options.threads workers over
/// chunks of vertices (parallel_for); with a progress callback the calling thread only reports.
/// Results are returned only on success.
TransferBake bake_transfer(const std::vector<glm::dvec3>& vertices, const std::vector<glm::dvec3>& normals,
                           const std::vector<Triangle>& triangles, const TransferOptions& options,
                           const OccluderMesh& occluders = {});

/// Ṽ of order `order` for every vertex ([N][(order+1)²]): bake_transfer with only the visibility
/// requested.
std::vector<double> bake_visibility(const std::vector<glm::dvec3>& vertices, const std::vector<glm::dvec3>& normals,
                                    const std::vector<Triangle>& triangles, int order, int rays,
                                    std::uint64_t seed = 0, const OccluderMesh& occluders = {},
                                    std::function<bool(std::size_t, std::size_t)> progress = {});


/// The spherical Fibonacci set of `count` points: z_i = 1 − (2i+1)/count, azimuth 2π frac(i φ⁻¹)
/// (φ the golden ratio), an equal-weight rule for dμ.
std::vector<glm::dvec3> spherical_fibonacci(int count);

/// The uniformly random rotation of `vertex`'s ray set (Shoemake's quaternion from splitmix64).
glm::dmat3 vertex_ray_rotation(std::uint64_t seed, std::size_t vertex);

/// The R ray directions of `vertex`: vertex_ray_rotation(seed, vertex) × spherical_fibonacci(rays),
/// in the order of TransferBake::ray_visibility.
std::vector<glm::dvec3> vertex_ray_directions(int rays, std::uint64_t seed, std::size_t vertex);

}  // namespace sd
