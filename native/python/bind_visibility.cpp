// Bindings of the visibility / transfer precompute (sdlighting/visibility.h): bake_transfer,
// bake_visibility, the ray-direction hook and the BakeCancelled exception; the sides of the faces
// to bake (sdlighting/face_sides.h); and the least-squares vertex fit of baked values
// (sdlighting/vertex_fit.h).
//
// Arrays are checked here (shapes, dtypes, finiteness) so that bad input raises ValueError naming the
// argument; the library's std::invalid_argument surfaces as ValueError too. The bake runs without
// the GIL; the progress callback is called with the GIL re-acquired, from the calling thread only.
#include "array_checks.h"
#include "mesh_arrays.h"
#include "progress.h"
#include "bindings.h"
#include "sdlighting/face_sides.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/vertex_fit.h"
#include "sdlighting/visibility.h"
#include "sdlighting/weighted_design.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sdpy {
namespace {

using IndexPair = std::optional<std::pair<int, int>>;

// Moves a vector into a numpy array that owns it (no copy).
template <typename T>
py::array adopt(std::vector<T>&& values, std::vector<py::ssize_t> shape, const py::dtype& dtype = py::dtype::of<T>()) {
  auto* heap = new std::vector<T>(std::move(values));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array(dtype, std::move(shape), {}, heap->data(), owner);
}

// An (s, s') pair of orders: None leaves both -1 (not requested); a pair must hold two valid orders.
void read_order_pair(const char* name, const IndexPair& pair, int& s, int& s_prime) {
  if (!pair) return;
  s = pair->first;
  s_prime = pair->second;
  check_order(std::string(name) + " s", s, sd::kMaxTransferOrder);
  check_order(std::string(name) + " s'", s_prime, sd::kMaxVisibilityOrder);
}

sd::TransferBake run_bake(const DoubleArray& vertices, const DoubleArray& normals, const py::object& triangles,
                          sd::TransferOptions options, const std::optional<DoubleArray>& occluder_vertices,
                          const py::object& occluder_triangles, const py::object& progress) {
  if (options.threads < 0) {
    value_error("threads must be >= 0 (0: every hardware thread), got " + std::to_string(options.threads));
  }
  const std::vector<glm::dvec3> v = read_points("vertices", vertices);
  if (v.empty()) value_error("vertices is empty: the mesh needs at least one vertex");
  const std::vector<glm::dvec3> n = read_points("normals", normals, false);
  if (n.size() != v.size()) {
    value_error("normals must have shape (" + std::to_string(v.size()) + ", 3) to match vertices, got " +
                shape_string(normals));
  }
  const std::vector<sd::Triangle> t = read_triangles("triangles", triangles);
  const sd::OccluderMesh occluders = read_occluders(occluder_vertices, occluder_triangles);
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) value_error("progress must be callable or None");
  options.progress = progress_function(&progress);
  py::gil_scoped_release release;
  return sd::bake_transfer(v, n, t, options, occluders);
}

py::dict bake_dict(sd::TransferBake&& bake, bool return_rays) {
  const auto n = static_cast<py::ssize_t>(bake.vertex_count);
  py::dict out;
  out["ambient_occlusion"] = adopt(std::move(bake.ambient_occlusion), {n});
  if (bake.visibility_order >= 0) {
    out["visibility"] = adopt(std::move(bake.visibility), {n, py::ssize_t(sd::sh_count(bake.visibility_order))});
  }
  if (bake.product_order >= 0) {
    out["product_matrices"] =
        adopt(std::move(bake.product_matrices), {n, py::ssize_t(sd::sh_count(bake.product_order)),
                                                 py::ssize_t(sd::sh_count(bake.product_visibility_order))});
  }
  if (bake.transfer_order >= 0) {
    out["transfer"] = adopt(std::move(bake.transfer), {n, py::ssize_t(sd::sh_count(bake.transfer_order))});
  }
  if (bake.design_degree >= 0) {
    const auto total = static_cast<py::ssize_t>(bake.design_nodes.size());
    out["design_offsets"] = adopt(std::move(bake.design_offsets), {n + 1});
    out["design_nodes"] = points_array(bake.design_nodes);
    out["design_weights"] = adopt(std::move(bake.design_weights), {total});
    out["design_residuals"] = adopt(std::move(bake.design_residuals), {n});
    out["design_degree"] = bake.design_degree;
  }
  if (return_rays) {
    out["ray_visibility"] =
        adopt(std::move(bake.ray_visibility), {n, py::ssize_t(bake.rays)}, py::dtype("bool"));
  }
  const auto repaired = static_cast<py::ssize_t>(bake.fallback_normals.size());
  out["fallback_normals"] = adopt(std::move(bake.fallback_normals), {repaired});
  out["normals"] = points_array(bake.normals);
  out["rays"] = bake.rays;
  out["seed"] = bake.seed;
  out["ray_origins"] = points_array(bake.ray_origins);
  out["seconds"] = bake.seconds;
  out["setup_seconds"] = bake.setup_seconds;
  return out;
}

