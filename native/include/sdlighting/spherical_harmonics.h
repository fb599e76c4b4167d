// Real spherical harmonics orthonormal for the normalised measure dμ = dx/4π on S².
//
// Convention (used everywhere: C++, Python, GLSL):
//   y_l0     = sqrt(2l+1) P_l(z)
//   y_l,+m   = Q_lm(z) Re (x + i y)^m      (m > 0)
//   y_l,-m   = Q_lm(z) Im (x + i y)^m      (m > 0)
// with Q_lm(z) = sqrt(2 (2l+1) (l-m)!/(l+m)!) P_l^m(z) / sin^m θ and P_l^m *without* the
// Condon–Shortley phase, so y_00 = 1, y_1,-1 = √3 y, y_10 = √3 z, y_11 = √3 x.
// Flat index of (l, m) is l² + l + m; an expansion of order s has (s+1)² coefficients.
// Evaluation uses the fully normalised three-term recurrences of geodesy, stable far beyond
// order 32 (msd-notes: "Spherical harmonics convention"):
//   Q_mm = sqrt((2m+1)/(2m)) Q_{m-1,m-1}   (Q_00 = 1, Q_11 = √3)
//   Q_lm = a_lm z Q_{l-1,m} − b_lm Q_{l-2,m}   (m < l; a_{m+1,m} = √(2m+3), b_{m+1,m} = 0)
// with the constants of sh_recurrence(), which the GLSL shader receives too.
#pragma once

#include <glm/vec3.hpp>

#include <vector>

namespace sd {

/// Number of coefficients of an SH expansion of order `order`: (order+1)².
constexpr int sh_count(int order) { return (order + 1) * (order + 1); }

/// Flat index l² + l + m of the harmonic y_lm.
constexpr int sh_index(int l, int m) { return l * l + l + m; }

/// Position l(l+1)/2 + m of (l, m), 0 <= m <= l, in the triangular tables of ShRecurrence.
constexpr int sh_triangle_index(int l, int m) { return l * (l + 1) / 2 + m; }

/// The constants of the recurrences above for l <= order: what sh_basis evaluates with, exported
/// so that other evaluators (the GLSL shader) use the very same numbers.
struct ShRecurrence {
  std::vector<double> diagonal;  ///< Q_mm, m = 0 .. order
  /// a_lm and b_lm at sh_triangle_index(l, m), (order+1)(order+2)/2 entries; 0 where m == l.
  std::vector<double> a, b;
};

/// The recurrence constants up to `order` in [0, kMaxShOrder] (else std::invalid_argument).
ShRecurrence sh_recurrence(int order);

/// Writes y_lm(dir) for all l <= order into out[0 .. sh_count(order)).
/// `dir` must be a unit vector.
void sh_basis(int order, const glm::dvec3& dir, double* out);

/// Convenience overload returning a freshly allocated vector.
std::vector<double> sh_basis(int order, const glm::dvec3& dir);

/// Writes y_lm(dir) into values and the tangential gradient of each y_lm (a vector orthogonal
/// to `dir`, three doubles per harmonic) into gradients[0 .. 3 sh_count(order)).
void sh_basis_with_gradient(int order, const glm::dvec3& dir, double* values, double* gradients);

/// Legendre polynomial P_l(t) by the three-term recurrence (never through monomials).
double legendre(int l, double t);

/// Writes P_0(t) .. P_lmax(t) into out[0 .. lmax].
void legendre_all(int lmax, double t, double* out);

}  // namespace sd
