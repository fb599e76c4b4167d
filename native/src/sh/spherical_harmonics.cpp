#include "sdlighting/spherical_harmonics.h"

#include "sdlighting/limits.h"
#include "sh/azimuthal_power.h"

#include <glm/geometric.hpp>

#include <cmath>

namespace sd {
namespace {

// Orders up to this use the tabulated recurrence constants (the square roots dominate otherwise).
constexpr int kTabulatedOrder = 64;

// The recurrence constants of the header, one entry at a time: the only place they are written.
// Q_mm = sqrt((2m+1)/(2m)) Q_{m-1,m-1}, Q_00 = 1, Q_11 = √3.
double diagonal_step(int m, double previous) {
  return m == 1 ? std::sqrt(3.0) : previous * std::sqrt((2.0 * m + 1.0) / (2.0 * m));
}

// a_lm for m < l; a_{m+1,m} = sqrt(2m+3) starts the column from Q_mm.
double coefficient_a(int l, int m) {
  if (l == m + 1) return std::sqrt(2.0 * m + 3.0);
  return std::sqrt((2.0 * l - 1.0) * (2.0 * l + 1.0) / ((l - m) * double(l + m)));
}

// b_lm for m < l; b_{m+1,m} = 0 (there is no Q_{m-1,m}).
double coefficient_b(int l, int m) {
  if (l == m + 1) return 0.0;
  return std::sqrt((2.0 * l + 1.0) * (l + m - 1.0) * (l - m - 1.0) / ((l - m) * double(l + m) * (2.0 * l - 3.0)));
}

const ShRecurrence& tabulated() {
  static const ShRecurrence table = sh_recurrence(kTabulatedOrder);
  return table;
}

template <bool kWithGradient>
void evaluate(int order, const glm::dvec3& d, double* values, double* gradients) {
  const ShRecurrence& table = tabulated();
  double q_mm = 1.0;
  AzimuthalPower power;
  for (int m = 0; m <= order; ++m) {
    q_mm = m <= kTabulatedOrder ? table.diagonal[m] : diagonal_step(m, q_mm);
    if (m > 0) power.next(d.x, d.y);
    const double re = power.re, im = power.im, re_prev = power.re_prev, im_prev = power.im_prev;
    double q_prev2 = 0.0, q_prev = 0.0, dq_prev2 = 0.0, dq_prev = 0.0;
    for (int l = m; l <= order; ++l) {
      double q, dq;
      if (l == m) {
        q = q_mm;
        dq = 0.0;
      } else {
        const bool in_table = l <= kTabulatedOrder;
        const double a = in_table ? table.a[sh_triangle_index(l, m)] : coefficient_a(l, m);
        const double b = in_table ? table.b[sh_triangle_index(l, m)] : coefficient_b(l, m);
        q = a * d.z * q_prev - b * q_prev2;
        dq = a * (q_prev + d.z * dq_prev) - b * dq_prev2;
      }
      q_prev2 = q_prev;
      q_prev = q;
      dq_prev2 = dq_prev;
      dq_prev = dq;

      const int center = l * l + l;
      values[center + m] = q * re;
      if (m > 0) values[center - m] = q * im;
      if constexpr (kWithGradient) {
        // Ambient gradient of the polynomial extension, then projected onto the tangent plane.
        auto store = [&](int index, glm::dvec3 g) {
          g -= glm::dot(g, d) * d;
          gradients[3 * index + 0] = g.x;
          gradients[3 * index + 1] = g.y;
          gradients[3 * index + 2] = g.z;
        };
        store(center + m, {q * m * re_prev, -q * m * im_prev, dq * re});
        if (m > 0) store(center - m, {q * m * im_prev, q * m * re_prev, dq * im});
      }
    }
  }
}

}  // namespace

ShRecurrence sh_recurrence(int order) {
  check_order("sh_recurrence: order", order, kMaxShOrder);
  ShRecurrence r;
  r.diagonal.assign(order + 1, 1.0);
  for (int m = 1; m <= order; ++m) r.diagonal[m] = diagonal_step(m, r.diagonal[m - 1]);
  r.a.assign(sh_triangle_index(order + 1, 0), 0.0);
  r.b.assign(r.a.size(), 0.0);
  for (int l = 1; l <= order; ++l) {
    for (int m = 0; m < l; ++m) {
      r.a[sh_triangle_index(l, m)] = coefficient_a(l, m);
      r.b[sh_triangle_index(l, m)] = coefficient_b(l, m);
    }
  }
  return r;
}

void sh_basis(int order, const glm::dvec3& dir, double* out) {
  evaluate<false>(order, dir, out, nullptr);
}

std::vector<double> sh_basis(int order, const glm::dvec3& dir) {
  std::vector<double> out(sh_count(order));
  sh_basis(order, dir, out.data());
  return out;
}

void sh_basis_with_gradient(int order, const glm::dvec3& dir, double* values, double* gradients) {
  evaluate<true>(order, dir, values, gradients);
}

void legendre_all(int lmax, double t, double* out) {
  out[0] = 1.0;
  if (lmax >= 1) out[1] = t;
  for (int l = 2; l <= lmax; ++l) {
    out[l] = ((2.0 * l - 1.0) * t * out[l - 1] - (l - 1.0) * out[l - 2]) / l;
  }
}

double legendre(int l, double t) {
  double p_prev = 1.0, p = t;
  if (l == 0) return 1.0;
  for (int k = 2; k <= l; ++k) {
    const double next = ((2.0 * k - 1.0) * t * p - (k - 1.0) * p_prev) / k;
    p_prev = p;
    p = next;
  }
  return p;
}

}  // namespace sd
