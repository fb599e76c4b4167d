// Ringing of the truncated expansion L̃ of an environment map (environment.h): the windows σ_l
// against it, the error of the displayed (clamped) radiance that decides between them, and the
// choice of a window per lobe, order and map. The windowed textures: band_limited (sh_projection.h).
#pragma once

#include "sdlighting/environment.h"
#include "sdlighting/zonal_lobe.h"

#include <string>
#include <vector>

namespace sd {

/// Windows σ_l against ringing of the truncated expansion L̃ = Σ_{l<=s} σ_l L_lm y_lm:
/// None σ_l = 1; Hanning σ_l = (1 + cos(π l/(s+1)))/2; Lanczos σ_l = sinc(l/(s+1)) = sin(πx)/(πx);
/// Sloan σ_l = 1/(1 + λ l²(l+1)²) (P.-P. Sloan, "Stupid Spherical Harmonics (SH) Tricks", GDC 2008,
/// section "Windowing": the minimiser of ‖f̃ − f‖² + λ ‖Δf̃‖², the Laplacian's eigenvalue being −l(l+1)).
enum class RingingWindow { None, Hanning, Lanczos, Sloan };

/// A window with its parameter: Sloan's λ (>= 0; ignored by the others). Converts from a RingingWindow
/// (λ = 0), so a Sloan window needs its λ given explicitly.
struct RingingWindowSpec {
  RingingWindow window = RingingWindow::None;
  double sloan_lambda = 0.0;
  RingingWindowSpec(RingingWindow w = RingingWindow::None, double lambda = 0.0) : window(w), sloan_lambda(lambda) {}
};

/// "none", "hanning" (or "hann"), "lanczos" or "sloan"; throws std::invalid_argument otherwise.
RingingWindow ringing_window_from_name(const std::string& name);

/// The name ringing_window_from_name reads.
std::string ringing_window_name(RingingWindow window);

/// σ_l of the window for band l of an expansion of order `order` (0 <= l <= order).
double ringing_window_factor(const RingingWindowSpec& window, int l, int order);

/// What ringing_window reports: a window for one lobe and order s, and the error of the displayed
/// radiance with it and without (see displayed_error for the measure).
struct RingingWindowChoice {
  RingingWindowSpec window;
  std::vector<double> factors;          // σ_0..σ_s
  double error = 0.0;                   // displayed_error with the window
  double unwindowed_error = 0.0;        // displayed_error with none
  double l2_error = 0.0;                // plain relative RMS of the clamped B, with the window
  double unwindowed_l2_error = 0.0;     // the same with none
  double min_over_max = 0.0;            // min / max of B̃ (not clamped) over axes and channels
  double unwindowed_min_over_max = 0.0; // the same with none: negative = ringing below zero
};

/// The error of the *displayed* unshadowed B of order s with window factors σ_0..σ_order (one per
/// band; order 0..kMaxShadingOrder) against the full-resolution B — the one that decides the window
/// (ringing_window). Both are evaluated per RGB channel c at the centres of a 256 × 128 equirect
/// grid of lobe axes a (the texels' solid angles as weights):
///     B̃_c(a) = Σ_{l<=s} σ_l ŵ_l L_lm y_lm(a),   B_c(a) = Σ_{l<=64} ŵ_l L_lm y_lm(a)  (Funk–Hecke),
/// and compared as displayed: clamped at 0 (D = max(B̃, 0), the live shading's clamp) and through
/// Reinhard's tone curve T_c(x) = x / (x + B̄_c), B̄_c = L_00,c the mean of B over the axes:
///     sqrt( Σ_a Σ_c (T_c(D_c) − T_c(max(B_c, 0)))² Δμ / Σ_a Σ_c T_c(max(B_c, 0))² Δμ ).
/// Why this measure: in plain L² the truncation is the best approximation of order s, so any
/// window loses there; clamping does not change that at first order (lifting a negative lobe
/// towards 0 shows nothing, its cost elsewhere stays), and L² weighs a sun's highlight a thousand
/// times more than the dark side it rings into. What ringing spoils on screen is that dark side
/// (axes shown black, or as rings, next to a bright one), which T, relative to the local
/// brightness above the mean and absolute below it, measures. The plain clamped relative RMS is
/// reported beside it (RingingWindowChoice::l2_error). L_lm: the reference projection of
/// band_energies (sh_projection.h). 0 for a black map. Throws std::invalid_argument for a bad
/// order or size.
RingingWindowChoice displayed_error(const Environment& environment, const ZonalLobe& lobe, int order,
                                    const std::vector<double>& factors);

/// The window for `lobe` and order s (0..kMaxShadingOrder) and its errors (displayed_error):
/// None, Hanning and Lanczos as defined; Sloan with the λ that minimises displayed_error over
/// λ = t / (s(s+1))², t = 10^(k/4), k = −16..12 (t is 1/σ_s − 1: the attenuation of the top band).
RingingWindowChoice ringing_window(const Environment& environment, const ZonalLobe& lobe, int order,
                                   RingingWindow window);

/// The automatic choice: of None, Hanning, Lanczos and Sloan (as ringing_window), the window with
/// the smallest displayed_error; None unless another lowers none's error by more than 1 % of it.
/// Costs about 40 evaluations of order s and one of order 64 on the 256 × 128 grid (0.1–0.4 s on
/// two cores for s = 4..16), plus the reference projection the first time (band_energies).
RingingWindowChoice automatic_ringing_window(const Environment& environment, const ZonalLobe& lobe, int order);

}  // namespace sd
