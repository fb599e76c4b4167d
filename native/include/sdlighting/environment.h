// Environment maps L (the distant light of eq. (1)): loading through OpenImageIO, projection to
// real spherical harmonics, band-limited textures L̃, the error measures that choose the order s
// and weighted designs of a channel. Rotation: rotated_sh (sh_rotation.h); importance sampling:
// environment_sampler.h.
//
// Orientation (Blender/Cycles world, blender-notes "Cycles as a reference"): a direction d is
// seen in an equirectangular image at
//     u = 0.5 − atan2(d.y, d.x) / (2π),   v = 1 − acos(d.z) / π,   v = 0 at the image's BOTTOM row.
// Images are held with the file's top row first (as OpenImageIO reads them), so the pixel in row j
// from the top and column i has the centre direction
//     θ = π (j + 0.5) / H,   φ = atan2(d.y, d.x) = π − 2π (i + 0.5) / W   (wrapped),
// d = (sin θ cos φ, sin θ sin φ, cos θ): +X looks at the horizontal centre, +Y at column W/4,
// +Z at the top row.
//
// Cube maps use the OpenGL face-orientation table (the "major axis" rule of the OpenGL
// specification, section "Cube Map Texture Selection"), applied directly to the world axes of
// Blender (Z up; no Y-up remapping): faces in the order +X, −X, +Y, −Y, +Z, −Z; for a direction
// d with major axis ma,
//     face +X: sc = −z, tc = −y      face −X: sc = +z, tc = −y
//     face +Y: sc = +x, tc = +z      face −Y: sc = +x, tc = −z
//     face +Z: sc = +x, tc = −y      face −Z: sc = −x, tc = −y
//     s = (sc / |ma| + 1) / 2 (column, left to right),  t = (tc / |ma| + 1) / 2 (row, top to bottom).
// A cube map made for a Y-up renderer must have its faces renamed/rotated by the caller.
//
// Internally either layout is a set of texels: a centre direction, an exact solid angle in units
// of dμ = dx/4π (the texels' solid angles sum to 1), and a linear RGB radiance. The map is the
// piecewise-constant function that takes a texel's radiance over the whole texel; radiance(dir)
// looks it up (nearest texel), and every sum over the map runs over these texels: masses and norms
// exactly, SH coefficients with the integral of y_lm over each texel's area (not its value at the
// centre, which makes a small constant map light like a few point lights).
//
// SH convention: spherical_harmonics.h (y_00 = 1, orthonormal for dμ). RGB coefficient arrays
// are coefficient-major, channel-minor: c[3 i + ch] is coefficient i = l² + l + m of channel ch,
// as ShRotation::apply(in, out, 3) and the shading evaluators (shading.h) expect.
#pragma once

