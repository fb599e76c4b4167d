// Throughput of the visibility bake (sdlighting/visibility.h), measured in one run:
//   - rays/s of bake_transfer (visibility order 2 only) against raw Embree on the SAME rays in a tight
//     loop: rtcOccluded1, and the stream (rtcOccluded1M, what the bake uses) and packet variants; the
//     ratio against the raw stream is our overhead;
//   - the 2-thread against 1-thread speedup of the bake;
//   - the per-vertex cost of the design output at s + s' = 6.
// The mesh is a bumpy icosphere (real self-occlusion) standing above a ground quad (an occluder).
// Usage: visibility_benchmarks [icosphere levels = 4] [rays = 1024] [repeats = 3] [design = 1]
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/visibility.h"
#include "sdtesting/meshes.h"

#include <embree3/rtcore.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {

using sd::Triangle;
using sd::test::Mesh;

double seconds_best(int repeats, const std::function<void()>& run) {
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    run();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

// The bake's scene, rebuilt here with the same flags, for the raw loops.
struct RawScene {
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = nullptr;
  RawScene(const Mesh& m, const sd::OccluderMesh& occ) {
    scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    add(m.vertices, m.triangles);
    add(occ.vertices, occ.triangles);
    rtcCommitScene(scene);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw std::runtime_error("Embree error");
  }
  ~RawScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
  void add(const std::vector<glm::dvec3>& v, const std::vector<Triangle>& t) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), v.size()));
    auto* ib = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), t.size()));
    for (size_t i = 0; i < v.size(); ++i)
      for (int k = 0; k < 3; ++k) vb[3 * i + k] = static_cast<float>(v[i][k]);
    for (size_t i = 0; i < t.size(); ++i)
      for (int k = 0; k < 3; ++k) ib[3 * i + k] = static_cast<unsigned>(t[i][k]);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
  }
};

// One occlusion ray in float32 from origin o along direction d, as the raw loops hand Embree.
RTCRay raw_ray(const float* o, const float* d) {
  RTCRay ray{};
  ray.org_x = o[0];
  ray.org_y = o[1];
  ray.org_z = o[2];
  ray.dir_x = d[0];
  ray.dir_y = d[1];
  ray.dir_z = d[2];
  ray.tnear = 0.0f;
  ray.tfar = std::numeric_limits<float>::infinity();
  ray.mask = 0xFFFFFFFFu;
  return ray;
}

// Origins and directions of every ray of the bake, as the floats Embree gets.
struct Rays {
  int per_vertex = 0;
  std::vector<float> origins;     // [N][3]
  std::vector<float> directions;  // [N][R][3]
};

Rays bake_rays(const Mesh& m, const sd::OccluderMesh& occ, int rays, std::uint64_t seed) {
  Rays r;
  r.per_vertex = rays;
  sd::TransferOptions one_ray;  // the bake's own ray origins
  one_ray.rays = 1;
  const std::vector<glm::dvec3> origins = sd::bake_transfer(m.vertices, m.normals, m.triangles, one_ray, occ).ray_origins;
  const auto base = sd::spherical_fibonacci(rays);
  for (size_t v = 0; v < m.vertices.size(); ++v) {
    for (int k = 0; k < 3; ++k) r.origins.push_back(static_cast<float>(origins[v][k]));
    const glm::dmat3 rotation = sd::vertex_ray_rotation(seed, v);
    for (const auto& b : base) {
      const glm::dvec3 x = rotation * b;
      for (int k = 0; k < 3; ++k) r.directions.push_back(static_cast<float>(x[k]));
    }
  }
  return r;
}

size_t raw_occluded1(RTCScene scene, const Rays& rays) {
  size_t escaped = 0;
  const size_t n = rays.origins.size() / 3;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (size_t v = 0; v < n; ++v) {
    const float* o = &rays.origins[3 * v];
    const float* d = &rays.directions[3 * v * rays.per_vertex];
    for (int i = 0; i < rays.per_vertex; ++i) {
      RTCRay ray = raw_ray(o, d + 3 * i);
      rtcOccluded1(scene, &context, &ray);
      escaped += ray.tfar >= 0.0f;
    }
  }
  return escaped;
}

