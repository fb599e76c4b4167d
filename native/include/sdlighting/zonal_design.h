// Weighted spherical designs for zonal weights w(x·e3): the BRDF lobes of Theorem 2.1 and any
// tabulated zonal weight.
#pragma once

#include "sdlighting/gauss_quadrature.h"
#include "sdlighting/spherical_design.h"
#include "sdlighting/zonal_lobe.h"

#include <optional>
#include <string>
#include <vector>

namespace sd {

/// How to build a design: the Gauss product rule, gradient projection (eq. 14), or the smaller
/// certified one of both.
enum class DesignMethod { Auto, Gauss, Gradient };

/// "auto", "gauss" or "gradient"; throws std::invalid_argument otherwise.
DesignMethod design_method_from_name(const std::string& name);

/// A zonal weight on the sphere, held as a discrete measure in s = 1 − x·e3 ∈ [0, 2] that
/// integrates every polynomial in s of degree <= 2 kMaxDesignDegree + 7 exactly — all that the
/// design builders ever ask of it.
class ZonalWeight {
 public:
  /// The lobe's weight (mass 1): a Gauss–Jacobi rule of the closed-form recurrence.
  static ZonalWeight from_lobe(const ZonalLobe& lobe);

  /// w given at increasing t_i ∈ [−1, 1] (at least two samples, w_i >= 0, finite), linear between
  /// samples and zero outside [t_0, t_last]. Throws std::invalid_argument on bad input.
  static ZonalWeight tabulated(const std::vector<double>& t, const std::vector<double>& w);

  /// ∫ w(x·e3) dμ(x).
  double mass() const { return mass_; }

  /// ½ ∫ w(t) P_l(t) dt for l = 0 .. lmax (so moment l of y_l0 is sqrt(2l+1) times it).
  std::vector<double> legendre_moments(int lmax) const;

  /// The SH moments ∫ y_lm w dμ, l <= degree (zero unless m = 0).
  std::vector<double> sh_moments(int degree) const;

  /// First n recurrence coefficients, in s, of the measure (s(2−s))^m w(1−s) ds/2, the radial
  /// factor of the weight's order-m harmonics (|x + i y|^2m = (s(2−s))^m).
  Recurrence radial_recurrence(int m, int n) const;

  /// The lowest and highest s where the weight lives.
  double support_min() const { return support_min_; }
  double support_max() const { return support_max_; }

 private:
  std::vector<double> nodes_;    // s
  std::vector<double> weights_;  // include the ½ of dt/2, so they sum to the mass
  double mass_ = 0.0;
  double support_min_ = 0.0, support_max_ = 2.0;
};

/// A design of `degree` (0..kMaxDesignDegree) for the zonal weight, nodes around e3, weights
/// summing to its mass, certified (residual <= kDesignTolerance); throws std::runtime_error if no
/// method yields one and std::invalid_argument for a degree out of range.
/// - Gauss: n Gauss nodes in s times degree+1 equally spaced φ, or the Gauss–Radau variant with
///   the pole as a node (the seed's 11 and 22 nodes for degrees 4 and 6), whichever is smaller.
/// - Gradient: gradient projection (eq. 14) from well-spread starts, searching down from the
///   generic node count for the smallest design it can certify.
/// - Auto: the smaller of both.
SphericalDesign zonal_design(const ZonalWeight& weight, int degree, DesignMethod method = DesignMethod::Auto);

/// The design of `degree` for `weight` continued from `start`, a design of the same degree for a
/// neighbouring weight `start_weight` (the lobe at a nearby exponent): every node keeps its
/// azimuth and moves along its meridian to where the same fraction of the mass lies closer to the
/// pole, then gradient projection (eq. 14) refits the design and, if `thin`, removes nodes while
/// it still certifies (costly at high degrees: worth it where the chain of steps ends, not on the
/// way); the Gauss product rule instead when that is smaller. Milliseconds where
/// zonal_design's search takes seconds to minutes, with about as many nodes as the start (often
/// fewer than the search finds). std::nullopt when the moved design does not refit to a certified
/// one (the step was too large: continue in smaller steps, or use zonal_design). Throws
/// std::invalid_argument for a degree out of range or a start of another degree.
std::optional<SphericalDesign> zonal_design_continued(const ZonalWeight& weight, int degree,
                                                      const ZonalWeight& start_weight, const SphericalDesign& start,
                                                      bool thin = true);

}  // namespace sd
