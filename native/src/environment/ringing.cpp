// Ringing of the truncated expansion: the windows σ_l, the error of the displayed (clamped) radiance
// that decides between them, and the automatic choice per lobe, order and environment. Conventions
// and the measure: ringing.h.
#include "sdlighting/ringing.h"

#include "environment/environment_detail.h"
#include "environment/texel_layout.h"
#include "sdlighting/limits.h"
#include "sdlighting/spherical_harmonics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sd {
namespace {

// The grid of lobe axes of displayed_error: 256 × 128 texels (1.4° in θ) resolve B up to l ≈ 128,
// twice the reference order 64.
constexpr int kAxesWidth = 256;
constexpr int kAxesHeight = 128;

// Sloan's λ is searched as t / (s(s+1))², t = 10^(k/4) for k in [kSloanFirst, kSloanLast]: from a top
// band kept to 1e-4 (practically none) to one attenuated a thousandfold.
constexpr int kSloanFirst = -16;
constexpr int kSloanLast = 12;

// The automatic choice takes a window only when it lowers none's error by more than this fraction of
// it: a Sloan window of a vanishing λ is none in effect, and a gain in the fourth digit is not one.
constexpr double kMinimumGain = 0.01;

// Per-row sums of displayed_error, reduced in row order (bit-identical for any thread count).
struct RowSums {
  double tone_error = 0.0, tone_norm = 0.0, error = 0.0, norm = 0.0;
  double min_value = std::numeric_limits<double>::infinity();
  double max_value = -std::numeric_limits<double>::infinity();
};

// The lobe-filtered coefficients f_l ŵ_l L_lm for l <= order (f empty: 1).
std::vector<double> filtered(const std::vector<double>& light, const std::vector<double>& w_hat, int order,
                             const std::vector<double>& f) {
  std::vector<double> out(light.begin(), light.begin() + 3 * sh_count(order));
  for (int l = 0; l <= order; ++l) {
    const double scale = w_hat[l] * (f.empty() ? 1.0 : f[l]);
    for (int q = 3 * l * l; q < 3 * (l + 1) * (l + 1); ++q) out[q] *= scale;
  }
  return out;
}

std::vector<double> window_factors(const RingingWindowSpec& window, int order) {
  std::vector<double> f(order + 1);
  for (int l = 0; l <= order; ++l) f[l] = ringing_window_factor(window, l, order);
  return f;
}

// displayed_error's measure (ringing.h) for one lobe: the full-resolution B on the grid of
// axes, evaluated once, against which any order and window factors are then measured.
class DisplayedError {
 public:
  DisplayedError(const std::vector<double>& light, const ZonalLobe& lobe)
      : light_(light), w_hat_(lobe.coefficients(kMaxEnergyOrder)), mean_{light[0], light[1], light[2]},
        reference_(3 * static_cast<size_t>(kAxesWidth) * kAxesHeight) {
    // Clamped at 0: it is non-negative but for its own, far smaller, ringing.
    evaluate_equirect_rows(filtered(light_, w_hat_, kMaxEnergyOrder, {}), kMaxEnergyOrder, kAxesWidth, kAxesHeight,
                           [&](int j, const double* values) {
                             double* out = reference_.data() + 3 * static_cast<size_t>(j) * kAxesWidth;
                             for (int q = 0; q < 3 * kAxesWidth; ++q) out[q] = std::max(values[q], 0.0);
                           });
  }

  // (tone-mapped error, plain clamped relative RMS, min B̃ / max B̃) of order s with factors f.
  std::array<double, 3> operator()(int order, const std::vector<double>& f) const {
    std::vector<RowSums> rows(kAxesHeight);
    evaluate_equirect_rows(filtered(light_, w_hat_, order, f), order, kAxesWidth, kAxesHeight,
                           [&](int j, const double* values) {
                             RowSums r;
                             const double* ref = reference_.data() + 3 * static_cast<size_t>(j) * kAxesWidth;
                             for (int q = 0; q < 3 * kAxesWidth; ++q) {
                               r.min_value = std::min(r.min_value, values[q]);
                               r.max_value = std::max(r.max_value, values[q]);
                               const double shown = std::max(values[q], 0.0), truth = ref[q];
                               r.error += (shown - truth) * (shown - truth);
                               r.norm += truth * truth;
                               const double key = mean_[q % 3];
                               if (key > 0.0) {
                                 const double t_shown = shown / (shown + key), t_truth = truth / (truth + key);
                                 r.tone_error += (t_shown - t_truth) * (t_shown - t_truth);
                                 r.tone_norm += t_truth * t_truth;
                               }
                             }
                             const double area = equirect_row_solid_angle(j, kAxesWidth, kAxesHeight);
                             r.error *= area;
                             r.norm *= area;
                             r.tone_error *= area;
                             r.tone_norm *= area;
                             rows[j] = r;
                           });
    RowSums total;
    for (const RowSums& r : rows) {
      total.tone_error += r.tone_error;
      total.tone_norm += r.tone_norm;
      total.error += r.error;
      total.norm += r.norm;
      total.min_value = std::min(total.min_value, r.min_value);
      total.max_value = std::max(total.max_value, r.max_value);
    }
    return {total.tone_norm > 0.0 ? std::sqrt(total.tone_error / total.tone_norm) : 0.0,
            total.norm > 0.0 ? std::sqrt(total.error / total.norm) : 0.0,
            total.max_value > 0.0 ? total.min_value / total.max_value : 0.0};
  }

