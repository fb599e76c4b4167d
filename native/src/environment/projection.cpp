// The SH side of an environment (sh_projection.h): projection to SH coefficients (eq. (1)'s L_lm),
// the reference projection and its band energies, band-limited textures L̃ (eqs. (12), (13)).
// Conventions: environment.h and sh_projection.h.
#include "sdlighting/sh_projection.h"

#include "environment/environment_detail.h"
#include "environment/texel_layout.h"
#include "sdlighting/gauss_quadrature.h"
#include "sdlighting/limits.h"
#include "sdlighting/spherical_harmonics.h"
#include "util/number_string.h"
#include "util/parallel_for.h"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace sd {
namespace {

// The reference copy for the high-order projection (band_energies): see sh_projection.h.
constexpr int64_t kReferenceEquirectTexels = int64_t(4096) * 2048;
constexpr int kReferenceCubeFace = 128;

// cos(mφ_i) and sin(mφ_i) of every equirect column i, m < mc, stored by column: [i mc + m].
struct AzimuthTables {
  std::vector<double> cos, sin;
  AzimuthTables(int width, int mc) : cos(static_cast<size_t>(width) * mc), sin(static_cast<size_t>(width) * mc) {
    for (int i = 0; i < width; ++i) {
      const double phi = equirect_phi(i, width);
      for (int m = 0; m < mc; ++m) {
        cos[static_cast<size_t>(i) * mc + m] = std::cos(m * phi);
        sin[static_cast<size_t>(i) * mc + m] = std::sin(m * phi);
      }
    }
  }
};

// ---- texels as areas ----
// The map is piecewise constant (environment.h), so L_lm = Σ_texels L ∫_texel y_lm dμ. Taking
// y_lm at the texel centre instead (the midpoint rule) is wrong by O((l h)²) for texels of angular
// size h: a 2 × 1 constant map then lit like two point lights. Each texel integral is a Gauss–Legendre
// rule per texel side instead, with as many points as the texel's size and the order need.

// The error bound texel_rule_points meets, relative to h max |f|. Each coefficient of a map is
// then within kTexelRuleTolerance × max |y_lm| × its mass (|y_lm| <= √(2l+1)) of the exact integral
// of the piecewise-constant map; the midpoint rule is off by ~(kh)²/24: 3 % for order 16 on a
// 64 × 32 map, 100 % on a 4 × 2 one.
constexpr double kTexelRuleTolerance = 1e-5;

// The fewest points n of a Gauss–Legendre rule whose error on an interval of length h, for a
// function whose derivatives grow like k^n (a trigonometric polynomial of degree k: Bernstein's
// inequality), is within kTexelRuleTolerance of h max |f|: the rule's error term
// h^{2n+1} (n!)⁴ / ((2n+1) ((2n)!)³) max |f^{(2n)}|.
int texel_rule_points(double k_times_h) {
  for (int n = 1;; ++n) {
    const double log_error = 2.0 * n * std::log(std::max(k_times_h, 1e-300)) + 4.0 * std::lgamma(n + 1.0) -
                             std::log(2.0 * n + 1.0) - 3.0 * std::lgamma(2.0 * n + 1.0);
    if (log_error <= std::log(kTexelRuleTolerance)) return n;
  }
}

// The n-point Gauss–Legendre rule on [0, 1] (weights summing to 1).
Rule1D unit_gauss_rule(int n) { return gauss_rule(jacobi_recurrence_unit_interval(0.0, n), n); }

// For every l <= order, m >= 0: the integral over any texel of equirect row j of y_l,±m, divided by
// {cos, sin}(m φ_i) at the texel's centre column φ_i:
//     (1/4π) ∫_{θ_j}^{θ_j+1} P̄_lm(θ) sin θ dθ × (2π/W) sinc(m π/W),
// with P̄_lm = y_l,+m at φ = 0 (spherical_harmonics.h) and ∫ cos m(φ_i + u) du over |u| <= π/W =
// (2π/W) sinc(mπ/W) cos mφ_i (likewise sin). P̄_lm(θ) sin θ is a trigonometric polynomial of degree
// l + 1 in θ, so the θ rule follows texel_rule_points; it is scaled to give the exact solid angle
// for l = 0. out[l² + l + m] for m >= 0 (entries m < 0 are scratch).
void equirect_row_integrals(int j, int width, int height, int order, const Rule1D& rule, double* out) {
  const int k = sh_count(order);
  std::fill(out, out + k, 0.0);
  std::vector<double> p(k);
  const double theta0 = kPi * j / height, span = kPi / height;
  for (size_t q = 0; q < rule.nodes.size(); ++q) {
    const double theta = theta0 + span * rule.nodes[q];
    sh_basis(order, glm::dvec3(std::sin(theta), 0.0, std::cos(theta)), p.data());
    const double w = rule.weights[q] * std::sin(theta);
    for (int i = 0; i < k; ++i) out[i] += w * p[i];
  }
  const double scale = equirect_row_solid_angle(j, width, height) / out[0];
  for (int l = 0; l <= order; ++l) {
    for (int m = 0; m <= l; ++m) {
      // sin(mπ/W) is 0 exactly when W divides m: the texel spans whole periods.
      const double x = kPi * m / width;
      const double sinc = m == 0 ? 1.0 : m % width == 0 ? 0.0 : std::sin(x) / x;
      out[l * l + l + m] *= scale * sinc;
    }
  }
}

// Coefficient-major RGB: out[3 i + c]. Cost ∝ W H (order+1) + H n (order+1)², n the points of each
// row's θ rule; bit-identical for any thread count: every row's azimuthal sums are computed by one
// thread, then combined in row order.
std::vector<double> project_equirect(const float* rgb, int width, int height, int order, int threads) {
  const int mc = order + 1;  // number of m >= 0
  const int k = sh_count(order);
  const AzimuthTables azimuth(width, mc);
  // Per row j: Σ_i L_c cos(mφ_i) and Σ_i L_c sin(mφ_i), six arrays of mc: (cos R, G, B, sin R, G, B).
  std::vector<double> sums(static_cast<size_t>(height) * 6 * mc, 0.0);
  parallel_for(
      static_cast<size_t>(height), 4,
      [&](size_t j0, size_t j1) {
        for (size_t j = j0; j < j1; ++j) {
          double* __restrict cr = sums.data() + j * 6 * mc;
          double* __restrict cg = cr + mc;
          double* __restrict cb = cg + mc;
          double* __restrict sr = cb + mc;
          double* __restrict sg = sr + mc;
          double* __restrict sb = sg + mc;
          const float* row = rgb + j * 3 * static_cast<size_t>(width);
          for (int i = 0; i < width; ++i) {
            const double r = row[3 * i], g = row[3 * i + 1], b = row[3 * i + 2];
            if (r == 0.0 && g == 0.0 && b == 0.0) continue;
            const double* __restrict ct = azimuth.cos.data() + static_cast<size_t>(i) * mc;
            const double* __restrict st = azimuth.sin.data() + static_cast<size_t>(i) * mc;
            for (int m = 0; m < mc; ++m) {
              cr[m] += ct[m] * r;
              cg[m] += ct[m] * g;
              cb[m] += ct[m] * b;
              sr[m] += st[m] * r;
              sg[m] += st[m] * g;
              sb[m] += st[m] * b;
            }
          }
        }
      },
      ParallelOptions(threads));

  // The rule resolves kMaxEnergyOrder whatever the order (a few points per row at most sizes), so
  // sh(s) and the band energies' order-64 projection agree to rounding.
  const Rule1D rule = unit_gauss_rule(texel_rule_points((kMaxEnergyOrder + 1) * kPi / height));
  std::vector<double> out(static_cast<size_t>(k) * 3, 0.0), row(k);
  for (int j = 0; j < height; ++j) {
    equirect_row_integrals(j, width, height, order, rule, row.data());
    const double* s = sums.data() + static_cast<size_t>(j) * 6 * mc;
    for (int l = 0; l <= order; ++l) {
      const int center = l * l + l;
      for (int m = 0; m <= l; ++m) {
        const double w = row[center + m];
        double* plus = out.data() + 3 * (center + m);
        for (int c = 0; c < 3; ++c) plus[c] += w * s[c * mc + m];
        if (m > 0) {
          double* minus = out.data() + 3 * (center - m);
          for (int c = 0; c < 3; ++c) minus[c] += w * s[(3 + c) * mc + m];
        }
      }
    }
  }
  return out;
}

// Cube maps: the integral of y_lm over each texel by a product Gauss–Legendre rule in the face
// coordinates (a, b), whose area element on the sphere is da db / (1 + a² + b²)^{3/2}. The
// direction turns by at most h over a texel side of length h, so y_lm varies like a trigonometric
// polynomial of degree l there; the area element's poles at a² + b² = −1 limit big texels, which
// are cut into panels of at most kCubePanel first. Each texel's weights are scaled to its exact
// solid angle. The rule costs points² basis evaluations per texel (4 on a face-128 map), so it
// resolves the first kMaxProjectionOrder bands whatever the order: the bands above feed only
// band_energies' order-64 projection, where the face-128 copy's box filter already attenuates them
// by percents (sh_projection.h); and sh(s) agrees with that projection to rounding. Fixed blocks of texel rows (independent of the thread count) are summed by one
// thread each, then reduced in block order: bit-identical for any thread count.
constexpr double kCubePanel = 0.25;

std::vector<double> project_cube(const float* rgb, int n, int order, int threads) {
  const int k = sh_count(order);
  const double side = 2.0 / n;  // a texel's side in face coordinates
  const int panels = static_cast<int>(std::ceil(side / kCubePanel - 1e-9));
  const double panel = side / panels;
  const Rule1D base = unit_gauss_rule(texel_rule_points((kMaxProjectionOrder + 1) * panel));
  Rule1D rule;  // on [0, 1], panels × base
  for (int p = 0; p < panels; ++p) {
    for (size_t q = 0; q < base.nodes.size(); ++q) {
      rule.nodes.push_back((p + base.nodes[q]) / panels);
      rule.weights.push_back(base.weights[q] / panels);
    }
  }
  const int points = static_cast<int>(rule.nodes.size());
  const int rows = 6 * n;
  const int rows_per_block = std::max(1, (rows + 63) / 64);
  const int blocks = (rows + rows_per_block - 1) / rows_per_block;
  std::vector<double> partial(static_cast<size_t>(blocks) * 3 * k, 0.0);
  parallel_for(
      static_cast<size_t>(blocks), 1,
      [&](size_t b0, size_t b1) {
        std::vector<double> y(k), weights(static_cast<size_t>(points) * points);
        for (size_t block = b0; block < b1; ++block) {
          double* __restrict ar = partial.data() + block * 3 * k;
          double* __restrict ag = ar + k;
          double* __restrict ab = ag + k;
          const int row_end = std::min(rows, static_cast<int>(block + 1) * rows_per_block);
          for (int row = static_cast<int>(block) * rows_per_block; row < row_end; ++row) {
            const int face = row / n, j = row % n;
            for (int i = 0; i < n; ++i) {
              const float* px = rgb + 3 * (static_cast<size_t>(row) * n + i);
              if (px[0] == 0.0f && px[1] == 0.0f && px[2] == 0.0f) continue;
              const glm::dvec2 corner(cube_edge(i, n), cube_edge(j, n));
              double area = 0.0;
              for (int qb = 0; qb < points; ++qb) {
                for (int qa = 0; qa < points; ++qa) {
                  const glm::dvec2 c = corner + side * glm::dvec2(rule.nodes[qa], rule.nodes[qb]);
                  const double r2 = 1.0 + c.x * c.x + c.y * c.y;
                  weights[qb * points + qa] = rule.weights[qa] * rule.weights[qb] / (r2 * std::sqrt(r2));
                  area += weights[qb * points + qa];
                }
              }
              const double scale = cube_texel_solid_angle(i, j, n) / area;
              for (int qb = 0; qb < points; ++qb) {
                for (int qa = 0; qa < points; ++qa) {
                  const glm::dvec2 c = corner + side * glm::dvec2(rule.nodes[qa], rule.nodes[qb]);
                  sh_basis(order, glm::normalize(cube_face_direction(face, c.x, c.y)), y.data());
                  const double w = weights[qb * points + qa] * scale;
                  const double r = px[0] * w, g = px[1] * w, b = px[2] * w;
                  for (int q = 0; q < k; ++q) {
                    ar[q] += y[q] * r;
                    ag[q] += y[q] * g;
                    ab[q] += y[q] * b;
                  }
                }
              }
            }
          }
        }
      },
      ParallelOptions(threads));
  std::vector<double> out(static_cast<size_t>(k) * 3, 0.0);
  for (int block = 0; block < blocks; ++block) {
    const double* a = partial.data() + static_cast<size_t>(block) * 3 * k;
    for (int q = 0; q < k; ++q) {
      for (int c = 0; c < 3; ++c) out[3 * q + c] += a[c * k + q];
    }
  }
  return out;
}

std::vector<double> project(const Environment& environment, int order, int threads) {
  return environment.layout() == EnvironmentLayout::Equirect
             ? project_equirect(environment.pixels().data(), environment.width(), environment.height(), order, threads)
             : project_cube(environment.pixels().data(), environment.width(), order, threads);
}

void check_output_size(const char* what, int width, int height) {
  check_range(std::string(what) + ": width", width, 1, kMaxTextureSide);
  check_range(std::string(what) + ": height", height, 1, kMaxTextureSide);
}

}  // namespace

