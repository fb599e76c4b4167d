// Rotation of real spherical-harmonic expansions (convention: spherical_harmonics.h).
#pragma once

#include <glm/mat3x3.hpp>

#include <vector>

namespace sd {

/// The proper rotation nearest to `rotation` (its polar factor U Vᵀ), after checking that it is one:
/// finite, orthogonal to 1e-5 (‖RᵀR − I‖_F: float32 rotations pass) and not a reflection (det < 0);
/// std::invalid_argument otherwise. Every function that takes a rotation (ShRotation, rotated_sh,
/// shade_reference) checks it with this.
glm::dmat3 proper_rotation(const glm::dmat3& rotation);

/// The block-diagonal matrix D(R) that rotates SH coefficients, band by band, built with the
/// Ivanic–Ruedenberg recurrence (J. Phys. Chem. 1996, 100, 6342; errata 1998).
///
/// Meaning: if f has coefficients c, then the rotated function f_R(x) = f(Rᵀ x) (f turned by R,
/// so that f_R(R x) = f(x)) has coefficients D(R) c. The environment of eq. (1) goes through
/// rotated_sh, never through this class directly.
class ShRotation {
 public:
  /// Builds D(R) for all bands l <= order. `rotation` (column-major glm: rotation[col][row]) must
  /// be finite, orthogonal to 1e-5 (‖RᵀR − I‖_F: float32 rotations pass) and not a reflection
  /// (det < 0); D is built from the nearest exact rotation (R's polar factor). order must lie in
  /// [0, 64]. Throws std::invalid_argument otherwise. Costs O(order³).
  ShRotation(const glm::dmat3& rotation, int order);

  /// The highest band held.
  int order() const { return order_; }

  /// Band l (0 <= l <= order(), unchecked) as a row-major (2l+1)×(2l+1) orthogonal matrix; row
  /// and column index m + l.
  const double* band(int l) const { return bands_[l].data(); }

  /// out = D(R) in for `channels` interleaved channels: in[i * channels + c] is coefficient i of
  /// channel c; both arrays hold sh_count(bands) * channels doubles and must not overlap. bands:
  /// the highest band turned, -1 for order(); one above order() is unchecked. Throws
  /// std::invalid_argument if channels < 1.
  void apply(const double* in, double* out, int channels = 1, int bands = -1) const;

 private:
  int order_;
  std::vector<std::vector<double>> bands_;
};

/// D(R) applied without building it, for the many rotations of a bake (each vertex's ray set is
/// turned by its own R, and its sums are turned back): R = Rz(α) Ry(β) Rz(γ), and
/// Ry(β) = Rx(−90°) Rz(β) Rx(90°), so D(R) = Z(α) Xᵀ Z(β) X Z(γ) with X = D(Rx(90°)), built once,
/// and Z(θ) = D(Rz(θ)) turning each pair of coefficients ±m by mθ (the "zxzxz" rotation of Kautz,
/// Sloan and Snyder, "Fast, Arbitrary BRDF Shading for Low-Frequency Lighting Using Spherical
/// Harmonics", EGRW 2002). Agrees with ShRotation to rounding.
class EulerShRotation {
 public:
  /// Prepares bands 0..order; order must lie in [0, kMaxShOrder] (std::invalid_argument otherwise).
  explicit EulerShRotation(int order);

  /// The highest band it can turn.
  int order() const { return x_.order(); }

  /// data ← D(R) data for bands 0..bands: data holds sh_count(bands) rows of `channels` doubles
  /// (ShRotation::apply's layout). Throws std::invalid_argument unless 0 <= bands <= order() and
  /// channels >= 1. R must be a proper rotation (unchecked: ShRotation and proper_rotation check one).
  void apply(const glm::dmat3& rotation, double* data, int channels, int bands) const;

 private:
  ShRotation x_;          // X = D(Rx(90°))
  ShRotation x_inverse_;  // Xᵀ = D(Rx(−90°))
};

/// THE convention of the environment rotation g of eq. (1), stated here only: the environment
/// seen through g is x ↦ L(g x) = L_{gᵀ}(x), whose coefficients (the seed's L_lm(g)) are
///     L(g) = D(gᵀ) L      (ShRotation(gᵀ, order)).
/// Every caller (shading, the bindings, the add-on through sdnative.rotated_environment_sh)
/// rotates L with this function. `coeffs` holds sh_count(order) × channels doubles,
/// coefficient-major (coeffs[channels i + c]); g must be a proper rotation (ShRotation's checks).
/// Throws std::invalid_argument for a wrong size, an order outside [0, kMaxShOrder],
/// channels < 1 or a bad g.
std::vector<double> rotated_sh(const std::vector<double>& coeffs, int order, const glm::dmat3& g, int channels = 3);

}  // namespace sd
