// bake_transfer on meshes decoded from the bytes — vertices and normals with NaN, inf, zero and
// huge values, triangles with indices out of range, occluders, every output order (now and then
// out of range), cancelled now and then — with few rays on one or two threads. Every input must
// give finite outputs with AO in [0, 1] = Ṽ_00 and certified designs, or a std::exception with a
// message (BakeCancelled included).
#include "fuzz_values.h"
#include "sdlighting/spherical_design.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/visibility.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace {

void expect_finite(const std::vector<double>& values, const char* what) {
  for (double v : values) {
    if (!std::isfinite(v)) sd::fuzz::contract_broken(what);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  FuzzedDataProvider data(bytes, size);
  const double scale = std::pow(10.0, data.ConsumeIntegralInRange(-4, 4));
  const bool hostile = data.ConsumeIntegralInRange(0, 3) == 0;  // NaN/inf positions now and then
  const std::size_t vertex_count = data.ConsumeIntegralInRange<std::size_t>(hostile ? 0 : 1, 12);
  const std::size_t triangle_count = data.ConsumeIntegralInRange<std::size_t>(0, 16);
  sd::TransferOptions options;
  options.rays = sd::fuzz::hostile_order(data, 1, 48);
  options.seed = data.ConsumeIntegral<std::uint64_t>();
  options.threads = data.ConsumeIntegralInRange(1, 2);
  // Now and then a progress callback that cancels at its k-th call (k = 1: before any vertex).
  const int cancel_at = data.ConsumeIntegralInRange(0, 7) == 0 ? data.ConsumeIntegralInRange(1, 3) : 0;
  int progress_calls = 0;
  if (cancel_at > 0) options.progress = [&](std::size_t, std::size_t) { return ++progress_calls < cancel_at; };
  if (data.ConsumeBool()) options.visibility_order = sd::fuzz::hostile_order(data, 0, 3);
  if (data.ConsumeBool()) {
    options.product_order = sd::fuzz::hostile_order(data, 0, 3);
    options.product_visibility_order = sd::fuzz::hostile_order(data, 0, 2);
  }
  if (data.ConsumeBool()) options.transfer_order = sd::fuzz::hostile_order(data, 0, 3);
  if (data.ConsumeBool()) {
    options.design_order = sd::fuzz::hostile_order(data, 0, 2);
    options.design_visibility_order = sd::fuzz::hostile_order(data, 0, 2);
  }
  options.warm_start_designs = data.ConsumeBool();
  const auto vertices = sd::fuzz::points(data, vertex_count, scale, !hostile);
  std::vector<glm::dvec3> normals(vertex_count);
  for (auto& n : normals) n = sd::fuzz::hostile_vec3(data);
  const auto faces = sd::fuzz::triangles(data, triangle_count, vertex_count);
  sd::OccluderMesh occluders;
  if (data.ConsumeBool()) {
    occluders.vertices = sd::fuzz::points(data, data.ConsumeIntegralInRange<std::size_t>(0, 6), scale, !hostile);
    occluders.triangles = sd::fuzz::triangles(data, data.ConsumeIntegralInRange<std::size_t>(0, 6), occluders.vertices.size());
  }
  try {
    const sd::TransferBake bake = sd::bake_transfer(vertices, normals, faces, options, occluders);
    if (bake.vertex_count != vertex_count || bake.ambient_occlusion.size() != vertex_count) {
      sd::fuzz::contract_broken("a bake of the wrong size");
    }
    for (std::size_t p = 0; p < vertex_count; ++p) {
      const double ao = bake.ambient_occlusion[p];
      if (!(ao >= 0.0 && ao <= 1.0)) sd::fuzz::contract_broken("AO outside [0, 1]");
      if (bake.visibility_order >= 0 &&
          std::abs(bake.visibility[p * sd::sh_count(bake.visibility_order)] - ao) > 1e-12) {
        sd::fuzz::contract_broken("Ṽ_00 differs from AO");
      }
    }
    for (const auto& o : bake.ray_origins) {
      if (!std::isfinite(o.x) || !std::isfinite(o.y) || !std::isfinite(o.z)) sd::fuzz::contract_broken("a ray origin is not finite");
    }
    expect_finite(bake.visibility, "Ṽ is not finite");
    expect_finite(bake.product_matrices, "M is not finite");
    expect_finite(bake.transfer, "T is not finite");
    expect_finite(bake.design_weights, "a design weight is not finite");
    for (double r : bake.design_residuals) {
      if (!(r <= sd::kDesignTolerance)) sd::fuzz::contract_broken("a design is not certified");
    }
    for (double w : bake.design_weights) {
      if (!(w > 0.0)) sd::fuzz::contract_broken("a design weight is not positive");
    }
    if (bake.design_degree >= 0) {
      for (std::size_t p = 0; p < vertex_count; ++p) {  // a design's weights sum to its vertex's AO
        double mass = 0.0;
        for (auto nu = bake.design_offsets[p]; nu < bake.design_offsets[p + 1]; ++nu) mass += bake.design_weights[nu];
        if (std::abs(mass - bake.ambient_occlusion[p]) > 1e-9) sd::fuzz::contract_broken("a design's mass is not AO");
      }
    }
  } catch (const std::exception& error) {
    sd::fuzz::check_message(error);
  }
  return 0;
}