std::vector<double> sh(const Environment& environment, int order, int threads) {
  check_order("Environment::sh: order", order, kMaxProjectionOrder);
  return project(environment, order, threads);
}

const ReferenceProjection& reference_projection(const Environment& environment) {
  ReferenceProjection& cache = *environment.reference_;
  std::lock_guard<std::mutex> lock(cache.mutex);
  if (cache.ready) return cache;
  // The reference copy (sh_projection.h, band_energies).
  const Environment* source = &environment;
  std::optional<Environment> reduced;
  const int64_t texels = environment.texel_count();
  if (environment.layout() == EnvironmentLayout::Equirect && texels > kReferenceEquirectTexels) {
    const double scale = std::sqrt(static_cast<double>(texels) / kReferenceEquirectTexels);
    reduced = environment.area_averaged(std::max(1, static_cast<int>(environment.width() / scale)),
                                        std::max(1, static_cast<int>(environment.height() / scale)));
    source = &*reduced;
  } else if (environment.layout() == EnvironmentLayout::Cube && environment.width() > kReferenceCubeFace) {
    reduced = environment.area_averaged(kReferenceCubeFace, kReferenceCubeFace);
    source = &*reduced;
  }
  std::vector<double> coefficients = project(*source, kMaxEnergyOrder, 0);
  std::vector<double> energies(static_cast<size_t>(kMaxEnergyOrder + 1) * 4, 0.0);
  for (int l = 0; l <= kMaxEnergyOrder; ++l) {
    for (int m = -l; m <= l; ++m) {
      const double* c = coefficients.data() + 3 * sh_index(l, m);
      const double y = luminance(c[0], c[1], c[2]);
      for (int ch = 0; ch < 3; ++ch) energies[4 * l + ch] += c[ch] * c[ch];
      energies[4 * l + 3] += y * y;
    }
  }
  cache.coefficients = std::move(coefficients);
  cache.energies = std::move(energies);
  cache.norm_squared = source->norm_squared_;
  cache.ready = true;
  return cache;
}

