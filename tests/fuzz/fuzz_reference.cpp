// shade_reference (eq. (1) by Monte Carlo, reference.h) on meshes, views, rotations, materials and
// small environment maps decoded from the bytes — NaN/inf positions, normals and views, indices
// out of range, rotation matrices that are not rotations, σ outside [0, 10⁴], black maps — with
// few samples on one or two threads. Every input must give finite radiance and standard errors
// or a std::exception with a message.
#include "fuzz_values.h"
#include "sdlighting/environment.h"
#include "sdlighting/reference.h"

#include <glm/mat3x3.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  FuzzedDataProvider data(bytes, size);
  const int width = data.ConsumeIntegralInRange(1, 8), height = data.ConsumeIntegralInRange(1, 4);
  std::vector<float> rgb(3 * width * height);
  for (float& v : rgb) v = static_cast<float>(std::abs(sd::fuzz::finite_double(data, data.ConsumeBool() ? 1.0 : 1e4)));
  const bool hostile = data.ConsumeIntegralInRange(0, 3) == 0;
  const std::size_t vertex_count = data.ConsumeIntegralInRange<std::size_t>(hostile ? 0 : 1, 8);
  const auto vertices = sd::fuzz::points(data, vertex_count, 1.0, !hostile);
  std::vector<glm::dvec3> normals(vertex_count), views(vertex_count);
  for (auto& n : normals) n = hostile ? sd::fuzz::hostile_vec3(data) : sd::fuzz::unit_vec3(data);
  for (auto& v : views) v = hostile ? sd::fuzz::hostile_vec3(data) : sd::fuzz::unit_vec3(data);
  const auto faces = sd::fuzz::triangles(data, data.ConsumeIntegralInRange<std::size_t>(0, 12), vertex_count);
  glm::dmat3 rotation(1.0);
  if (data.ConsumeIntegralInRange(0, 3) == 0) {
    for (int col = 0; col < 3; ++col)
      for (int row = 0; row < 3; ++row) rotation[col][row] = sd::fuzz::hostile_double(data);
  }
  const sd::Material material = data.ConsumeBool() ? sd::Material::lambert()
                                                   : sd::Material{true, data.ConsumeIntegralInRange(0, 7) == 0
                                                                            ? sd::fuzz::hostile_double(data, 1e4)
                                                                            : data.ConsumeFloatingPointInRange(0.0, 1e4)};
  sd::ReferenceOptions options;
  options.samples = sd::fuzz::hostile_order(data, 1, 32);
  options.seed = data.ConsumeIntegral<std::uint64_t>();
  options.threads = data.ConsumeIntegralInRange(1, 2);
  try {
    const sd::Environment map = sd::Environment::from_equirect_pixels(width, height, std::move(rgb));
    const sd::ReferenceResult result =
        sd::shade_reference(map, rotation, vertices, normals, views, faces, material, options);
    if (result.radiance.size() != 3 * vertex_count) sd::fuzz::contract_broken("a result of the wrong size");
    for (double v : result.radiance) {
      if (!std::isfinite(v) || v < 0.0) sd::fuzz::contract_broken("a reference radiance is negative or not finite");
    }
    for (double e : result.standard_error) {
      if (!std::isfinite(e) || e < 0.0) sd::fuzz::contract_broken("a standard error is negative or not finite");
    }
  } catch (const std::exception& error) {
    sd::fuzz::check_message(error);
  }
  return 0;
}
