// Every method against the reference (eq. (1) by Monte Carlo) on a real HDRI and a shadowed scene.
//
// A ground plane with a box standing over its centre, lit by Blender's sunset.exr: the methods that
// carry visibility (PRT (2), (8)-(9), (10), MSD (12), (13)) converge to the reference as s, s' and
// the rays grow; the ones that do not (unshadowed, ambient occlusion) stay far off, which is why the
// scene calls for visibility. On the same real data MSD equals PRT exactly: (12) = (10) and
// (13) = (8)-(9).
#include "sdlighting/environment.h"
#include "sdlighting/reference.h"
#include "sdlighting/sh_projection.h"
#include "sdlighting/shading.h"
#include "sdlighting/visibility.h"
#include "sdlighting/zonal_design.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace sd {
namespace {

const std::string kHdri = "/usr/share/blender/datafiles/studiolights/world/sunset.exr";

struct Level {
  int s, s_v, rays;
};
constexpr Level kLevels[] = {{2, 1, 256}, {4, 2, 1024}, {6, 3, 2048}};

// An n × n grid on [−1, 1]² in z = 0 (normals +z) under a box [−0.4, 0.4]² × [0.1, 0.9] (an occluder),
// seen from an eye at (3, −2, 2.5).
struct Scene {
  std::vector<glm::dvec3> vertices, normals, views;
  std::vector<Triangle> triangles;
  OccluderMesh box;
};

Scene plane_under_a_box(int n = 8) {
  Scene scene;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      scene.vertices.emplace_back(-1.0 + 2.0 * j / (n - 1), -1.0 + 2.0 * i / (n - 1), 0.0);
      scene.normals.emplace_back(0.0, 0.0, 1.0);
      scene.views.push_back(glm::normalize(glm::dvec3(3.0, -2.0, 2.5) - scene.vertices.back()));
    }
  }
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      const std::int64_t a = i * n + j;
      scene.triangles.push_back({a, a + 1, a + n + 1});
      scene.triangles.push_back({a, a + n + 1, a + n});
    }
  }
  for (double x : {-0.4, 0.4})
    for (double y : {-0.4, 0.4})
      for (double z : {0.1, 0.9}) scene.box.vertices.emplace_back(x, y, z);
  scene.box.triangles = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                         {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  return scene;
}

double relative_rms(const std::vector<double>& estimate, const std::vector<double>& reference) {
  double error = 0.0, norm = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    error += (estimate[i] - reference[i]) * (estimate[i] - reference[i]);
    norm += reference[i] * reference[i];
  }
  return std::sqrt(error / norm);
}

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

// B at every vertex by every method, for one level.
std::map<std::string, std::vector<double>> all_methods(const Environment& environment, const Scene& scene,
                                                       const Material& material, const Level& level) {
  TransferOptions options;
  options.rays = level.rays;
  options.seed = 1;
  options.visibility_order = level.s_v;
  options.product_order = options.design_order = level.s;
  options.product_visibility_order = options.design_visibility_order = level.s_v;
  options.transfer_order = level.s;
  const TransferBake bake = bake_transfer(scene.vertices, scene.normals, scene.triangles, options, scene.box);

  const std::vector<double> light = sh(environment, level.s);
  std::vector<double> normals, views;
  for (std::size_t p = 0; p < scene.vertices.size(); ++p) {
    normals.insert(normals.end(), {scene.normals[p].x, scene.normals[p].y, scene.normals[p].z});
    views.insert(views.end(), {scene.views[p].x, scene.views[p].y, scene.views[p].z});
  }
  ShadingInputs in;
  in.light_order = level.s;
  in.light = light.data();
  in.vertex_count = scene.vertices.size();
  in.normals = normals.data();
  in.view_dirs = views.data();
  in.material = material;

  std::vector<double> design_nodes;
  for (const glm::dvec3& x : bake.design_nodes) design_nodes.insert(design_nodes.end(), {x.x, x.y, x.z});
  const SphericalDesign lobe_design =
      zonal_design(ZonalWeight::from_lobe(material.lobe()), level.s + level.s_v);

  std::map<std::string, std::vector<double>> out;
  auto result = [&](const char* name) -> double* {
    out[name].assign(3 * scene.vertices.size(), 0.0);
    return out[name].data();
  };
  shade_unshadowed(in, result("unshadowed"));
  shade_ambient_occlusion(in, bake.ambient_occlusion.data(), result("ambient_occlusion"));
  shade_prt_matrix(in, level.s_v, bake.product_matrices.data(), result("prt_matrix"));
  shade_prt_gaunt(in, level.s_v, bake.visibility.data(), result("prt_gaunt"));
  shade_msd_lobe(in, level.s_v, bake.visibility.data(), lobe_design, result("msd_lobe"));
  shade_msd_visibility(in, level.s_v,
                       VertexDesigns{bake.design_offsets.data(), design_nodes.data(), bake.design_weights.data()},
                       result("msd_visibility"));
  if (!material.glossy) shade_prt_diffuse(in, bake.transfer.data(), result("prt_diffuse"));
  return out;
}

void expect_convergence(const Material& material, double final_error) {
  ASSERT_TRUE(std::filesystem::exists(kHdri))
      << kHdri << " is missing: install Debian's blender package (scripts/install_dependencies.sh)";
  const Environment environment = Environment::load(kHdri);
  const Scene scene = plane_under_a_box();
  ReferenceOptions options;
  options.samples = 8192;
  const ReferenceResult reference = shade_reference(environment, glm::dmat3(1.0), scene.vertices, scene.normals,
                                                    scene.views, scene.triangles, material, options, scene.box);
  std::vector<double> upper = reference.radiance;
  for (std::size_t i = 0; i < upper.size(); ++i) upper[i] += reference.standard_error[i];
  ASSERT_LT(relative_rms(upper, reference.radiance), 0.02) << "the reference itself is not converged";

  std::vector<std::map<std::string, double>> errors;
  for (const Level& level : kLevels) {
    const auto out = all_methods(environment, scene, material, level);
    // MSD is PRT computed another way: equal on real data, not only on random data.
    for (const auto& [msd, prt] : {std::pair<const char*, const char*>{"msd_lobe", "prt_gaunt"},
                                   std::pair<const char*, const char*>{"msd_visibility", "prt_matrix"}}) {
      const double tolerance = 1e-9 * max_abs(out.at(prt));
      for (std::size_t i = 0; i < out.at(prt).size(); ++i) ASSERT_NEAR(out.at(msd)[i], out.at(prt)[i], tolerance);
    }
    std::map<std::string, double> level_errors;
    for (const auto& [name, value] : out) level_errors[name] = relative_rms(value, reference.radiance);
    errors.push_back(level_errors);
  }
  for (const auto& [name, first] : errors.front()) {
    const double last = errors.back().at(name);
    if (name == "unshadowed" || name == "ambient_occlusion") {
      EXPECT_GT(last, 0.3) << name << " should miss the box's shadow";
    } else {
      EXPECT_LT(last, first) << name << " does not converge";
      EXPECT_LT(last, final_error) << name << " ends this far from the reference";
    }
  }
}

TEST(Convergence, LambertMethodsWithVisibilityConvergeToTheReference) {
  expect_convergence(Material::lambert(), 0.05);
}

TEST(Convergence, PhongMethodsWithVisibilityConvergeToTheReference) {
  expect_convergence(Material::phong(8.0), 0.2);
}

}  // namespace
}  // namespace sd