py::dict py_bake_transfer(const DoubleArray& vertices, const DoubleArray& normals, const py::object& triangles,
                          int rays, std::uint64_t seed, int visibility_order, const IndexPair& product_orders,
                          int transfer_order, const IndexPair& design_orders,
                          const std::optional<DoubleArray>& occluder_vertices, const py::object& occluder_triangles,
                          const py::object& progress, int threads, bool return_rays, bool common_rotation,
                          bool offset_origins, bool horizon) {
  sd::TransferOptions options;
  options.rays = rays;
  options.seed = seed;
  options.visibility_order = visibility_order;
  read_order_pair("product_orders", product_orders, options.product_order, options.product_visibility_order);
  options.transfer_order = transfer_order;
  read_order_pair("design_orders", design_orders, options.design_order, options.design_visibility_order);
  options.threads = threads;
  options.record_rays = return_rays;
  options.common_rotation = common_rotation;
  options.offset_origins = offset_origins;
  options.horizon = horizon;
  return bake_dict(run_bake(vertices, normals, triangles, options, occluder_vertices, occluder_triangles, progress),
                   return_rays);
}

py::array py_bake_visibility(const DoubleArray& vertices, const DoubleArray& normals, const py::object& triangles,
                             int order, int rays, std::uint64_t seed,
                             const std::optional<DoubleArray>& occluder_vertices,
                             const py::object& occluder_triangles, const py::object& progress, int threads) {
  check_order("order", order, sd::kMaxVisibilityOrder);
  sd::TransferOptions options;
  options.rays = rays;
  options.seed = seed;
  options.visibility_order = order;
  options.threads = threads;
  sd::TransferBake bake =
      run_bake(vertices, normals, triangles, options, occluder_vertices, occluder_triangles, progress);
  const auto n = static_cast<py::ssize_t>(bake.vertex_count);
  return adopt(std::move(bake.visibility), {n, py::ssize_t(sd::sh_count(order))});
}

py::array py_face_sides(const DoubleArray& vertices, const py::object& triangles,
                        const std::optional<DoubleArray>& occluder_vertices, const py::object& occluder_triangles,
                        const py::object& progress, int threads) {
  if (threads < 0) value_error("threads must be >= 0 (0: every hardware thread), got " + std::to_string(threads));
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) value_error("progress must be callable or None");
  const std::vector<glm::dvec3> v = read_points("vertices", vertices);
  const std::vector<sd::Triangle> t = read_triangles("triangles", triangles);
  const sd::OccluderMesh occluders = read_occluders(occluder_vertices, occluder_triangles);
  sd::FaceSidesOptions options;
  options.threads = threads;
  options.progress = progress_function(&progress);
  std::vector<sd::FaceSides> sides;
  {
    py::gil_scoped_release release;
    sides = sd::face_sides(v, t, occluders, options);
  }
  std::vector<std::uint8_t> codes(sides.size());
  for (std::size_t i = 0; i < sides.size(); ++i) codes[i] = static_cast<std::uint8_t>(sides[i]);
  return adopt(std::move(codes), {static_cast<py::ssize_t>(codes.size())});
}

py::array_t<double> py_vertex_ray_directions(int rays, std::uint64_t seed, py::ssize_t vertex) {
  check_range("rays", rays, 1, sd::kMaxRaysPerVertex);
  if (vertex < 0) value_error("vertex must be >= 0, got " + std::to_string(vertex));
  return points_array(sd::vertex_ray_directions(rays, seed, static_cast<size_t>(vertex)));
}