#include "sdlighting/limits.h"
#include "sdlighting/spherical_design.h"
#include "sdlighting/zonal_lobe.h"

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace sd {

/// Channel index meaning the luminance Y = 0.2126 R + 0.7152 G + 0.0722 B (Rec. 709 / linear sRGB
/// primaries, as Blender's default scene-linear space) in the functions that take a channel.
constexpr int kLuminance = 3;

/// The luminance weights of R, G, B.
constexpr std::array<double, 3> kLuminanceWeights = {0.2126, 0.7152, 0.0722};

/// The luminance Y of linear RGB.
inline double luminance(double r, double g, double b) {
  return kLuminanceWeights[0] * r + kLuminanceWeights[1] * g + kLuminanceWeights[2] * b;
}

/// The two storage layouts.
enum class EnvironmentLayout { Equirect, Cube };

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

/// What Environment::ringing_window reports: a window for one lobe and order s, and the error of the
/// displayed radiance with it and without (see Environment::displayed_error for the measure).
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

/// What Environment::band_limited reports about L̃ (all in linear radiance).
struct BandLimitedReport {
  std::array<double, 3> min_value{};  // per channel; negative = ringing below zero
  std::array<double, 3> max_value{};  // per channel
  int64_t negative_texels = 0;        // output texels with at least one channel < 0
  double negative_fraction = 0.0;     // negative_texels / (width * height)
  double negative_solid_angle = 0.0;  // μ-measure (dx/4π) covered by those texels, in [0, 1]
};

/// A distant environment map, immutable once built. Copies share the lazily computed high-order
/// projection (band_energies); every const member is safe to call from several threads at once.
class Environment {
 public:
  // ---- construction ----

  /// Loads an equirectangular map (Blender's world orientation, see the file comment) with
  /// OpenImageIO: EXR, HDR, PFM, TIFF, PNG, JPEG, … (subimage 0, full resolution).
  /// Float and half files are taken as linear. Integer files (8 or 16 bit) are decoded from sRGB
  /// with the exact sRGB curve, as Blender does for byte images — unless the file's
  /// "oiio:ColorSpace" attribute names a linear space. One channel (or grey + alpha) is copied to
  /// R, G, B; alpha and any channel after the third are ignored.
  /// Negative values are clamped to 0 and counted (clamped_negative_pixels()).
  /// Throws std::runtime_error naming the path and OpenImageIO's message if the file cannot be
  /// opened or read, and before opening it (stat only: nothing blocks or reads) if it is not a
  /// non-empty regular file — a directory, a FIFO, a device such as /dev/zero; std::invalid_argument
  /// naming the path and the pixel if a value is NaN or infinite or the image is empty.
  static Environment load(const std::string& path);

  /// Loads a cube map from six square images of one size, in the order +X, −X, +Y, −Y, +Z, −Z
  /// (OpenGL face orientation on Blender's world axes, see the file comment). Same decoding and
  /// errors as load(); faces of different or non-square sizes throw std::invalid_argument.
  static Environment load_cube(const std::array<std::string, 6>& faces);

  /// An equirectangular map from linear RGB floats, rows top-first (row j from the top, column
  /// i at rgb[3 (j width + i) + c]) — the file layout, for tests and for Blender's in-memory
  /// images (which are stored bottom-up: flip them first). Throws std::invalid_argument if
  /// width or height < 1, rgb.size() != 3 width height, or a value is NaN or infinite; negative
  /// values are clamped to 0 and counted.
  static Environment from_equirect_pixels(int width, int height, std::vector<float> rgb);

  /// A cube map from linear RGB floats: six faces in the order +X, −X, +Y, −Y, +Z, −Z, each
  /// face_size² pixels rows top-first: rgb[3 ((f face_size + j) face_size + i) + c].
  /// Same checks as from_equirect_pixels.
  static Environment from_cube_pixels(int face_size, std::vector<float> rgb);

  // ---- geometry and data ----

  /// Equirect or Cube.
  EnvironmentLayout layout() const { return layout_; }
  /// Image width (cube: the face size).
  int width() const { return width_; }
  /// Image height (cube: the face size).
  int height() const { return height_; }
  /// Number of texels: width × height, or 6 × face_size² for a cube.
  int64_t texel_count() const { return static_cast<int64_t>(rgb_.size() / 3); }
  /// Pixels that had at least one negative channel (clamped to 0 on load).
  int64_t clamped_negative_pixels() const { return clamped_negative_pixels_; }
  /// The texels' linear RGB, texel-major (texel t at [3t, 3t+3)); equirect texel t = j W + i,
  /// cube texel t = (f N + j) N + i, rows top-first.
  const std::vector<float>& pixels() const { return rgb_; }

  /// Unit centre direction of texel t (0 <= t < texel_count(), unchecked).
  glm::dvec3 texel_direction(int64_t t) const;
  /// Exact solid angle of texel t in units of dμ = dx/4π: equirect (2π/W)(cos θ_top − cos θ_bottom)/(4π),
  /// cube the atan formula Σ ±atan2(a b, √(a²+b²+1)) over the texel's corners, divided by 4π.
  double texel_solid_angle(int64_t t) const;
  /// Linear RGB of texel t.
  glm::dvec3 texel_radiance(int64_t t) const;
  /// The texel containing direction `dir` (finite, non-zero; need not be unit).
  /// Throws std::invalid_argument for a zero or non-finite direction.
  int64_t texel_index(const glm::dvec3& dir) const;
  /// L(dir): the radiance of the texel containing dir (nearest texel, no filtering).
  glm::dvec3 radiance(const glm::dvec3& dir) const { return texel_radiance(texel_index(dir)); }

  /// ∫ L_c dμ = Σ_texels L_c Δμ for channel c in 0..2, or of the luminance for kLuminance
  /// (the average radiance: 1 for a uniform white map). Throws std::invalid_argument for other c.
  double mass(int channel) const;
  /// ‖L_c‖² = ∫ L_c² dμ = Σ_texels L_c² Δμ (channel as for mass()).
  double norm_squared(int channel) const;

  /// An area-averaged copy of the same layout: exact box filter of the piecewise-constant map
  /// (each new texel holds ∫_texel L dμ / Δμ over its own area), so masses are preserved exactly.
  /// Equirect: any width × height >= 1 (separable overlaps in φ and in cos θ). Cube: pass the new
  /// face size as both width and height (overlaps in face coordinates, exact solid angles).
  /// Throws std::invalid_argument for sizes < 1 or a non-square cube size.
  Environment area_averaged(int width, int height) const;

  // ---- spherical harmonics ----

  /// L_lm = ∫ L y_lm dμ = Σ_texels L(texel) ∫_texel y_lm dμ for l <= order (0..kMaxProjectionOrder,
  /// else std::invalid_argument): the exact coefficients of the piecewise-constant map, each texel
  /// integral by a Gauss–Legendre rule sized to the texel (within 1e-5 of max |y_lm| × the mass; a
  /// constant map of any size, down to 1 × 1, gives L_00 = the constant and every other
  /// coefficient below that bound). Returns sh_count(order) × 3 doubles, out[3 i + c].
  /// Multi-threaded on `threads` threads (0: every hardware thread); the result is bit-identical
  /// for every thread count (per-row partial sums reduced in a fixed order). Equirect maps use the
  /// row structure: the azimuthal integrals exactly (sinc factors) once per column, the θ rule
  /// once per row (cost ∝ W H (order+1)); cube maps evaluate y_lm at each texel's rule points
  /// (cost ∝ texels × points × (order+1)², 4 points per texel from face 128 on).
  std::vector<double> sh(int order, int threads = 0) const;

  /// Band-limited L̃(d) = Σ_{l<=order} σ_l L_lm y_lm(d) (the seed's partial sum of order s, windowed
  /// by σ_l against ringing) — the L̃ that eqs. (12) and (13) look up, stored as a texture as comment 1
  /// to Theorem 2.1 suggests — sampled at the centres of a width × height equirectangular texture in
  /// the same orientation, rows top-first: 3 floats per texel, rgb[3 (j width + i) + c] — ready
  /// for a float texture (L̃ is not clamped: negative lobes are kept and reported).
  /// order 0..kMaxEnergyOrder; coefficients from sh(order) for order <= kMaxProjectionOrder,
  /// otherwise from the reference projection (see band_energies); then band_limited_texture.
  /// If `report` is non-null it receives the minima/maxima and the negative texels of L̃.
  /// Throws std::invalid_argument for an order out of range or a size < 1 (or above 16384).
  std::vector<float> band_limited(int order, int width, int height, const RingingWindowSpec& window = {},
                                  BandLimitedReport* report = nullptr) const;

  /// Per-band energies E_l = Σ_m L_lm² for l = 0..lmax (lmax in 0..kMaxEnergyOrder), channels
  /// R, G, B and the luminance: out[4 l + c]. Rotation invariant. Computed once (lazily, cached)
  /// from the reference projection of order kMaxEnergyOrder: of the map itself when it has at
  /// most 4096 × 2048 texels (equirect) or a face of at most 128 (cube); of an area_averaged copy
  /// reduced to that otherwise. Box-filtering over texels of angular width h attenuates band l by
  /// about l(l+1)h²/12 in energy: < 1e-3 at l = 64 for the 4096-wide equirect copy, about 2 % at
  /// l = 32 for the face-128 cube copy — negligible in the lobe-filtered errors, whose factors ŵ_l²
  /// are below 1e-7 (Lambert) and 1e-17 (Phong σ = 32) from l = 32 on.
  std::vector<double> band_energies(int lmax) const;

  /// The seed's low-frequency measure ε(s) = ‖L − L̃_s‖ / ‖L‖ in L²(dμ) (the condition stated before
  /// Theorem 1.1, whose bound |B − B̄| <= ε ‖L‖ ‖ρ̂‖ uses eqs. (6)–(7)) for one channel (0..2 or
  /// kLuminance), exact via Parseval: ‖L − L̃_s‖² = ‖L‖² − Σ_{l<=s} E_l, with ‖L‖² = Σ L² Δμ over
  /// the texels of the map the energies were projected from. order in 0..kMaxEnergyOrder.
  /// Returns 0 for a black channel.
  double low_frequency_error(int order, int channel = kLuminance) const;

  /// The error that really decides s (msd-notes, "Facts worth knowing"): the relative RMS over
  /// lobe axes a ∈ S² of the truncation error B − B̄ of eq. (6) for V = 1, i.e. of the unshadowed
  /// B(a) = Σ_lm ŵ_l L_lm y_lm(a) (Funk–Hecke) cut at l <= s, on luminance:
  ///     sqrt( Σ_{order<l<=64} ŵ_l² E_l / Σ_{l<=64} ŵ_l² E_l ),
  /// since ∫ (B − B̃_s)² dμ(a) = Σ_{l>s} ŵ_l² E_l. order in 0..kMaxEnergyOrder. 0 for a black map.
  /// The neglected tail Σ_{l>64} ŵ_l² E_l has factors ŵ_l² < 1e-19 for Phong σ <= 100 (< 2e-13 for
  /// σ = 150, < 3e-9 for Lambert); for much narrower lobes the error is underestimated (it is then
  /// close to 1 anyway).
  double lobe_filtered_error(const ZonalLobe& lobe, int order) const;

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
  /// band_energies. 0 for a black map. Throws std::invalid_argument for a bad order or size.
  RingingWindowChoice displayed_error(const ZonalLobe& lobe, int order, const std::vector<double>& factors) const;

  /// The window for `lobe` and order s (0..kMaxShadingOrder) and its errors (displayed_error):
  /// None, Hanning and Lanczos as defined; Sloan with the λ that minimises displayed_error over
  /// λ = t / (s(s+1))², t = 10^(k/4), k = −16..12 (t is 1/σ_s − 1: the attenuation of the top band).
  RingingWindowChoice ringing_window(const ZonalLobe& lobe, int order, RingingWindow window) const;

  /// The automatic choice: of None, Hanning, Lanczos and Sloan (as ringing_window), the window with
  /// the smallest displayed_error; None unless another lowers none's error by more than 1 % of it.
  /// Costs about 40 evaluations of order s and one of order 64 on the 256 × 128 grid (0.1–0.4 s on
  /// two cores for s = 4..16), plus the reference projection the first time (band_energies).
  RingingWindowChoice automatic_ringing_window(const ZonalLobe& lobe, int order) const;

  /// The smallest s in [0, max_order] with lobe_filtered_error(lobe, s) <= target_error, or −1
  /// if none reaches it. max_order in 0..kMaxEnergyOrder; target_error finite and >= 0.
  int smallest_order(const ZonalLobe& lobe, double target_error, int max_order) const;

  /// A weighted spherical design of `degree` (0..kMaxDesignDegree) for one channel (0..2 or
  /// kLuminance) of the environment, i.e. for the measure L_c dμ (the seed's comment 3 and
  /// Table 2): sd::weighted_design on an area-averaged copy of about 2000 texels (equirect
  /// 64 × 32, cube face 18; the map itself when it is already that small), with nodes at texel
  /// centres and weights L_c Δμ, so the design's moments are those of the copy: they match the
  /// full map's L_lm up to the box filter's attenuation (about l(l+1)h²/24, h ≈ 0.1 rad: ~1 %
  /// at l = 4). Certified to kDesignTolerance against the copy's moments. Throws
  /// std::invalid_argument for a bad channel or degree or a black channel, std::runtime_error
  /// if no design certifies.
  SphericalDesign channel_design(int channel, int degree) const;

 private:
  struct EnergyCache;

  Environment() = default;
  static Environment from_texels(EnvironmentLayout layout, int width, int height, std::vector<float> rgb,
                                 const std::string& origin);
  const EnergyCache& energy_cache() const;

  EnvironmentLayout layout_ = EnvironmentLayout::Equirect;
  int width_ = 0;
  int height_ = 0;
  std::vector<float> rgb_;
  int64_t clamped_negative_pixels_ = 0;
  std::array<double, 4> mass_{};
  std::array<double, 4> norm_squared_{};
  std::shared_ptr<EnergyCache> cache_;
};

/// The texture of Environment::band_limited from given RGB coefficients (layout as sh(), e.g.
/// already rotated by rotated_sh): L̃(d) = Σ_{l<=order} σ_l c_lm y_lm(d) at the texel centres of
/// a width × height equirect image in the file comment's orientation, rows top-first, 3 floats
/// per texel; `report` (if non-null) as for band_limited. order in 0..kMaxEnergyOrder, sizes in
/// [1, 16384], coefficients finite and sh_count(order) × 3 of them, and every value within the
/// float32 range of the texture (huge coefficients overflow it); std::invalid_argument otherwise. Multi-threaded over rows; cost ∝ width × height × (order+1).
std::vector<float> band_limited_texture(const std::vector<double>& coefficients, int order, int width, int height,
                                        const RingingWindowSpec& window = {},
                                        BandLimitedReport* report = nullptr);

/// Σ_{l<=order} Σ_m c_lm y_lm(dir) for the three channels of RGB coefficients (layout as sh()).
/// `dir` must be unit.
glm::dvec3 evaluate_sh_rgb(const std::vector<double>& coeffs, int order, const glm::dvec3& dir);

}  // namespace sd
