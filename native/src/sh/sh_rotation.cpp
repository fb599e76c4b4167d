// Band rotation matrices by the recurrence of J. Ivanic and K. Ruedenberg, "Rotation matrices for
// real spherical harmonics. Direct determination by recursion", J. Phys. Chem. 100, 6342 (1996),
// with the corrections of J. Phys. Chem. A 102, 9099 (1998). Each band l is built from band 1 and
// band l-1 only, in O(l²), and stays orthogonal to rounding far beyond the orders used here.
#include "sdlighting/sh_rotation.h"

#include "sdlighting/limits.h"
#include "sdlighting/spherical_harmonics.h"
#include "util/number_string.h"

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <glm/matrix.hpp>

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace sd {
namespace {

// ‖RᵀR − I‖_F accepted: float32 rotations (a Blender matrix_world) reach a few 1e-7; a matrix
// 1e-5 from orthogonal is no rounding artefact but a scale or shear.
constexpr double kRotationTolerance = 1e-5;

// Ivanic & Ruedenberg index band matrices by m, n ∈ [-l, l]; storing them row-major with offset l
// lets the recurrence be written in the paper's notation.
class CenteredBand {
 public:
  CenteredBand(const std::vector<double>& data, int l) : data_(data.data()), l_(l), size_(2 * l + 1) {}
  double operator()(int m, int n) const { return data_[(m + l_) * size_ + (n + l_)]; }

 private:
  const double* data_;
  int l_;
  int size_;
};

// The auxiliary function P of Ivanic & Ruedenberg (1996), Table 2, with the 1998 corrections:
// it couples row i of band 1 with row a of band l-1; the b = ±l cases fold the two band-1 columns
// ±1 that a column of band l-1 cannot reach on its own.
double p_term(int i, int a, int b, int l, const CenteredBand& r1, const CenteredBand& prev) {
  if (b == l) return r1(i, 1) * prev(a, l - 1) - r1(i, -1) * prev(a, -l + 1);
  if (b == -l) return r1(i, 1) * prev(a, -l + 1) + r1(i, -1) * prev(a, l - 1);
  return r1(i, 0) * prev(a, b);
}

double u_term(int m, int n, int l, const CenteredBand& r1, const CenteredBand& prev) {
  return p_term(0, m, n, l, r1, prev);
}

// The m < 0 branch follows the 1998 errata: the √2 belongs to the P(-1, ...) term, mirroring m > 0.
double v_term(int m, int n, int l, const CenteredBand& r1, const CenteredBand& prev) {
  if (m == 0) return p_term(1, 1, n, l, r1, prev) + p_term(-1, -1, n, l, r1, prev);
  if (m > 0) {
    const double first = p_term(1, m - 1, n, l, r1, prev);
    if (m == 1) return std::sqrt(2.0) * first;
    return first - p_term(-1, -m + 1, n, l, r1, prev);
  }
  const double second = p_term(-1, -m - 1, n, l, r1, prev);
  if (m == -1) return std::sqrt(2.0) * second;
  return p_term(1, m + 1, n, l, r1, prev) + second;
}

double w_term(int m, int n, int l, const CenteredBand& r1, const CenteredBand& prev) {
  if (m > 0) return p_term(1, m + 1, n, l, r1, prev) + p_term(-1, -m - 1, n, l, r1, prev);
  return p_term(1, m - 1, n, l, r1, prev) - p_term(-1, -m + 1, n, l, r1, prev);
}

// Band l from band 1 and band l-1 (Ivanic & Ruedenberg 1996, Tables 1 and 2). The integer
// numerators decide exactly which of u, v, w vanish: U, V, W would index outside band l-1 there.
std::vector<double> band_from_previous(int l, const std::vector<double>& band1,
                                       const std::vector<double>& previous) {
  const CenteredBand r1(band1, 1), prev(previous, l - 1);
  const int size = 2 * l + 1;
  std::vector<double> band(size_t(size) * size);
  for (int m = -l; m <= l; ++m) {
    const int am = std::abs(m);
    const double delta_m0 = m == 0 ? 1.0 : 0.0;
    for (int n = -l; n <= l; ++n) {
      const double denominator =
          std::abs(n) == l ? 2.0 * l * (2.0 * l - 1.0) : double(l + n) * double(l - n);
      const int u_numerator = (l + m) * (l - m);
      const int v_numerator = (l + am - 1) * (l + am);
      const int w_numerator = m == 0 ? 0 : (l - am - 1) * (l - am);
      double value = 0.0;
      if (u_numerator != 0) {
        value += std::sqrt(u_numerator / denominator) * u_term(m, n, l, r1, prev);
      }
      if (v_numerator != 0) {
        const double v = 0.5 * std::sqrt((1.0 + delta_m0) * v_numerator / denominator) *
                         (1.0 - 2.0 * delta_m0);
        value += v * v_term(m, n, l, r1, prev);
      }
      if (w_numerator != 0) {
        value += -0.5 * std::sqrt(w_numerator / denominator) * w_term(m, n, l, r1, prev);
      }
      band[size_t(m + l) * size + (n + l)] = value;
    }
  }
  return band;
}

// out = D in, band by band; kChannels > 0 fixes the channel count at compile time, 0 means `channels`.
template <int kChannels>
void apply_bands(const std::vector<std::vector<double>>& bands, int order, const double* in,
                 double* out, int channels) {
  const int ch = kChannels > 0 ? kChannels : channels;
  for (int l = 0; l <= order; ++l) {
    const int size = 2 * l + 1;
    const double* matrix = bands[l].data();
    const double* band_in = in + size_t(l) * l * ch;
    double* band_out = out + size_t(l) * l * ch;
    for (int i = 0; i < size; ++i) {
      double* o = band_out + size_t(i) * ch;
      const double* row = matrix + size_t(i) * size;
      for (int c = 0; c < ch; ++c) o[c] = 0.0;
      for (int j = 0; j < size; ++j) {
        const double rij = row[j];
        const double* x = band_in + size_t(j) * ch;
        for (int c = 0; c < ch; ++c) o[c] += rij * x[c];
      }
    }
  }
}

}  // namespace

// Blender hands over float32 matrices, orthogonal only to about 1e-7, and the band recurrence would
// carry such a defect into every band, so the bands are built from the exactly orthogonal polar
// factor instead.
glm::dmat3 proper_rotation(const glm::dmat3& rotation) {
  Eigen::Matrix3d r;
  for (int col = 0; col < 3; ++col) {
    for (int row = 0; row < 3; ++row) {
      if (!std::isfinite(rotation[col][row])) {
        throw std::invalid_argument("rotation matrix has a non-finite entry");
      }
      r(row, col) = rotation[col][row];
    }
  }
  const double defect = (r.transpose() * r - Eigen::Matrix3d::Identity()).norm();  // Frobenius
  if (!(defect <= kRotationTolerance)) {
    throw std::invalid_argument("rotation matrix is not orthogonal (||R^T R - I||_F = " + number_string(defect) +
                                ", tolerance " + number_string(kRotationTolerance) + ")");
  }
  const double det = r.determinant();
  if (det < 0.0) {
    throw std::invalid_argument("rotation matrix is a reflection (det = " + number_string(det) +
                                "), not a rotation");
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d polar = svd.matrixU() * svd.matrixV().transpose();
  glm::dmat3 out;
  for (int col = 0; col < 3; ++col) {
    for (int row = 0; row < 3; ++row) out[col][row] = polar(row, col);
  }
  return out;
}


ShRotation::ShRotation(const glm::dmat3& rotation, int order) : order_(order) {
  check_order("ShRotation: order", order, kMaxShOrder);
  const glm::dmat3 r = proper_rotation(rotation);

  bands_.reserve(order + 1);
  bands_.push_back({1.0});
  if (order == 0) return;

  // Band 1 is R itself in the basis (y, z, x) ∝ (y_1,-1, y_10, y_11): with no Condon–Shortley phase
  // this is exactly Ivanic & Ruedenberg's R¹, so the recurrence below needs no sign fix-ups (the
  // Condon–Shortley variant of google/spherical-harmonics has to flip signs here instead).
  // D1[m][n] = R[axis(m)][axis(n)] makes y_1n ∘ Rᵀ = Σ_m D1[m][n] y_1m, the meaning in the header.
  const int axis[3] = {1, 2, 0};
  std::vector<double> band1(9);
  for (int m = 0; m < 3; ++m) {
    for (int n = 0; n < 3; ++n) band1[m * 3 + n] = r[axis[n]][axis[m]];
  }
  bands_.push_back(band1);
  for (int l = 2; l <= order; ++l) bands_.push_back(band_from_previous(l, bands_[1], bands_[l - 1]));
}

void ShRotation::apply(const double* in, double* out, int channels, int bands) const {
  if (channels < 1) throw std::invalid_argument("ShRotation::apply: channels must be >= 1");
  const int order = bands < 0 ? order_ : bands;
  // Fixed channel counts let the compiler unroll the inner loop (RGB is the hot case).
  switch (channels) {
    case 1: return apply_bands<1>(bands_, order, in, out, 1);
    case 3: return apply_bands<3>(bands_, order, in, out, 3);
    case 4: return apply_bands<4>(bands_, order, in, out, 4);
    default: return apply_bands<0>(bands_, order, in, out, channels);
  }
}

namespace {

glm::dmat3 quarter_turn_about_x(double sign) {
  glm::dmat3 r(0.0);  // column-major: r[column][row]
  r[0][0] = 1.0;
  r[1][2] = sign;   // y -> ±z
  r[2][1] = -sign;  // z -> ∓y
  return r;
}

// data ← Z(θ) data: f turned about z by θ, f(Rz(θ)ᵀ x), moves each azimuthal pair, cos mφ (index
// l² + l + m) and sin mφ (l² + l − m), as a' = a cos mθ − b sin mθ, b' = a sin mθ + b cos mθ.
void turn_about_z(double angle, double* data, int channels, int bands) {
  const double c1 = std::cos(angle), s1 = std::sin(angle);
  double c = 1.0, s = 0.0;  // cos mθ, sin mθ
  for (int m = 1; m <= bands; ++m) {
    const double next_c = c * c1 - s * s1;
    s = s * c1 + c * s1;
    c = next_c;
    for (int l = m; l <= bands; ++l) {
      double* a = data + size_t(l * l + l + m) * channels;
      double* b = data + size_t(l * l + l - m) * channels;
      for (int k = 0; k < channels; ++k) {
        const double ak = a[k], bk = b[k];
        a[k] = ak * c - bk * s;
        b[k] = ak * s + bk * c;
      }
    }
  }
}

}  // namespace

EulerShRotation::EulerShRotation(int order)
    : x_(quarter_turn_about_x(1.0), order), x_inverse_(quarter_turn_about_x(-1.0), order) {}

void EulerShRotation::apply(const glm::dmat3& rotation, double* data, int channels, int bands) const {
  if (bands < 0 || bands > order() || channels < 1) {
    throw std::invalid_argument("EulerShRotation::apply: bands must lie in [0, " + std::to_string(order()) +
                                "] and channels be >= 1, got " + std::to_string(bands) + " and " +
                                std::to_string(channels));
  }
  // R = Rz(α) Ry(β) Rz(γ): its third column is (cos α, sin α) sin β, cos β, and its upper 2×2
  // block holds (1 + cos β) times the cosine and sine of α + γ and (1 − cos β) times those of α − γ.
  // Near β = 0 (or π) α is known only to rounding / sin β, but γ taken from the well-determined sum
  // (or difference) makes up for it, so that the turn stays exact to rounding through gimbal lock.
  auto r = [&](int row, int column) { return rotation[column][row]; };
  const double beta = std::atan2(std::hypot(r(0, 2), r(1, 2)), r(2, 2));
  const double alpha = std::atan2(r(1, 2), r(0, 2));
  const double gamma = r(2, 2) >= 0.0 ? std::atan2(r(1, 0) - r(0, 1), r(0, 0) + r(1, 1)) - alpha
                                      : alpha - std::atan2(-(r(1, 0) + r(0, 1)), r(1, 1) - r(0, 0));
  std::vector<double> scratch(size_t(sh_count(bands)) * channels);
  turn_about_z(gamma, data, channels, bands);
  x_.apply(data, scratch.data(), channels, bands);
  turn_about_z(beta, scratch.data(), channels, bands);
  x_inverse_.apply(scratch.data(), data, channels, bands);
  turn_about_z(alpha, data, channels, bands);
}

std::vector<double> rotated_sh(const std::vector<double>& coeffs, int order, const glm::dmat3& g, int channels) {
  check_order("rotated_sh: order", order, kMaxShOrder);
  if (channels < 1) throw std::invalid_argument("rotated_sh: channels must be >= 1");
  const size_t expected = static_cast<size_t>(sh_count(order)) * channels;
  if (coeffs.size() != expected) {
    throw std::invalid_argument("rotated_sh: expected " + std::to_string(expected) + " coefficients, got " +
                                std::to_string(coeffs.size()));
  }
  const ShRotation rotation(glm::transpose(g), order);
  std::vector<double> out(expected);
  rotation.apply(coeffs.data(), out.data(), channels);
  return out;
}

}  // namespace sd
