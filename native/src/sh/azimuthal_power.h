// The azimuthal factor of the real SH (spherical_harmonics.h): y_l,±m ∝ {Re, Im} (x + i y)^m. Shared
// by the SH evaluator and the zonal designs' orthonormal basis. Private to the library.
#pragma once

namespace sd {

/// (x + i y)^m and, for the gradients ∂/∂x (x + i y)^m = m (x + i y)^(m−1), the power before it,
/// for m = 0, 1, 2, … as next() is called.
struct AzimuthalPower {
  double re = 1.0, im = 0.0;            ///< (x + i y)^m
  double re_prev = 0.0, im_prev = 0.0;  ///< (x + i y)^(m−1) (0 for m = 0)

  /// From m to m + 1.
  void next(double x, double y) {
    re_prev = re;
    im_prev = im;
    const double r = re * x - im * y;
    im = re * y + im * x;
    re = r;
  }
};

}  // namespace sd