std::vector<float> band_limited(const Environment& environment, int order, int width, int height,
                                const RingingWindowSpec& window, BandLimitedReport* report) {
  check_order("Environment::band_limited: order", order, kMaxEnergyOrder);
  check_output_size("Environment::band_limited", width, height);
  std::vector<double> coefficients;
  if (order <= kMaxProjectionOrder) {
    coefficients = sh(environment, order);
  } else {
    const auto& all = reference_projection(environment).coefficients;
    coefficients.assign(all.begin(), all.begin() + 3 * sh_count(order));
  }
  return band_limited_texture(coefficients, order, width, height, window, report);
}

std::vector<double> band_energies(const Environment& environment, int lmax) {
  check_order("Environment::band_energies: lmax", lmax, kMaxEnergyOrder);
  const auto& energies = reference_projection(environment).energies;
  return std::vector<double>(energies.begin(), energies.begin() + 4 * (lmax + 1));
}

std::vector<float> band_limited_texture(const std::vector<double>& sh_coefficients, int order, int width, int height,
                                        const RingingWindowSpec& window, BandLimitedReport* report) {
  check_order("band_limited_texture: order", order, kMaxEnergyOrder);
  check_output_size("band_limited_texture", width, height);
  const int k = sh_count(order), mc = order + 1;
  // The texture, and the azimuth tables of every column.
  check_allocation("band_limited_texture: a " + std::to_string(width) + " x " + std::to_string(height) + " texture",
                   12.0 * width * height + 16.0 * width * mc);
  if (sh_coefficients.size() != static_cast<size_t>(3 * k)) {
    throw std::invalid_argument("band_limited_texture: expected 3 (order+1)^2 = " + std::to_string(3 * k) +
                                " coefficients, got " + std::to_string(sh_coefficients.size()));
  }
  for (double c : sh_coefficients) {
    if (!std::isfinite(c)) throw std::invalid_argument("band_limited_texture: coefficients contain NaN or infinity");
  }
  std::vector<double> coefficients = sh_coefficients;
  // Windowed coefficients σ_l L_lm.
  for (int l = 0; l <= order; ++l) {
    const double sigma = ringing_window_factor(window, l, order);
    for (int q = 3 * l * l; q < 3 * (l + 1) * (l + 1); ++q) coefficients[q] *= sigma;
  }
  std::vector<float> rgb(static_cast<size_t>(width) * height * 3);
  // Per-row statistics, reduced in row order afterwards.
  std::vector<std::array<double, 6>> row_extrema(height);
  std::vector<int64_t> row_negative(height, 0);
  std::vector<char> row_overflow(height, 0);  // a value beyond float32 (or inf/NaN in double)
  evaluate_equirect_rows(coefficients, order, width, height, [&](int j, const double* values) {
    std::array<double, 6> extrema = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                                     std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                                     -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    int64_t negative = 0;
    float* out = rgb.data() + j * 3 * static_cast<size_t>(width);
    for (int i = 0; i < width; ++i) {
      bool below = false;
      for (int c = 0; c < 3; ++c) {
        const double v = values[3 * i + c];
        out[3 * i + c] = static_cast<float>(v);
        if (!(std::abs(v) <= std::numeric_limits<float>::max())) row_overflow[j] = 1;
        extrema[c] = std::min(extrema[c], v);
        extrema[3 + c] = std::max(extrema[3 + c], v);
        below = below || v < 0.0;
      }
      negative += below ? 1 : 0;
    }
    row_extrema[j] = extrema;
    row_negative[j] = negative;
  });
  if (std::find(row_overflow.begin(), row_overflow.end(), 1) != row_overflow.end()) {
    double largest = 0.0;
    for (double c : sh_coefficients) largest = std::max(largest, std::abs(c));
    throw std::invalid_argument("band_limited_texture: the band-limited values exceed the float32 range (3.4e38) of a "
                                "texture: the coefficients are too large (largest |c| = " + number_string(largest) +
                                ")");
  }
  if (report != nullptr) {
    BandLimitedReport r;
    r.min_value.fill(std::numeric_limits<double>::infinity());
    r.max_value.fill(-std::numeric_limits<double>::infinity());
    for (int j = 0; j < height; ++j) {
      for (int c = 0; c < 3; ++c) {
        r.min_value[c] = std::min(r.min_value[c], row_extrema[j][c]);
        r.max_value[c] = std::max(r.max_value[c], row_extrema[j][3 + c]);
      }
      r.negative_texels += row_negative[j];
      r.negative_solid_angle += row_negative[j] * equirect_row_solid_angle(j, width, height);
    }
    r.negative_fraction = static_cast<double>(r.negative_texels) / (static_cast<double>(width) * height);
    *report = r;
  }
  return rgb;
}

