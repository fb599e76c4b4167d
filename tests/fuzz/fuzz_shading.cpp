// The shading evaluators (shading.h) on coefficient, normal, view, visibility, transfer and
// design arrays decoded from the bytes: sizes as the contract states them (the evaluators take
// raw pointers; the bindings check shapes and finiteness and normalise normals and views), values
// finite but otherwise arbitrary, orders now and then out of range, Phong σ anywhere (out of
// [0, 10⁴] too). Every call must give finite radiance or a std::exception with a message.
#include "fuzz_values.h"
#include "sdlighting/shading.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/zonal_design.h"

#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

namespace {

std::vector<double> finite_array(FuzzedDataProvider& data, std::size_t count, double scale) {
  std::vector<double> out(count);
  for (double& v : out) v = sd::fuzz::finite_double(data, scale);
  return out;
}

// Lobe designs of MSD (12), built once per (σ, degree): the Gauss product rule, a valid design
// that costs microseconds (the gradient search takes seconds under the sanitizers).
const sd::SphericalDesign& lobe_design(const sd::Material& material, int degree) {
  static std::map<std::pair<double, int>, sd::SphericalDesign> designs;
  const auto key = std::make_pair(material.glossy ? material.exponent : -1.0, degree);
  auto found = designs.find(key);
  if (found == designs.end()) {
    found = designs.emplace(key, sd::zonal_design(sd::ZonalWeight::from_lobe(material.lobe()), degree, sd::DesignMethod::Gauss)).first;
  }
  return found->second;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  FuzzedDataProvider data(bytes, size);
  const int s = sd::fuzz::hostile_order(data, 0, 4), s_v = sd::fuzz::hostile_order(data, 0, 2);
  const std::size_t vertices = data.ConsumeIntegralInRange<std::size_t>(0, 8);
  // σ from a small set (the lobe designs are cached by it) or, for the evaluators without a lobe
  // design, anywhere in [0, 1e4] including out of range.
  const int method = data.ConsumeIntegralInRange(0, 6);
  double exponent = data.PickValueInArray({0.0, 1.0, 7.5, 32.0, 1e4});
  if (method != 5) exponent = sd::fuzz::hostile_double(data, 1e4);
  const sd::Material material = data.ConsumeBool() ? sd::Material::lambert() : sd::Material{true, exponent};
  const int k = sd::sh_count(std::max(s, 0)), kv = sd::sh_count(std::max(s_v, 0));
  const auto light = finite_array(data, 3 * k, 1e3);
  std::vector<double> normals, views;  // unit, as the contract says (the bindings normalise them)
  for (std::size_t p = 0; p < vertices; ++p) {
    for (auto* field : {&normals, &views}) {
      const glm::dvec3 d = sd::fuzz::unit_vec3(data);
      field->insert(field->end(), {d.x, d.y, d.z});
    }
  }
  sd::ShadingInputs in;
  in.light_order = s;
  in.light = light.data();
  in.vertex_count = vertices;
  in.normals = normals.data();
  in.view_dirs = views.data();
  in.material = material;
  std::vector<double> out(3 * vertices);
  try {
    switch (method) {
      case 0: sd::shade_unshadowed(in, out.data()); break;
      case 1: sd::shade_ambient_occlusion(in, finite_array(data, vertices, 1.0).data(), out.data()); break;
      case 2: sd::shade_prt_diffuse(in, finite_array(data, vertices * k, 1.0).data(), out.data()); break;
      case 3: sd::shade_prt_matrix(in, s_v, finite_array(data, vertices * k * kv, 1.0).data(), out.data()); break;
      case 4: sd::shade_prt_gaunt(in, s_v, finite_array(data, vertices * kv, 1.0).data(), out.data()); break;
      case 5: {
        const auto visibility = finite_array(data, vertices * kv, 1.0);
        const int degree = sd::fuzz::hostile_order(data, 0, 6);
        sd::shade_msd_lobe(in, s_v, visibility.data(), lobe_design(material, degree), out.data());
        break;
      }
      default: {
        std::vector<std::int64_t> offsets = {0};
        std::vector<double> nodes, weights;
        for (std::size_t p = 0; p < vertices; ++p) {
          const std::size_t count = data.ConsumeIntegralInRange<std::size_t>(0, 6);
          for (std::size_t nu = 0; nu < count; ++nu) {
            const glm::dvec3 x = sd::fuzz::unit_vec3(data);
            nodes.insert(nodes.end(), {x.x, x.y, x.z});
            weights.push_back(data.ConsumeFloatingPointInRange(0.0, 1.0));
          }
          offsets.push_back(static_cast<std::int64_t>(weights.size()));
        }
        sd::shade_msd_visibility(in, s_v, sd::VertexDesigns{offsets.data(), nodes.data(), weights.data()},
                                 out.data());
        break;
      }
    }
    for (double v : out) {
      if (!std::isfinite(v)) sd::fuzz::contract_broken("a shaded value is not finite");
    }
  } catch (const std::exception& error) {
    sd::fuzz::check_message(error);
  }
  return 0;
}