// rtcOccluded1M over blocks of at most `block` rays of one vertex.
size_t raw_stream(RTCScene scene, const Rays& rays, int block, bool coherent) {
  size_t escaped = 0;
  const size_t n = rays.origins.size() / 3;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  if (coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  std::vector<RTCRay> batch(block);
  for (size_t v = 0; v < n; ++v) {
    const float* o = &rays.origins[3 * v];
    const float* d0 = &rays.directions[3 * v * rays.per_vertex];
    for (int start = 0; start < rays.per_vertex; start += block) {
    const int count = std::min(block, rays.per_vertex - start);
    const float* d = d0 + 3 * start;
    for (int i = 0; i < count; ++i) {
      batch[i] = raw_ray(o, d + 3 * i);
    }
    rtcOccluded1M(scene, &context, batch.data(), static_cast<unsigned>(count), sizeof(RTCRay));
    for (int i = 0; i < count; ++i) escaped += batch[i].tfar >= 0.0f;
    }
  }
  return escaped;
}

template <int W, typename Packet, typename Fn>
size_t raw_packets(RTCScene scene, const Rays& rays, Fn occluded) {
  size_t escaped = 0;
  const size_t n = rays.origins.size() / 3;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  Packet p;
  int valid[W];
  for (size_t v = 0; v < n; ++v) {
    const float* o = &rays.origins[3 * v];
    const float* d = &rays.directions[3 * v * rays.per_vertex];
    for (int start = 0; start < rays.per_vertex; start += W) {
      for (int j = 0; j < W; ++j) {
        const int i = start + j;
        valid[j] = i < rays.per_vertex ? -1 : 0;
        p.org_x[j] = o[0];
        p.org_y[j] = o[1];
        p.org_z[j] = o[2];
        p.tnear[j] = 0.0f;
        p.dir_x[j] = i < rays.per_vertex ? d[3 * i] : 0.0f;
        p.dir_y[j] = i < rays.per_vertex ? d[3 * i + 1] : 0.0f;
        p.dir_z[j] = i < rays.per_vertex ? d[3 * i + 2] : 1.0f;
        p.time[j] = 0.0f;
        p.tfar[j] = std::numeric_limits<float>::infinity();
        p.mask[j] = 0xFFFFFFFFu;
        p.id[j] = 0;
        p.flags[j] = 0;
      }
      occluded(valid, scene, &context, &p);
      for (int j = 0; j < W; ++j) escaped += valid[j] && p.tfar[j] >= 0.0f;
    }
  }
  return escaped;
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const int levels = argc > 1 ? std::stoi(argv[1]) : 4;
  const int ray_count = argc > 2 ? std::stoi(argv[2]) : 1024;
  const int repeats = argc > 3 ? std::stoi(argv[3]) : 3;
  const bool with_design = argc > 4 ? std::stoi(argv[4]) != 0 : true;
  const std::uint64_t seed = 1;

  const Mesh mesh = sd::test::bumpy_sphere(levels);
  const sd::OccluderMesh ground = sd::test::ground_quad(4.0, -1.3);
  const size_t n = mesh.vertices.size();
  const double total_rays = static_cast<double>(n) * ray_count;
  std::printf("mesh: bumpy icosphere, %zu vertices, %zu triangles + ground quad; %d rays per vertex (%.3g rays)\n",
              n, mesh.triangles.size(), ray_count, total_rays);
  std::printf("hardware threads: %u\n\n", std::thread::hardware_concurrency());

  auto bake = [&](int threads, int design_s, int design_sv, int visibility_order = 2) {
    sd::TransferOptions options;
    options.rays = ray_count;
    options.seed = seed;
    options.visibility_order = visibility_order;
    options.design_order = design_s;
    options.design_visibility_order = design_sv;
    options.threads = threads;
    return sd::bake_transfer(mesh.vertices, mesh.normals, mesh.triangles, options, ground);
  };

  // ---- raw Embree on the same rays ----
  const Rays rays = bake_rays(mesh, ground, ray_count, seed);
  RawScene raw(mesh, ground);
  size_t escaped1 = 0, escaped_stream = 0, escaped8 = 0, escaped16 = 0;
  const double t_raw1 = seconds_best(repeats, [&] { escaped1 = raw_occluded1(raw.scene, rays); });
  const double t_stream = seconds_best(repeats, [&] { escaped_stream = raw_stream(raw.scene, rays, 1024, false); });
  const double t_stream64 = seconds_best(repeats, [&] { raw_stream(raw.scene, rays, 64, false); });
  const double t_stream_coherent = seconds_best(repeats, [&] { raw_stream(raw.scene, rays, 1024, true); });
  const double t_raw8 = seconds_best(repeats, [&] {
    escaped8 = raw_packets<8, RTCRay8>(raw.scene, rays, [](const int* valid, RTCScene s, RTCIntersectContext* c,
                                                           RTCRay8* p) { rtcOccluded8(valid, s, c, p); });
  });
  const double t_raw16 = seconds_best(repeats, [&] {
    escaped16 = raw_packets<16, RTCRay16>(raw.scene, rays, [](const int* valid, RTCScene s, RTCIntersectContext* c,
                                                              RTCRay16* p) { rtcOccluded16(valid, s, c, p); });
  });

  // ---- the bake, visibility order 2 only ----
  sd::TransferBake one, two;
  const double t_bake1 = seconds_best(repeats, [&] { one = bake(1, -1, -1); });
  const double t_bake2 = seconds_best(repeats, [&] { two = bake(2, -1, -1); });
  const double t_bake_ao = seconds_best(repeats, [&] { bake(1, -1, -1, -1); });
  double ao_sum = 0.0;
  for (double ao : one.ambient_occlusion) ao_sum += ao;
  const auto bake_escaped = static_cast<size_t>(std::llround(ao_sum * ray_count));

  std::printf("%-44s %10s %12s %8s\n", "variant (1 thread unless noted)", "seconds", "Mrays/s", "vs raw1");
  auto row = [&](const char* name, double t) {
    std::printf("%-44s %10.4f %12.2f %8.3f\n", name, t, total_rays / t * 1e-6, t_raw1 / t);
  };
  row("raw Embree rtcOccluded1, tight loop", t_raw1);
  row("raw Embree rtcOccluded1M, blocks of 1024", t_stream);
  row("raw Embree rtcOccluded1M, blocks of 64", t_stream64);
  row("raw Embree rtcOccluded1M, 1024, COHERENT flag", t_stream_coherent);
  row("raw Embree rtcOccluded8 packets", t_raw8);
  row("raw Embree rtcOccluded16 packets", t_raw16);
  row("bake_transfer, visibility order 2, 1 thread", t_bake1);
  row("bake_transfer, visibility order 2, 2 threads", t_bake2);
  row("bake_transfer, AO only, 1 thread", t_bake_ao);
  std::printf("\nescaping rays: raw1 %zu, stream %zu, packet8 %zu, packet16 %zu, bake %zu (mean AO %.4f)\n", escaped1,
              escaped_stream, escaped8, escaped16, bake_escaped, ao_sum / n);
  std::printf("bake (1 thread) / raw rtcOccluded1 throughput ratio: %.3f   (bake wall time includes the BVH build)\n",
              t_raw1 / t_bake1);
  std::printf("bake (1 thread) / raw rtcOccluded1M (what the bake calls) ratio: %.3f\n", t_stream / t_bake1);
  std::printf("bake 2-thread / 1-thread speedup: %.3f\n", t_bake1 / t_bake2);
  if (one.visibility != two.visibility) std::printf("WARNING: 1- and 2-thread results differ\n");

  // ---- T alone (PRT eq. 2, s = 6): every ray, or only those above each vertex's horizon ----
  auto transfer = [&](bool horizon) {
    sd::TransferOptions options;
    options.rays = ray_count;
    options.seed = seed;
    options.transfer_order = 6;
    options.horizon = horizon;
    return sd::bake_transfer(mesh.vertices, mesh.normals, mesh.triangles, options, ground);
  };
  sd::TransferBake every, above;
  const double t_every = seconds_best(repeats, [&] { every = transfer(false); });
  const double t_above = seconds_best(repeats, [&] { above = transfer(true); });
  double largest = 0.0, difference = 0.0;
  for (std::size_t i = 0; i < every.transfer.size(); ++i) {
    largest = std::max(largest, std::abs(every.transfer[i]));
    difference = std::max(difference, std::abs(every.transfer[i] - above.transfer[i]));
  }
  std::printf("\nT alone (s = 6), 2 threads: every ray %.3f s, above the horizon %.3f s, speedup %.3f; "
              "max |difference| / max |T| %.1e\n", t_every, t_above, t_every / t_above, difference / largest);

  if (!with_design) return 0;
  // ---- the design output at s + s' = 6 ----
  sd::TransferBake design1, design2;
  const int design_repeats = std::max(1, repeats / 2);
  const double t_design1 = seconds_best(design_repeats, [&] { design1 = bake(1, 4, 2); });
  const double t_design2 = seconds_best(design_repeats, [&] { design2 = bake(2, 4, 2); });
  const double nodes = static_cast<double>(design1.design_nodes.size()) / n;
  std::printf("\ndesign of degree 6 (s = 4, s' = 2) per vertex, %d rays:\n", ray_count);
  std::printf("  1 thread : bake %.3f s, design cost %.1f us per vertex (bake with design − bake without)\n", t_design1,
              (t_design1 - t_bake1) / n * 1e6);
  std::printf("  2 threads: bake %.3f s, %.1f us per vertex wall; speedup %.3f\n", t_design2, t_design2 / n * 1e6,
              t_design1 / t_design2);
  std::printf("  mean nodes per vertex %.2f (lower bound 16, at most 49)\n", nodes);
  if (design1.design_nodes != design2.design_nodes) std::printf("WARNING: 1- and 2-thread designs differ\n");
  return 0;
}
