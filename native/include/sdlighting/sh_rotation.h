// Rotation of real spherical-harmonic expansions (convention: spherical_harmonics.h).
#pragma once

#include <glm/mat3x3.hpp>

#include <vector>

namespace sd {

/// The block-diagonal matrix D(R) that rotates SH coefficients, band by band, built with the
/// Ivanic–Ruedenberg recurrence (J. Phys. Chem. 1996, 100, 6342; errata 1998).
///
/// Meaning: if f has coefficients c, then the rotated function f_R(x) = f(Rᵀ x) (f turned by R,
/// so that f_R(R x) = f(x)) has coefficients D(R) c. For eq. (1) the environment seen through
/// g is L(g x) = L_{gᵀ}(x): its coefficients are D(gᵀ) L.
class ShRotation {
 public:
  /// Builds D(R) for all bands l <= order. `rotation` (column-major glm: rotation[col][row]) must
  /// be finite and orthogonal with determinant +1 to about 1e-9 (‖RᵀR − I‖_F and |det − 1|), and
  /// order must lie in [0, 64]; throws std::invalid_argument otherwise. Costs O(order³).
  ShRotation(const glm::dmat3& rotation, int order);

  /// The highest band held.
  int order() const { return order_; }

  /// Band l (0 <= l <= order(), unchecked) as a row-major (2l+1)×(2l+1) orthogonal matrix; row
  /// and column index m + l.
  const double* band(int l) const { return bands_[l].data(); }

  /// out = D(R) in for `channels` interleaved channels: in[i * channels + c] is coefficient i of
  /// channel c; both arrays hold sh_count(order) * channels doubles and must not overlap.
  /// Throws std::invalid_argument if channels < 1.
  void apply(const double* in, double* out, int channels = 1) const;

 private:
  int order_;
  std::vector<std::vector<double>> bands_;
};

}  // namespace sd
