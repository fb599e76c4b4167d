// Environments from pixel arrays (Environment::from_equirect_pixels / from_cube_pixels, the path
// of Blender's in-memory images) with hostile sizes and values, then what the add-on asks of
// them: the SH projection, a band-limited texture, the error measures, area averaging and a
// channel design. Every call must give finite results or a std::exception with a message.
#include "fuzz_values.h"
#include "sdlighting/channel_design.h"
#include "sdlighting/environment.h"
#include "sdlighting/environment_error.h"
#include "sdlighting/ringing.h"
#include "sdlighting/sh_projection.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace {

void expect_finite(const std::vector<double>& values, const char* what) {
  for (double v : values) {
    if (!std::isfinite(v)) sd::fuzz::contract_broken(what);
  }
}

// One of the queries on a map that loaded.
void query(FuzzedDataProvider& data, const sd::Environment& map) {
  switch (data.ConsumeIntegralInRange<int>(0, 5)) {
    case 0: expect_finite(sd::sh(map, sd::fuzz::hostile_order(data, 0, 4), 1), "an SH coefficient is not finite"); break;
    case 1: {
      const auto window = static_cast<sd::RingingWindow>(data.ConsumeIntegralInRange<int>(0, 2));
      const int order = sd::fuzz::hostile_order(data, 0, 6);
      const int width = sd::fuzz::hostile_order(data, 1, 16), height = sd::fuzz::hostile_order(data, 1, 8);
      for (float v : sd::band_limited(map, order, width, height, window)) {
        if (!std::isfinite(v)) sd::fuzz::contract_broken("a band-limited texel is not finite");
      }
      break;
    }
    case 2: {
      const double error = sd::lobe_filtered_error(map, sd::ZonalLobe::phong(data.ConsumeFloatingPointInRange(0.0, 1e4)),
                                                   sd::fuzz::hostile_order(data, 0, 8));
      if (!(error >= 0.0 && error <= 1.0 + 1e-9)) sd::fuzz::contract_broken("a lobe-filtered error outside [0, 1]");
      break;
    }
    case 3: {
      const double error =
          sd::low_frequency_error(map, sd::fuzz::hostile_order(data, 0, 8), data.ConsumeIntegralInRange(0, 3));
      if (!(error >= 0.0 && error <= 1.0 + 1e-9)) sd::fuzz::contract_broken("ε(s) outside [0, 1]");
      break;
    }
    case 4: {
      const int width = sd::fuzz::hostile_order(data, 1, 12), height = sd::fuzz::hostile_order(data, 1, 6);
      const sd::Environment smaller = map.area_averaged(width, data.ConsumeBool() ? width : height);
      const double before = map.mass(sd::kLuminance), after = smaller.mass(sd::kLuminance);
      if (!(std::abs(after - before) <= 1e-5 * before + 1e-300)) sd::fuzz::contract_broken("area averaging lost mass");
      break;
    }
    default: {
      const sd::SphericalDesign design =
          sd::channel_design(map, sd::fuzz::hostile_order(data, 0, 3), sd::fuzz::hostile_order(data, 0, 4));
      for (double w : design.weights) {
        if (!(w > 0.0 && std::isfinite(w))) sd::fuzz::contract_broken("a channel design weight is not positive");
      }
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  FuzzedDataProvider data(bytes, size);
  const bool cube = data.ConsumeBool();
  const int width = sd::fuzz::hostile_order(data, 1, 16);
  const int height = cube ? width : sd::fuzz::hostile_order(data, 1, 8);
  std::size_t count = 3 * static_cast<std::size_t>(std::max(width, 0)) * std::max(height, 0) * (cube ? 6 : 1);
  if (data.ConsumeIntegralInRange(0, 15) == 0) count = data.ConsumeIntegralInRange<std::size_t>(0, 64);  // wrong size
  std::vector<float> rgb(count);
  for (float& v : rgb) v = static_cast<float>(data.ConsumeIntegralInRange(0, 7) == 0 ? sd::fuzz::hostile_double(data, 1e3)
                                                                                     : std::abs(sd::fuzz::finite_double(data, 1e3)));
  try {
    const sd::Environment map =
        cube ? sd::Environment::from_cube_pixels(width, std::move(rgb)) : sd::Environment::from_equirect_pixels(width, height, std::move(rgb));
    for (int k = 0; k < 4 && data.remaining_bytes() > 0; ++k) query(data, map);
  } catch (const std::exception& error) {
    sd::fuzz::check_message(error);
  }
  return 0;
}