  // The choice's errors for the window spec with factors f, beside none's.
  RingingWindowChoice choice(int order, const RingingWindowSpec& window, const std::vector<double>& f) const {
    RingingWindowChoice out;
    out.window = window;
    out.factors = f;
    const std::array<double, 3> with = (*this)(order, f), without = (*this)(order, std::vector<double>(order + 1, 1.0));
    out.error = with[0];
    out.l2_error = with[1];
    out.min_over_max = with[2];
    out.unwindowed_error = without[0];
    out.unwindowed_l2_error = without[1];
    out.unwindowed_min_over_max = without[2];
    return out;
  }

  // ringing_window on this lobe.
  RingingWindowChoice best_of(int order, RingingWindow window) const {
    if (window != RingingWindow::Sloan || order == 0) return choice(order, window, window_factors(window, order));
    const double scale = static_cast<double>(order) * order * (order + 1.0) * (order + 1.0);
    RingingWindowSpec best(RingingWindow::Sloan, 0.0);
    double best_error = std::numeric_limits<double>::infinity();
    for (int k = kSloanFirst; k <= kSloanLast; ++k) {
      const RingingWindowSpec spec(RingingWindow::Sloan, std::pow(10.0, k / 4.0) / scale);
      const double error = (*this)(order, window_factors(spec, order))[0];
      if (error < best_error) {
        best_error = error;
        best = spec;
      }
    }
    return choice(order, best, window_factors(best, order));
  }

 private:
  const std::vector<double>& light_;
  std::vector<double> w_hat_;
  std::array<double, 3> mean_;  // B̄_c = ŵ_0 L_00,c, the mean of B over the axes
  std::vector<double> reference_;
};

}  // namespace

RingingWindow ringing_window_from_name(const std::string& name) {
  if (name == "none") return RingingWindow::None;
  if (name == "hanning" || name == "hann") return RingingWindow::Hanning;
  if (name == "lanczos") return RingingWindow::Lanczos;
  if (name == "sloan") return RingingWindow::Sloan;
  throw std::invalid_argument("unknown window '" + name + "' (expected 'none', 'hanning', 'lanczos' or 'sloan')");
}

std::string ringing_window_name(RingingWindow window) {
  switch (window) {
    case RingingWindow::Hanning: return "hanning";
    case RingingWindow::Lanczos: return "lanczos";
    case RingingWindow::Sloan: return "sloan";
    default: return "none";
  }
}

double ringing_window_factor(const RingingWindowSpec& window, int l, int order) {
  const double x = static_cast<double>(l) / (order + 1.0);
  switch (window.window) {
    case RingingWindow::Hanning: return 0.5 * (1.0 + std::cos(kPi * x));
    case RingingWindow::Lanczos: return l == 0 ? 1.0 : std::sin(kPi * x) / (kPi * x);
    case RingingWindow::Sloan: return 1.0 / (1.0 + window.sloan_lambda * l * l * (l + 1.0) * (l + 1.0));
    default: return 1.0;
  }
}

RingingWindowChoice displayed_error(const Environment& environment, const ZonalLobe& lobe, int order,
                                    const std::vector<double>& factors) {
  check_order("Environment::displayed_error: order", order, kMaxShadingOrder);
  if (factors.size() != static_cast<size_t>(order + 1)) {
    throw std::invalid_argument("Environment::displayed_error: expected order + 1 = " + std::to_string(order + 1) +
                                " window factors, got " + std::to_string(factors.size()));
  }
  for (double f : factors) {
    if (!std::isfinite(f)) throw std::invalid_argument("Environment::displayed_error: window factors must be finite");
  }
  return DisplayedError(reference_projection(environment).coefficients, lobe).choice(order, RingingWindowSpec(), factors);
}

RingingWindowChoice ringing_window(const Environment& environment, const ZonalLobe& lobe, int order,
                                   RingingWindow window) {
  check_order("Environment::ringing_window: order", order, kMaxShadingOrder);
  return DisplayedError(reference_projection(environment).coefficients, lobe).best_of(order, window);
}

RingingWindowChoice automatic_ringing_window(const Environment& environment, const ZonalLobe& lobe, int order) {
  check_order("Environment::automatic_ringing_window: order", order, kMaxShadingOrder);
  const DisplayedError measure(reference_projection(environment).coefficients, lobe);
  RingingWindowChoice best = measure.best_of(order, RingingWindow::None);
  const double threshold = (1.0 - kMinimumGain) * best.unwindowed_error;
  for (RingingWindow window : {RingingWindow::Hanning, RingingWindow::Lanczos, RingingWindow::Sloan}) {
    RingingWindowChoice candidate = measure.best_of(order, window);
    if (candidate.error < std::min(best.error, threshold)) best = candidate;
  }
  return best;
}

}  // namespace sd
