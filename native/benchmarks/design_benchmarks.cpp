// Cost of the per-vertex visibility designs of Theorem 2.2 in a bake, measured in one run: for each
// degree s + s' (s' = 2), the design time per vertex on one thread — the process CPU time of a bake
// with designs minus that of the same bake without, so that other jobs on a shared machine do not
// inflate it — with every design compressed from scratch (today's builder, the fallback)
// and refitted from a neighbour's (TransferOptions::warm_start_designs), their ratio, node counts
// and the largest certified residual.
//
//   design_benchmarks [rays=1024] [max_degree=10] [sphere_levels=3] [max_cold_degree=10] [min_degree=4]
//
// The mesh is a bumpy icosphere standing on a ground quad (real self-shadowing, every vertex's
// visibility different). Degrees above max_cold_degree run warm only: from scratch they take
// seconds per vertex.
#include "sdlighting/visibility.h"
#include "sdtesting/meshes.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>

namespace {

struct Run {
  double seconds = 0.0;
  double mean_nodes = 0.0;
  long max_nodes = 0;
  double max_residual = 0.0;
};

Run bake(const sd::test::Mesh& mesh, const sd::OccluderMesh& ground, int rays, int degree, bool warm) {
  sd::TransferOptions options;
  options.rays = rays;
  options.threads = 1;
  options.warm_start_designs = warm;
  if (degree >= 0) {
    options.design_visibility_order = std::min(2, degree);
    options.design_order = degree - options.design_visibility_order;
  }
  const std::clock_t start = std::clock();
  const sd::TransferBake result = sd::bake_transfer(mesh.vertices, mesh.normals, mesh.triangles, options, ground);
  Run run;
  run.seconds = static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
  if (degree >= 0) {
    const std::size_t n = result.vertex_count;
    for (std::size_t v = 0; v < n; ++v) {
      const long count = static_cast<long>(result.design_offsets[v + 1] - result.design_offsets[v]);
      run.max_nodes = std::max(run.max_nodes, count);
      run.max_residual = std::max(run.max_residual, result.design_residuals[v]);
    }
    run.mean_nodes = static_cast<double>(result.design_nodes.size()) / static_cast<double>(n);
  }
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  const int rays = argc > 1 ? std::atoi(argv[1]) : 1024;
  const int max_degree = argc > 2 ? std::atoi(argv[2]) : 10;
  const int levels = argc > 3 ? std::atoi(argv[3]) : 3;
  const int max_cold_degree = argc > 4 ? std::atoi(argv[4]) : 10;
  const sd::test::Mesh mesh = sd::test::bumpy_sphere(levels);
  const sd::OccluderMesh ground = sd::test::ground_quad(4.0, -1.3);
  const double n = static_cast<double>(mesh.vertices.size());
  std::printf("bumpy sphere on a ground quad: %zu vertices, %d rays per vertex, 1 thread, s' = 2, CPU time\n\n",
              mesh.vertices.size(), rays);
  std::printf("%6s | %12s %9s %5s | %12s %9s %5s | %7s | %s\n", "degree", "scratch ms/v", "nodes", "max",
              "warm ms/v", "nodes", "max", "speedup", "largest residual (scratch, warm)");
  const int min_degree = argc > 5 ? std::atoi(argv[5]) : 4;
  for (int degree = min_degree; degree <= max_degree; ++degree) {
    const double base = bake(mesh, ground, rays, -1, false).seconds;
    const Run warm = bake(mesh, ground, rays, degree, true);
    const double warm_ms = (warm.seconds - base) / n * 1e3;
    if (degree <= max_cold_degree) {
      const Run cold = bake(mesh, ground, rays, degree, false);
      const double cold_ms = (cold.seconds - base) / n * 1e3;
      std::printf("%6d | %12.3f %9.2f %5ld | %12.3f %9.2f %5ld | %6.1fx | %.1e, %.1e\n", degree, cold_ms,
                  cold.mean_nodes, cold.max_nodes, warm_ms, warm.mean_nodes, warm.max_nodes, cold_ms / warm_ms,
                  cold.max_residual, warm.max_residual);
    } else {
      std::printf("%6d | %12s %9s %5s | %12.3f %9.2f %5ld | %7s | -, %.1e\n", degree, "-", "-", "-", warm_ms,
                  warm.mean_nodes, warm.max_nodes, "-", warm.max_residual);
    }
  }
  return 0;
}
