// The rotation g_a of Theorem 2.1: any rotation taking e3 to the lobe axis. Private to the library.
#pragma once

#include <glm/vec3.hpp>

#include <cmath>

namespace sd {

/// Tangents t1, t2 with (t1, t2, a) a right-handed orthonormal frame, so that g_a x = x.x t1 +
/// x.y t2 + x.z a (Duff et al., "Building an orthonormal basis, revisited", 2017: no branch near
/// the poles but the sign). The twist does not matter for a zonal lobe.
inline void frame_around(const glm::dvec3& a, glm::dvec3& t1, glm::dvec3& t2) {
  const double sign = std::copysign(1.0, a.z);
  const double c = -1.0 / (sign + a.z);
  const double d = a.x * a.y * c;
  t1 = {1.0 + sign * a.x * a.x * c, sign * d, -sign * a.x};
  t2 = {d, sign + a.y * a.y * c, -a.y};
}

}  // namespace sd