// Penalty rows from (R, 4) integer vertices and (R, 4) coefficients.
std::vector<sd::PenaltyRow> read_penalties(const py::object& vertices, const DoubleArray& coefficients) {
  using IndexArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const py::array a = py::array::ensure(vertices);
  if (!a || a.ndim() != 2 || a.shape(1) != 4 || (a.shape(0) > 0 && a.dtype().kind() != 'i' && a.dtype().kind() != 'u')) {
    value_error("penalty_vertices must be an integer array of shape (R, 4)");
  }
  if (coefficients.ndim() != 2 || coefficients.shape(0) != a.shape(0) || coefficients.shape(1) != 4) {
    value_error("penalty_coefficients must have shape (" + std::to_string(a.shape(0)) + ", 4), got " +
                shape_string(coefficients));
  }
  const IndexArray indices = IndexArray::ensure(a);
  std::vector<sd::PenaltyRow> rows(static_cast<size_t>(a.shape(0)));
  for (size_t r = 0; r < rows.size(); ++r) {
    for (int k = 0; k < 4; ++k) {
      rows[r].vertices[k] = indices.data()[4 * r + k];
      rows[r].coefficients[k] = coefficients.data()[4 * r + k];
    }
  }
  return rows;
}

py::array py_fit_vertex_values(std::int64_t vertex_count, const py::object& sample_triangles,
                               const DoubleArray& barycentric, const DoubleArray& weights, const DoubleArray& values,
                               const py::object& penalty_vertices, const DoubleArray& penalty_coefficients,
                               double smoothness, int threads, const py::object& progress) {
  if (vertex_count < 0) value_error("vertex_count must be >= 0, got " + std::to_string(vertex_count));
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) value_error("progress must be callable or None");
  sd::MeshSamples samples;
  samples.triangles = read_triangles("sample_triangles", sample_triangles);
  samples.barycentric = read_points("sample_barycentric", barycentric);
  const size_t count = samples.triangles.size();
  if (weights.ndim() != 1 || static_cast<size_t>(weights.shape(0)) != count) {
    value_error("sample_weights must have shape (" + std::to_string(count) + ",), got " + shape_string(weights));
  }
  samples.weights.assign(weights.data(), weights.data() + count);
  if (values.ndim() < 1 || static_cast<size_t>(values.shape(0)) != count) {
    value_error("values must have shape (" + std::to_string(count) + ", ...), got " + shape_string(values));
  }
  std::vector<py::ssize_t> shape(values.shape(), values.shape() + values.ndim());
  size_t channels = 1;
  for (size_t k = 1; k < shape.size(); ++k) channels *= static_cast<size_t>(shape[k]);
  const std::vector<sd::PenaltyRow> penalties = read_penalties(penalty_vertices, penalty_coefficients);
  std::vector<double> fitted;
  {
    py::gil_scoped_release release;   // `values` (a C-contiguous float64 array held by the caller) is read in place
    fitted = sd::fit_vertex_values(static_cast<size_t>(vertex_count), samples, values.data(), count * channels,
                                   channels, penalties, smoothness, threads, progress_function(&progress));
  }
  shape[0] = static_cast<py::ssize_t>(vertex_count);
  return adopt(std::move(fitted), std::move(shape));
}

}  // namespace

