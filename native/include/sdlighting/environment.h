// Environment maps L (the distant light of eq. (1)): loading through OpenImageIO (load() and load_cube(),
// in the library sdlighting_image_files: the add-on's module links no image library), the texels, their
// masses and norms, area-averaged copies. What is computed from a map has a header per concern:
// sh_projection.h (SH coefficients, band energies, band-limited textures L̃), environment_error.h
// (the error measures that choose the order s), ringing.h (windows against ringing and the error of
// the displayed radiance that chooses them), channel_design.h (weighted designs of a channel).
// Rotation: rotated_sh (sh_rotation.h); importance sampling: environment_sampler.h; the map
// prefiltered by the GGX lobe for glossy light: glossy_prefilter.h.
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
#pragma once

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

/// The lazily computed high-order projection of a map (the reference of band_energies,
/// sh_projection.h), shared by its copies. Private to the library (src/environment/environment_detail.h).
struct ReferenceProjection;

/// A distant environment map, immutable once built. Copies share the lazily computed high-order
/// projection (band_energies, sh_projection.h); every const member, and every function of the
/// headers above that takes a map, is safe to call from several threads at once.
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

 private:
  /// The map's reference projection, computed on the first call (src/environment/projection.cpp).
  friend const ReferenceProjection& reference_projection(const Environment& environment);

  Environment() = default;
  static Environment from_texels(EnvironmentLayout layout, int width, int height, std::vector<float> rgb,
                                 const std::string& origin);

  EnvironmentLayout layout_ = EnvironmentLayout::Equirect;
  int width_ = 0;
  int height_ = 0;
  std::vector<float> rgb_;
  int64_t clamped_negative_pixels_ = 0;
  std::array<double, 4> mass_{};
  std::array<double, 4> norm_squared_{};
  std::shared_ptr<ReferenceProjection> reference_;
};

}  // namespace sd
