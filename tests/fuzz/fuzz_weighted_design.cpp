// weighted_design on directions and weights decoded from the bytes (NaN, inf, zero and
// denormal directions and weights, 1e-300..1e300 scales, degrees now and then out of range),
// refitted from its own result for changed weights as the bake's vertex walk does, and
// zonal_design for a Phong lobe of any σ in [0, 10⁴]. Every input must give a certified design
// (positive weights summing to the mass, residual within kDesignTolerance) or a std::exception
// with a message.
#include "fuzz_values.h"
#include "sdlighting/weighted_design.h"
#include "sdlighting/zonal_design.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace {

void expect_certified(const sd::SphericalDesign& design, double mass) {
  if (design.nodes.size() != design.weights.size()) sd::fuzz::contract_broken("nodes and weights differ in number");
  double sum = 0.0;
  for (std::size_t nu = 0; nu < design.weights.size(); ++nu) {
    const auto& x = design.nodes[nu];
    if (!(std::abs(x.x * x.x + x.y * x.y + x.z * x.z - 1.0) < 1e-9)) sd::fuzz::contract_broken("a node is not unit");
    if (!(design.weights[nu] > 0.0) || !std::isfinite(design.weights[nu])) {
      sd::fuzz::contract_broken("a weight is not positive");
    }
    sum += design.weights[nu];
  }
  if (!(design.residual <= sd::kDesignTolerance)) sd::fuzz::contract_broken("the residual is above the tolerance");
  if (!(std::abs(sum - mass) <= 1e-8 * mass)) sd::fuzz::contract_broken("the weights do not sum to the mass");
}

void weighted(FuzzedDataProvider& data) {
  const std::size_t count = data.ConsumeIntegralInRange<std::size_t>(0, 96);
  const int degree = sd::fuzz::hostile_order(data, 0, 5);
  const double scale = std::pow(10.0, data.ConsumeIntegralInRange(-300, 300));
  const bool hostile = data.ConsumeIntegralInRange(0, 3) == 0;
  std::vector<glm::dvec3> dirs(count);
  std::vector<double> weights(count);
  for (std::size_t i = 0; i < count; ++i) {
    dirs[i] = hostile ? sd::fuzz::hostile_vec3(data) : sd::fuzz::unit_vec3(data);
    weights[i] = hostile ? sd::fuzz::hostile_double(data, scale) : scale * data.ConsumeFloatingPointInRange(0.0, 1.0);
  }
  double mass = 0.0;
  for (double w : weights) mass += w;
  const sd::SphericalDesign design = sd::weighted_design(dirs, weights, degree);
  expect_certified(design, mass);
  // The vertex walk's refit: the same directions, some weights changed.
  for (double& w : weights) {
    if (data.ConsumeIntegralInRange(0, 3) == 0) w *= data.ConsumeFloatingPointInRange(0.0, 2.0);
  }
  mass = 0.0;
  for (double w : weights) mass += w;
  // Starts as the bake passes them: the neighbour's design, and null ones (skipped: the clustered
  // start) before or after it.
  std::vector<const sd::SphericalDesign*> starts{&design};
  if (data.ConsumeBool()) starts.insert(starts.begin(), nullptr);
  if (data.ConsumeBool()) starts.push_back(nullptr);
  if (data.ConsumeBool()) starts = {nullptr};
  expect_certified(sd::weighted_design(dirs, weights, degree, starts), mass);
}

void zonal(FuzzedDataProvider& data) {
  const double exponent = data.ConsumeIntegralInRange(0, 7) == 0 ? sd::fuzz::hostile_double(data, 1e4)
                                                                   : data.ConsumeFloatingPointInRange(0.0, 1e4);
  // Degree <= 5: the gradient search takes up to a second at degree 7 in Release and twenty times
  // that under the sanitizers, over the 10 s an input may take.
  const int degree = sd::fuzz::hostile_order(data, 0, 4);
  const auto method = static_cast<sd::DesignMethod>(data.ConsumeIntegralInRange(0, 2));
  const sd::ZonalLobe lobe = sd::ZonalLobe::phong(exponent);
  for (double w : lobe.coefficients(degree < 0 ? 0 : degree)) {
    if (!(std::abs(w) <= 1.0)) sd::fuzz::contract_broken("a Funk-Hecke factor above 1 in magnitude");
  }
  expect_certified(sd::zonal_design(sd::ZonalWeight::from_lobe(lobe), degree, method), 1.0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  FuzzedDataProvider data(bytes, size);
  try {
    if (data.ConsumeIntegralInRange(0, 3) == 0) {
      zonal(data);
    } else {
      weighted(data);
    }
  } catch (const std::exception& error) {
    sd::fuzz::check_message(error);
  }
  return 0;
}
