// Bindings of the reference integrator of eq. (1) (sdlighting/reference.h): sdnative.reference.
#include "array_checks.h"
#include "bindings.h"
#include "mesh_arrays.h"
#include "progress.h"
#include "sdlighting/environment.h"
#include "sdlighting/reference.h"
#include "sdlighting/shading.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace sdpy {
namespace {

py::tuple reference(const sd::Environment& environment, const DoubleArray& vertices, const DoubleArray& normals,
                    const py::object& triangles, const std::optional<DoubleArray>& views,
                    const std::optional<DoubleArray>& rotation, const std::string& lobe, double exponent, int samples,
                    std::uint64_t seed, const std::optional<DoubleArray>& occluder_vertices,
                    const py::object& occluder_triangles, int threads, const py::object& progress, bool horizon) {
  const std::vector<glm::dvec3> points = read_points("vertices", vertices);
  const std::vector<glm::dvec3> normal_rows = read_points("normals", normals);
  const sd::Material material = sd::Material::from_name(lobe, exponent);
  std::vector<glm::dvec3> view_rows;
  if (material.glossy) {
    if (!views) value_error("a phong material needs views (unit vectors from the vertices to the eye)");
    view_rows = read_directions("views", *views, false);
  }
  const std::vector<sd::Triangle> mesh = read_triangles("triangles", triangles);
  const sd::OccluderMesh occluders = read_occluders(occluder_vertices, occluder_triangles);
  const glm::dmat3 g = rotation ? read_rotation(*rotation) : glm::dmat3(1.0);
  check_range("threads", threads, 0, 1024);
  sd::ReferenceOptions options;
  options.samples = samples;
  options.seed = seed;
  options.threads = threads;
  options.horizon = horizon;
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) value_error("progress must be callable or None");
  options.progress = progress_function(&progress);
  sd::ReferenceResult result;
  {
    py::gil_scoped_release release;
    result = sd::shade_reference(environment, g, points, normal_rows, view_rows, mesh, material, options, occluders);
  }
  const auto rows = static_cast<py::ssize_t>(points.size());
  py::array_t<double> radiance({rows, py::ssize_t{3}}), error({rows, py::ssize_t{3}});
  std::copy(result.radiance.begin(), result.radiance.end(), radiance.mutable_data());
  std::copy(result.standard_error.begin(), result.standard_error.end(), error.mutable_data());
  return py::make_tuple(radiance, error);
}

}  // namespace

void bind_reference(py::module_& m) {
  m.def("reference", &reference, py::arg("environment"), py::arg("vertices"), py::arg("normals"),
        py::arg("triangles"), py::arg("views") = py::none(), py::arg("rotation") = py::none(),
        py::arg("lobe") = "lambert", py::arg("exponent") = 1.0, py::arg("samples") = 4096, py::arg("seed") = 0,
        py::arg("occluder_vertices") = py::none(), py::arg("occluder_triangles") = py::none(),
        py::arg("threads") = 0, py::arg("progress") = py::none(), py::arg("horizon") = false,
        R"doc(The reference: eq. (1) by Monte Carlo with the full-resolution environment, ray-traced V and the
exact lobe — what every method is measured against.

environment: an Environment (environment_from_pixels); vertices, normals (N, 3); triangles (T, 3) int:
the object's mesh (it shadows itself); occluder_vertices/occluder_triangles: other blockers.
views (N, 3): unit vectors to the eye (phong only); rotation g (3, 3) as in shade().
samples: sample pairs per vertex, one from the environment (∝ luminance) and one from the lobe,
combined by the balance heuristic; seed makes it deterministic (independent of threads).
Returns (radiance, standard_error), both (N, 3): the estimate and its Monte Carlo standard
error. Rays start at the bake's ray origins. progress(done, total) over the vertices, as bake_transfer's
(False cancels: BakeCancelled). horizon: V is also 0 below each vertex's tangent plane (with no triangles:
the lobe over the hemisphere the surface faces, what the prefiltered glossy light stands for).
Releases the GIL.)doc");
}

}  // namespace sdpy
