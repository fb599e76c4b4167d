// Gauss rules on an interval from the three-term recurrence of the weight's orthogonal
// polynomials (Golub–Welsch), for closed-form Jacobi weights and for any discrete measure.
//
// Zonal lobes are parametrised by s = 1 - t (t = cos θ), not by t: nodes of a narrow lobe crowd
// t = 1, where 1 - t loses its digits, while s keeps full relative precision (msd-notes,
// "Gauss product for a zonal weight").
#pragma once

#include <vector>

namespace sd {

/// Monic recurrence p_{k+1}(x) = (x - alpha_k) p_k(x) - beta_k p_{k-1}(x), p_0 = 1, p_{-1} = 0;
/// beta_0 is the measure's mass.
struct Recurrence {
  std::vector<double> alpha;
  std::vector<double> beta;
  int size() const { return static_cast<int>(alpha.size()); }
};

/// Nodes and weights of a one-dimensional rule.
struct Rule1D {
  std::vector<double> nodes;
  std::vector<double> weights;
};

/// The first n recurrence coefficients of the weight (1 - s)^exponent on s ∈ [0, 1]
/// (Jacobi with α = exponent, β = 0, shifted), in a form free of cancellation near s = 0.
/// beta_0 = 1/(exponent+1). Requires exponent >= 0.
Recurrence jacobi_recurrence_unit_interval(double exponent, int n);

/// The first n recurrence coefficients of the discrete measure Σ weights_i δ(nodes_i), by
/// Lanczos with full re-orthogonalisation (stable where the plain Stieltjes procedure is not).
/// Requires n <= number of positive weights.
Recurrence discrete_recurrence(const std::vector<double>& nodes, const std::vector<double>& weights,
                               int n);

/// n-point Gauss rule of the measure described by `recurrence` (needs n coefficients):
/// exact for polynomials of degree 2n-1; weights sum to beta_0.
Rule1D gauss_rule(const Recurrence& recurrence, int n);

/// n-point Gauss–Radau rule with one node fixed at `fixed_node` (an end of the support):
/// exact for polynomials of degree 2n-2; needs n coefficients.
Rule1D gauss_radau_rule(const Recurrence& recurrence, int n, double fixed_node);

/// Values of the orthonormal polynomials p_0 .. p_{n-1} of `recurrence` at x
/// (p_0 = 1/sqrt(beta_0)), and their derivatives when `derivatives` is not null.
void orthonormal_polynomials(const Recurrence& recurrence, int n, double x, double* values,
                             double* derivatives);

}  // namespace sd
