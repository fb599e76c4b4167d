// Per-vertex cost of every shading formula on the CPU, measured in one run, with the ratios the
// seed argues about: MSD (12) against PRT (10), MSD (13) against PRT (8)-(9) (it claims about 4×).
// Usage: shading_benchmarks [vertices] [s] [s'] [phong exponent]
#include "sdlighting/gaunt.h"
#include "sdlighting/shading.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/weighted_design.h"
#include "sdlighting/zonal_design.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

// Best of `repeats` wall-clock runs, in nanoseconds per vertex.
double ns_per_vertex(size_t vertices, int repeats, const std::function<void()>& run) {
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    run();
    const auto t1 = std::chrono::steady_clock::now();
    best = std::min(best, std::chrono::duration<double, std::nano>(t1 - t0).count() / vertices);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const size_t n = argc > 1 ? std::stoul(argv[1]) : 20000;
  const int s = argc > 2 ? std::stoi(argv[2]) : 4;
  const int s_v = argc > 3 ? std::stoi(argv[3]) : 2;
  const double sigma = argc > 4 ? std::stod(argv[4]) : 32.0;
  const int k = sd::sh_count(s), kv = sd::sh_count(s_v), rays = 256;

  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal;
  auto random_unit = [&] { return glm::normalize(glm::dvec3(normal(rng), normal(rng), normal(rng))); };
  std::vector<double> light(3 * k), normals, views, visibility(n * kv), ao(n), transfer(n * k),
      matrices(n * size_t(k) * kv);
  for (double& v : light) v = normal(rng);
  for (size_t p = 0; p < n; ++p) {
    for (auto* field : {&normals, &views}) {
      const glm::dvec3 d = random_unit();
      field->insert(field->end(), {d.x, d.y, d.z});
    }
  }
  for (double& v : visibility) v = normal(rng);
  for (double& v : ao) v = 0.5;
  for (double& v : transfer) v = normal(rng);
  for (double& v : matrices) v = normal(rng);

  // Per-vertex designs of a V given by rays (a tilted half-space each, recycled over vertices).
  std::vector<int64_t> offsets = {0};
  std::vector<double> nodes, weights;
  std::vector<std::vector<double>> design_pool_nodes, design_pool_weights;
  for (int d = 0; d < 64; ++d) {
    const glm::dvec3 up = random_unit();
    std::vector<glm::dvec3> dirs;
    for (int r = 0; r < rays; ++r) {
      const glm::dvec3 x = random_unit();
      if (glm::dot(x, up) > -0.2) dirs.push_back(x);
    }
    const sd::SphericalDesign design = sd::weighted_design(dirs, std::vector<double>(dirs.size(), 1.0 / rays), s + s_v);
    std::vector<double> flat;
    for (const auto& x : design.nodes) flat.insert(flat.end(), {x.x, x.y, x.z});
    design_pool_nodes.push_back(flat);
    design_pool_weights.push_back(design.weights);
  }
  for (size_t p = 0; p < n; ++p) {
    const auto& pool_nodes = design_pool_nodes[p % 64];
    const auto& pool_weights = design_pool_weights[p % 64];
    nodes.insert(nodes.end(), pool_nodes.begin(), pool_nodes.end());
    weights.insert(weights.end(), pool_weights.begin(), pool_weights.end());
    offsets.push_back(static_cast<int64_t>(weights.size()));
  }

  std::vector<double> out(3 * n);
  std::printf("CPU shading, %zu vertices, s = %d, s' = %d, %u threads\n", n, s, s_v, std::thread::hardware_concurrency());
  std::printf("%-10s %-34s %12s %14s\n", "material", "formula", "ns/vertex", "terms/vertex");
  for (const sd::Material material : {sd::Material::lambert(), sd::Material::phong(sigma)}) {
    sd::ShadingInputs in;
    in.light_order = s;
    in.light = light.data();
    in.vertex_count = n;
    in.normals = normals.data();
    in.view_dirs = views.data();
    in.material = material;
    const sd::SphericalDesign lobe_design = sd::zonal_design(sd::ZonalWeight::from_lobe(material.lobe()), s + s_v);
    const size_t gaunt_terms = sd::gaunt_coefficients(s, s_v, s + s_v).size();
    const double mean_design = double(offsets.back()) / n;
    const std::string name = material.glossy ? "phong " + std::to_string(int(sigma)) : "lambert";
    auto row = [&](const char* formula, double ns, double terms) {
      std::printf("%-10s %-34s %12.1f %14.0f\n", name.c_str(), formula, ns, terms);
      return ns;
    };
    const int repeats = 5;
    row("unshadowed", ns_per_vertex(n, repeats, [&] { sd::shade_unshadowed(in, out.data()); }), k);
    row("ambient occlusion", ns_per_vertex(n, repeats, [&] { sd::shade_ambient_occlusion(in, ao.data(), out.data()); }), k);
    if (!material.glossy) {
      row("PRT (2) diffuse", ns_per_vertex(n, repeats, [&] { sd::shade_prt_diffuse(in, transfer.data(), out.data()); }), k);
    }
    const double prt8 = row("PRT (8)-(9) product matrix",
                            ns_per_vertex(n, repeats, [&] { sd::shade_prt_matrix(in, s_v, matrices.data(), out.data()); }),
                            double(k) * kv);
    const double prt10 = row("PRT (10) Gaunt",
                             ns_per_vertex(n, repeats, [&] { sd::shade_prt_gaunt(in, s_v, visibility.data(), out.data()); }),
                             double(gaunt_terms));
    const double msd12 = row("MSD (12) lobe design",
                             ns_per_vertex(n, repeats, [&] {
                               sd::shade_msd_lobe(in, s_v, visibility.data(), lobe_design, out.data());
                             }),
                             double(lobe_design.size()) * kv);
    const double msd13 = row("MSD (13) visibility designs",
                             ns_per_vertex(n, repeats, [&] {
                               sd::shade_msd_visibility(in, s_v, sd::VertexDesigns{offsets.data(), nodes.data(), weights.data()},
                                                        out.data());
                             }),
                             mean_design * (s_v + 1));
    std::printf("%-10s ratio PRT (10) / MSD (12) = %.2f   PRT (8) / MSD (13) = %.2f   (lobe design %d nodes, "
                "mean V design %.1f nodes)\n",
                name.c_str(), prt10 / msd12, prt8 / msd13, lobe_design.size(), mean_design);
  }
  return 0;
}