void evaluate_equirect_rows(const std::vector<double>& coefficients, int order, int width, int height,
                            const std::function<void(int, const double*)>& row) {
  const int k = sh_count(order), mc = order + 1;
  const AzimuthTables azimuth(width, mc);
  parallel_for(static_cast<size_t>(height), 4, [&](size_t j0, size_t j1) {
    std::vector<double> p(k), a(6 * static_cast<size_t>(mc)), values(3 * static_cast<size_t>(width));
    for (size_t j = j0; j < j1; ++j) {
      const double theta = equirect_theta(static_cast<int>(j), height);
      sh_basis(order, glm::dvec3(std::sin(theta), 0.0, std::cos(theta)), p.data());
      // a[c mc + m] = Σ_l c_l,+m P̄_lm;  a[(3+c) mc + m] = Σ_l c_l,−m P̄_lm.
      std::fill(a.begin(), a.end(), 0.0);
      for (int l = 0; l <= order; ++l) {
        const int center = l * l + l;
        for (int m = 0; m <= l; ++m) {
          const double pl = p[center + m];
          for (int c = 0; c < 3; ++c) a[c * mc + m] += pl * coefficients[3 * (center + m) + c];
          if (m > 0) {
            for (int c = 0; c < 3; ++c) a[(3 + c) * mc + m] += pl * coefficients[3 * (center - m) + c];
          }
        }
      }
      for (int i = 0; i < width; ++i) {
        const double* ct = azimuth.cos.data() + static_cast<size_t>(i) * mc;
        const double* st = azimuth.sin.data() + static_cast<size_t>(i) * mc;
        for (int c = 0; c < 3; ++c) {
          const double* ac = a.data() + c * mc;
          const double* as = a.data() + (3 + c) * mc;
          double v = 0.0;
          for (int m = 0; m < mc; ++m) v += ac[m] * ct[m] + as[m] * st[m];
          values[3 * i + c] = v;
        }
      }
      row(static_cast<int>(j), values.data());
    }
  });
}

glm::dvec3 evaluate_sh_rgb(const std::vector<double>& coeffs, int order, const glm::dvec3& dir) {
  const int k = sh_count(order);
  if (order < 0 || coeffs.size() < static_cast<size_t>(k) * 3) {
    throw std::invalid_argument("evaluate_sh_rgb: need 3 (order+1)^2 coefficients");
  }
  std::vector<double> y(k);
  sh_basis(order, dir, y.data());
  glm::dvec3 sum(0.0);
  for (int q = 0; q < k; ++q) sum += y[q] * glm::dvec3(coeffs[3 * q], coeffs[3 * q + 1], coeffs[3 * q + 2]);
  return sum;
}

}  // namespace sd
