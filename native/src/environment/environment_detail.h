// What the files of environment maps share: the lazily computed high-order projection, the row
// evaluator of SH expansions and the channel check. Private to the environment files.
#pragma once

#include "sdlighting/environment.h"

#include <array>
#include <functional>
#include <mutex>
#include <vector>

namespace sd {

/// A map's reference projection (band_energies, sh_projection.h): computed once, shared by copies.
struct ReferenceProjection {
  std::mutex mutex;
  bool ready = false;
  std::vector<double> coefficients;     // order kMaxEnergyOrder, RGB interleaved
  std::vector<double> energies;         // (kMaxEnergyOrder+1) × 4
  std::array<double, 4> norm_squared{};  // of the projected copy
};

/// The reference projection of `environment`, computed on the first call (projection.cpp).
const ReferenceProjection& reference_projection(const Environment& environment);

/// Evaluates Σ_{l<=order} c_lm y_lm (RGB coefficients, layout as sh) at the texel centres of a
/// width × height equirect grid (environment.h's orientation, rows top-first) and calls
/// row(j, values) once per row j with values[3 i + c] for column i — from several threads at once,
/// for different rows. Cost ∝ height (order+1)² + width height (order+1). Unchecked sizes.
void evaluate_equirect_rows(const std::vector<double>& coefficients, int order, int width, int height,
                            const std::function<void(int, const double*)>& row);

/// Throws std::invalid_argument naming `what` unless channel is 0, 1, 2 (R, G, B) or kLuminance.
void check_channel(const char* what, int channel);

}  // namespace sd
