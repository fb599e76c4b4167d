// Hostile values decoded from a fuzzer's bytes (header-only, shared by the fuzz targets): mostly
// ordinary numbers, so that most inputs reach the computation, mixed with the values that break
// numerical code — NaN, ±inf, ±0, denormals, ±1e300, raw bit patterns, indices out of range.
#pragma once

#include <fuzzer/FuzzedDataProvider.h>

#include "sdlighting/mesh.h"

#include <glm/vec3.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <vector>

namespace sd::fuzz {

/// A double: one selector byte, then the value it names or the bytes of one.
inline double hostile_double(FuzzedDataProvider& data, double scale = 1.0) {
  switch (data.ConsumeIntegralInRange<int>(0, 15)) {
    case 0: return std::numeric_limits<double>::quiet_NaN();
    case 1: return std::numeric_limits<double>::infinity();
    case 2: return -std::numeric_limits<double>::infinity();
    case 3: return 0.0;
    case 4: return -0.0;
    case 5: return std::numeric_limits<double>::denorm_min();
    case 6: return data.ConsumeBool() ? 1e300 : -1e300;
    case 7: {  // any bit pattern
      const auto bits = data.ConsumeIntegral<std::uint64_t>();
      double value;
      std::memcpy(&value, &bits, sizeof value);
      return value;
    }
    default: return scale * data.ConsumeFloatingPointInRange<double>(-1.0, 1.0);
  }
}

/// A vector of three hostile_double.
inline glm::dvec3 hostile_vec3(FuzzedDataProvider& data, double scale = 1.0) {
  const double x = hostile_double(data, scale), y = hostile_double(data, scale);
  return {x, y, hostile_double(data, scale)};
}

/// A finite double in [-scale, scale] (for the arrays whose contract is finite values).
inline double finite_double(FuzzedDataProvider& data, double scale = 1.0) {
  return scale * data.ConsumeFloatingPointInRange<double>(-1.0, 1.0);
}

/// A unit vector from three finite doubles (+Z when they are all zero).
inline glm::dvec3 unit_vec3(FuzzedDataProvider& data) {
  const glm::dvec3 v(finite_double(data), finite_double(data), finite_double(data));
  const double norm = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
  return norm > 1e-6 ? v / norm : glm::dvec3(0.0, 0.0, 1.0);
}

/// An index into `count` items, now and then one outside: −1, count, the int64 extremes.
inline std::int64_t hostile_index(FuzzedDataProvider& data, std::int64_t count) {
  switch (data.ConsumeIntegralInRange<int>(0, 31)) {
    case 0: return -1;
    case 1: return count;
    case 2: return std::numeric_limits<std::int64_t>::min();
    case 3: return std::numeric_limits<std::int64_t>::max();
    default: return count > 0 ? data.ConsumeIntegralInRange<std::int64_t>(0, count - 1) : 0;
  }
}

/// An order or degree in [lo, hi], now and then just outside it.
inline int hostile_order(FuzzedDataProvider& data, int lo, int hi) {
  switch (data.ConsumeIntegralInRange<int>(0, 31)) {
    case 0: return lo - 1;
    case 1: return hi + 1;
    default: return data.ConsumeIntegralInRange<int>(lo, hi);
  }
}

/// Points in the cube [-scale, scale]³, one in eight hostile_vec3 unless `finite`.
inline std::vector<glm::dvec3> points(FuzzedDataProvider& data, std::size_t count, double scale, bool finite) {
  std::vector<glm::dvec3> out(count);
  for (auto& p : out) {
    p = finite || data.ConsumeIntegralInRange(0, 7) != 0
            ? glm::dvec3(finite_double(data, scale), finite_double(data, scale), finite_double(data, scale))
            : hostile_vec3(data, scale);
  }
  return out;
}

/// `count` triangles of hostile_index into `vertices` points.
inline std::vector<sd::Triangle> triangles(FuzzedDataProvider& data, std::size_t count, std::size_t vertices) {
  std::vector<sd::Triangle> out(count);
  for (auto& t : out) {
    for (auto& index : t) index = hostile_index(data, static_cast<std::int64_t>(vertices));
  }
  return out;
}

/// Stops the run, as a crash does, when an output breaks the entry point's contract.
[[noreturn]] inline void contract_broken(const char* what) {
  std::fprintf(stderr, "contract broken: %s\n", what);
  std::abort();
}

/// A refusal must be a std::exception that says why.
inline void check_message(const std::exception& error) {
  if (std::strlen(error.what()) == 0) contract_broken("an exception without a message");
}

}  // namespace sd::fuzz
