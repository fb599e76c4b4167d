// Numbers in messages. Private to the library.
#pragma once

#include <cstdio>
#include <string>

namespace sd {

/// A double as printf's %.6g: 1e-17 stays 1e-17 and 3e+300 stays 3e+300 (std::to_string's fixed
/// six decimals print both as useless "0.000000" or as 301 digits).
inline std::string number_string(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

}  // namespace sd
