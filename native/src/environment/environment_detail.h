// What the files of Environment share: its lazily computed high-order projection and the channel
// check. Private to the environment files.
#pragma once

#include "sdlighting/environment.h"

#include <array>
#include <mutex>
#include <vector>

namespace sd {

struct Environment::EnergyCache {
  std::mutex mutex;
  bool ready = false;
  std::vector<double> coefficients;     // order kMaxEnergyOrder, RGB interleaved
  std::vector<double> energies;         // (kMaxEnergyOrder+1) × 4
  std::array<double, 4> norm_squared{};  // of the projected copy
};

/// Throws std::invalid_argument naming `what` unless channel is 0, 1, 2 (R, G, B) or kLuminance.
void check_channel(const char* what, int channel);

}  // namespace sd