void bind_visibility(py::module_& m) {
  py::register_exception<sd::BakeCancelled>(m, "BakeCancelled", PyExc_RuntimeError);
  m.attr("BakeCancelled").attr("__doc__") =
      "Raised by bake_transfer / bake_visibility when the progress callback returns False (or the bake "
      "is otherwise cancelled). A subclass of RuntimeError; nothing is returned.";

  m.def("bake_transfer", &py_bake_transfer, py::arg("vertices"), py::arg("normals"), py::arg("triangles"),
        py::arg("rays"), py::arg("seed") = 0, py::arg("visibility_order") = -1,
        py::arg("product_orders") = py::none(), py::arg("transfer_order") = -1,
        py::arg("design_orders") = py::none(), py::arg("occluder_vertices") = py::none(),
        py::arg("occluder_triangles") = py::none(), py::arg("progress") = py::none(), py::arg("threads") = 0,
        py::arg("return_rays") = false, py::arg("common_rotation") = false, py::arg("offset_origins") = true,
        py::arg("horizon") = false,
        R"doc(Per-vertex visibility and transfer precompute with Embree (ray casting over the whole sphere).

For vertex p with unit normal n, `rays` rays x_r start at an origin q next to p in free space (off
the walls at concave edges, above a floor the object stands on; returned as "ray_origins") in the
directions of a spherical Fibonacci set turned by a random rotation drawn per vertex from the seed
(vertex_ray_directions gives them): deterministic, independent of the thread count. V_r = 1 if ray r
escapes the scene (the mesh's triangles plus the occluders; triangles are two-sided). With equal
weights 1/R and the module's real SH y_lm:
  ambient_occlusion  (1/R) sum_r V_r   (always returned)
  visibility         V~_lm = (1/R) sum_r V_r y_lm(x_r), l <= s' = visibility_order
  product_matrices   M[lm, l'm'] = (1/R) sum_r V_r y_lm(x_r) y_l'm'(x_r), l <= s, l' <= s'
                     for product_orders = (s, s')
  transfer           T_lm = (1/R) sum_r V_r 4 max(0, n.x_r) y_lm(x_r), l <= transfer_order (PRT eq. 2)
  design             per vertex, weighted_design(escaping directions, 1/R each, s + s') for
                     design_orders = (s, s') (Theorem 2.2): sum_v lambda_v f(x_v) equals
                     (1/R) sum_r V_r f(x_r) for every polynomial f of degree <= s + s'; the weights
                     sum to the vertex's ambient occlusion. A vertex whose rays are all blocked gets an
                     EMPTY design (0 nodes; its B is 0).

vertices: (N, 3) floats, N >= 1, finite.  normals: (N, 3) (normalised here); a zero or non-finite
    normal does not fail the bake: the vertex gets the area-weighted normal of its faces (+Z without
    faces), and its index is listed in "fallback_normals" so that the caller can warn.
triangles: (T, 3) integer indices into vertices (T may be 0: the vertices are then just probes).
rays: rays per vertex, in [1, MAX_RAYS_PER_VERTEX].  seed: non-negative int.
visibility_order: s' in [0, MAX_VISIBILITY_ORDER], or -1 (not requested).
product_orders, design_orders: None or (s, s') with s in [0, MAX_TRANSFER_ORDER], s' in
    [0, MAX_VISIBILITY_ORDER].  transfer_order: s in [0, MAX_TRANSFER_ORDER], or -1.
occluder_vertices (M, 3), occluder_triangles (K, 3): extra blocking geometry, both or neither.
progress: None or a callable progress(done, total) (vertex counts; (0, 0) while the scene is built,
    before any ray), called about every 50 ms and once at the end from the calling thread with the
    GIL held; returning False cancels the bake
    (BakeCancelled); an exception it raises cancels the bake and propagates. Ctrl-C cancels too.
threads: worker threads, 0 (default) = every hardware thread.
return_rays: test hook, adds "ray_visibility" (bool (N, rays), V_r in vertex_ray_directions order).
common_rotation: every vertex traces vertex 0's directions (common random numbers), so that
    differences between neighbouring vertices carry no ray noise where their visibility agrees
    (for comparing points, not for a bake to store).
offset_origins: False starts every vertex's rays as a vertex without faces does, a fixed fraction of
    the bounding-box diagonal along its normal, not off the walls (for measuring what the offset
    gains, not for a bake to store).
horizon: True traces only the rays above the vertex's horizon (n.x > 0); those below count as
    blocked. "transfer" is the same (its weight max(0, n.x) is 0 there) for about half the rays;
    the other arrays become those of a surface closed below (a bake that stores only T uses it).

Returns a dict: "ambient_occlusion" (N,); "visibility" (N, (s'+1)**2); "product_matrices"
(N, (s+1)**2, (s'+1)**2); "transfer" (N, (s+1)**2); "design_offsets" int64 (N+1,) (vertex i's nodes
are design_nodes[design_offsets[i]:design_offsets[i+1]]), "design_nodes" (total, 3),
"design_weights" (total,), "design_residuals" (N,) (certified moment residual / mass, 0 for an empty
design), "design_degree" (int); each only when requested; plus "rays", "seed", "ray_origins"
(N, 3) (where each vertex's rays start: about 1e-3 of the shortest edge around it away from p) and
"seconds" (wall time), "setup_seconds" (of it, the part before the rays: scene and origins), "fallback_normals" int64 (K,) (the vertices baked with a fallback normal) and
"normals" (N, 3) (the unit normals the vertices were baked with, fallbacks included).
Raises ValueError on bad input (and, before allocating, when the bake would need more than
MAX_CALL_BYTES), BakeCancelled when
cancelled, RuntimeError naming the vertex if a design cannot be certified. Releases the GIL.)doc");

  m.def("bake_visibility", &py_bake_visibility, py::arg("vertices"), py::arg("normals"), py::arg("triangles"),
        py::arg("order"), py::arg("rays"), py::arg("seed") = 0, py::arg("occluder_vertices") = py::none(),
        py::arg("occluder_triangles") = py::none(), py::arg("progress") = py::none(), py::arg("threads") = 0,
        R"doc(Visibility V~ of order `order` (s' in [0, MAX_VISIBILITY_ORDER]) for every vertex: the same
bake as bake_transfer(..., visibility_order=order)["visibility"], shape (N, (order+1)**2). Its
column 0 is the ambient occlusion. Arguments as for bake_transfer. Releases the GIL.)doc");

  m.def("face_sides", &py_face_sides, py::arg("vertices"), py::arg("triangles"),
        py::arg("occluder_vertices") = py::none(), py::arg("occluder_triangles") = py::none(),
        py::arg("progress") = py::none(), py::arg("threads") = 0,
        R"doc(What the baked copy needs of each triangle so that every side a viewer can see is baked
(sdlighting/face_sides.h), uint8 (T,): FACE_FRONT (as wound), FACE_FLIPPED (reverse it: its front is
inside the solid it bounds), FACE_BOTH (add a reverse copy: the back can be seen too) or FACE_SHEET
(its reverse is already a triangle of the mesh). Closed orientable pieces are told by their signed
volume; the back of any other face by FACE_SIDE_RAYS rays from just behind it, hidden when every one
meets a surface from behind. occluders: other surfaces that can hide a back. progress(done, total)
over the faces looked at, as bake_transfer's. Raises ValueError on bad input, BakeCancelled.
Releases the GIL.)doc");
  m.attr("FACE_FRONT") = static_cast<int>(sd::FaceSides::kFront);
  m.attr("FACE_FLIPPED") = static_cast<int>(sd::FaceSides::kFlipped);
  m.attr("FACE_BOTH") = static_cast<int>(sd::FaceSides::kBoth);
  m.attr("FACE_SHEET") = static_cast<int>(sd::FaceSides::kSheet);
  m.attr("FACE_SIDE_RAYS") = sd::kSideRays;

  m.def("fit_vertex_values", &py_fit_vertex_values, py::arg("vertex_count"), py::arg("sample_triangles"),
        py::arg("sample_barycentric"), py::arg("sample_weights"), py::arg("values"),
        py::arg("penalty_vertices"), py::arg("penalty_coefficients"), py::arg("smoothness") = 0.0,
        py::arg("threads") = 0, py::arg("progress") = py::none(),
        R"doc(Least-squares vertex values (Kavan, Bargteil and Sloan, "Least Squares Vertex Baking", 2011):
the per-vertex X whose linear interpolation best matches samples spread over the triangles,
    minimize  sum_s w_s |sum_k b_sk X[t_sk] - F_s|^2 + smoothness * d * sum_r |sum_k c_rk X[v_rk]|^2
with d the mean diagonal of the first term's normal matrix (so smoothness is relative) and r the
penalty rows (a regulariser: linear combinations of up to 4 vertices' values that should vanish),
solved by a sparse Cholesky factorization.

vertex_count: V >= 0.  sample_triangles: (S, 3) integer vertex indices of each sample's triangle
(a sample at a vertex: any triangle with barycentric coordinates (1, 0, 0)).
sample_barycentric: (S, 3) finite.  sample_weights: (S,) finite, >= 0 (the area each stands for).
values: (S, ...) finite: every trailing entry is a channel, fitted independently.
penalty_vertices: (R, 4) integer vertex indices, penalty_coefficients: (R, 4) finite (0: slot
unused).  smoothness: >= 0.
threads: for the channels' solves, 0 = every hardware thread.
progress: None or a callable progress(done, total) over the blocks of channels solved, as
    bake_transfer's (with none done before the factorization, which runs uninterrupted, and as the
    solves start);
    returning False raises BakeCancelled.
Returns (V, ...) float64. Raises ValueError on bad input, RuntimeError when a vertex (or a part of
the mesh) has no sample of positive weight to fix its value. Releases the GIL.)doc");

  m.def("vertex_ray_directions", &py_vertex_ray_directions, py::arg("rays"), py::arg("seed"), py::arg("vertex"),
        R"doc(The ray directions bake_transfer uses for vertex index `vertex` with this seed: a spherical
Fibonacci set of `rays` points (z_i = 1 - (2i+1)/rays, azimuth 2 pi frac(i / golden ratio)) turned by
the vertex's random rotation (Shoemake's uniform quaternion from splitmix64 seeded with
mix(seed) xor vertex). Returns (rays, 3) unit vectors, in the order of "ray_visibility".)doc");
}

}  // namespace sdpy
