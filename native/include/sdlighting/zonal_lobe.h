// The zonal BRDF lobes of the method, both normalised to ∫ w(a·x) dμ(x) = 1 (msd-notes, "The
// problem"): Lambert w(t) = 4 max(0, t) and Phong w(t) = (2σ+2) max(0, t)^σ. Lambert is Phong
// with σ = 1, and both are handled through that one family.
#pragma once

#include "sdlighting/limits.h"

#include <string>
#include <vector>

namespace sd {

/// A normalised zonal lobe around an axis a: w(a·x) = (2σ+2) max(0, a·x)^σ.
struct ZonalLobe {
  double exponent = 1.0;  // σ; Lambert is σ = 1

  /// Lambert: 4 max(0, t).
  static ZonalLobe lambert() { return ZonalLobe{1.0}; }
  /// Phong with exponent σ in [0, 1e4]; throws std::invalid_argument otherwise (NaN included).
  static ZonalLobe phong(double exponent);
  /// "lambert" (exponent ignored) or "phong"; throws std::invalid_argument for other names.
  static ZonalLobe from_name(const std::string& name, double exponent);

  /// w(t) for t = a·x.
  double value(double t) const;

  /// Funk–Hecke factors ŵ_0 .. ŵ_lmax, ŵ_l = ½ ∫ w(t) P_l(t) dt, ŵ_0 = 1, by the recurrence
  /// ŵ_{l+2} = ŵ_l (σ−l)/(σ+l+3) (msd-notes), whose factors all have magnitude below 1, so it
  /// is stable for any σ; never through monomials of P_l.
  std::vector<double> coefficients(int lmax) const;
};

/// The lobe truncated at order s': w̃(t) = Σ_{l<=order} (2l+1) ŵ_l P_l(t), as used by eq. (13).
/// `coefficients` must hold at least order+1 factors.
double truncated_lobe(const std::vector<double>& coefficients, int order, double t);

}  // namespace sd
