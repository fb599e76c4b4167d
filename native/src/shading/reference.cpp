#include "sdlighting/reference.h"

#include "sdlighting/environment_sampler.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/visibility.h"

#include "bake/traced_scene.h"
#include "util/orthonormal_basis.h"
#include "util/parallel_for.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace sd {

ReferenceResult shade_reference(const Environment& environment, const glm::dmat3& rotation,
                                const std::vector<glm::dvec3>& vertices, const std::vector<glm::dvec3>& normals,
                                const std::vector<glm::dvec3>& views, const std::vector<Triangle>& triangles,
                                const Material& material, const ReferenceOptions& options,
                                const OccluderMesh& occluders) {
  if (options.samples < 1) throw std::invalid_argument("samples must be >= 1");
  if (normals.size() != vertices.size()) throw std::invalid_argument("normals must match vertices");
  if (material.glossy && views.size() != vertices.size()) throw std::invalid_argument("a glossy material needs one view per vertex");
  check_points("vertices", vertices);
  check_triangles("triangles", triangles, vertices.size(), "vertices");
  const std::vector<glm::dvec3> unit = unit_normals(normals, vertices, triangles);  // the bake's fallbacks
  check_points("occluder vertices", occluders.vertices);
  check_triangles("occluder triangles", occluders.triangles, occluders.vertices.size(), "occluder vertices");
  const ZonalLobe lobe = material.lobe();
  // A matrix that is no rotation, or a zero or non-finite view, made every value NaN or silently
  // wrong (found by tests/fuzz/fuzz_reference): refused here, as the bindings refuse them.
  const glm::dmat3 g = proper_rotation(rotation);
  if (material.glossy) {
    for (size_t p = 0; p < views.size(); ++p) {
      const double length = glm::length(views[p]);
      if (!std::isfinite(length) || !(length > 0.0)) {
        throw std::invalid_argument("view " + std::to_string(p) + " is zero or not finite");
      }
    }
  }

  ParallelOptions parallel(options.threads);
  parallel.cancel = options.cancel;
  if (options.progress) parallel.progress = [&](std::size_t, std::size_t) { return options.progress(0, 0); };
  const TracedScene traced(vertices, unit, triangles, occluders, parallel);  // the bake's origins
  parallel.progress = options.progress;
  const EnvironmentSampler sampler(environment);
  // The integrand reads L at g x (rotated_sh, sh_rotation.h, states the convention); a direction y
  // drawn from the map is therefore the object-space direction x = gᵀ y.
  const glm::dmat3 g_inverse = glm::transpose(g);

  ReferenceResult result;
  result.samples = options.samples;
  result.radiance.assign(3 * vertices.size(), 0.0);
  result.standard_error.assign(3 * vertices.size(), 0.0);
  const ParallelOutcome outcome = parallel_for(vertices.size(), 4, [&](size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p) {
      std::mt19937_64 rng(options.seed * 0x9e3779b97f4a7c15ULL + p);
      std::uniform_real_distribution<double> uniform(0.0, 1.0);
      const glm::dvec3 n = unit[p];
      double axis[3];
      const glm::dvec3 v = material.glossy ? glm::normalize(views[p]) : n;
      lobe_axis(material, &n.x, &v.x, axis);
      const glm::dvec3 a = glm::normalize(glm::dvec3(axis[0], axis[1], axis[2]));
      glm::dvec3 t1, t2;
      orthonormal_basis(a, t1, t2);
      const glm::dvec3& origin = traced.origin(p);
      // f(x)/(pdf_env + pdf_lobe) for a direction x in object space; L is looked up at g x.
      auto balanced = [&](const glm::dvec3& x) {
        const double w = lobe.value(glm::dot(a, x));
        const glm::dvec3 y = g * x;
        const double pdf = sampler.pdf(y) + w;
        if (w <= 0.0 || pdf <= 0.0 || (options.horizon && glm::dot(n, x) <= 0.0) ||
            traced.scene().occluded(origin, x)) {
          return glm::dvec3(0.0);
        }
        return environment.radiance(y) * (w / pdf);
      };
      glm::dvec3 sum(0.0), sum_squares(0.0);
      for (int i = 0; i < options.samples; ++i) {
        const glm::dvec3 from_environment = g_inverse * sampler.sample(uniform(rng), uniform(rng));
        // The lobe's t has density (σ+1) t^σ on [0, 1]; 1 − t by expm1 keeps grazing precision.
        const double one_minus_t = -std::expm1(std::log(1.0 - uniform(rng)) / (lobe.exponent + 1.0));
        const double t = 1.0 - one_minus_t, r = std::sqrt(std::max(0.0, one_minus_t * (1.0 + t)));
        const double phi = 2.0 * M_PI * uniform(rng);
        const glm::dvec3 from_lobe = r * std::cos(phi) * t1 + r * std::sin(phi) * t2 + t * a;
        const glm::dvec3 estimate = balanced(from_environment) + balanced(from_lobe);
        sum += estimate;
        sum_squares += estimate * estimate;
      }
      const double count = options.samples;
      const glm::dvec3 mean = sum / count;
      const glm::dvec3 variance = glm::max(sum_squares / count - mean * mean, glm::dvec3(0.0)) / std::max(count - 1.0, 1.0);
      for (int c = 0; c < 3; ++c) {
        result.radiance[3 * p + c] = mean[c];
        result.standard_error[3 * p + c] = std::sqrt(variance[c]);
      }
    }
  }, parallel);
  if (!outcome.completed) {
    throw BakeCancelled("reference cancelled after " + std::to_string(outcome.done) + " of " +
                        std::to_string(vertices.size()) + " vertices");
  }
  return result;
}

}  // namespace sd
