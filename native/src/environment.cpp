// Environment maps: loading (OpenImageIO), SH projection, band-limited textures, error measures,
// designs of a channel and importance sampling. Conventions and equations: environment.h and
// msd-notes (equation numbers are the seed's).
#include "sdlighting/environment.h"

#include "parallel_for.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/weighted_design.h"

#include <OpenImageIO/imageio.h>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <utility>

namespace sd {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Guards against absurd allocations (and int overflow of texel indices in the bindings).
constexpr int kMaxImageSide = 65536;
constexpr int64_t kMaxTexels = int64_t(1) << 28;

// The reference copy for the high-order projection (band_energies): see environment.h.
constexpr int64_t kReferenceEquirectTexels = int64_t(4096) * 2048;
constexpr int kReferenceCubeFace = 128;

// channel_design's area-averaged copy.
constexpr int kDesignEquirectWidth = 64;
constexpr int kDesignEquirectHeight = 32;
constexpr int kDesignCubeFace = 18;

// Uniform share of EnvironmentSampler's texel distribution.
constexpr double kUniformShare = 0.01;

const char* const kFaceNames[6] = {"+X", "-X", "+Y", "-Y", "+Z", "-Z"};

double luminance(double r, double g, double b) {
  return kLuminanceWeights[0] * r + kLuminanceWeights[1] * g + kLuminanceWeights[2] * b;
}

// cos a − cos b = 2 sin((a+b)/2) sin((b−a)/2), without the cancellation near the poles.
double cos_difference(double a, double b) { return 2.0 * std::sin(0.5 * (a + b)) * std::sin(0.5 * (b - a)); }

// ---- equirect geometry (environment.h: θ = π (j+0.5)/H, φ = π − 2π (i+0.5)/W) ----

double equirect_theta(int j, int height) { return kPi * (j + 0.5) / height; }

// π (W − 2i − 1)/W: an integer numerator, so the centre column of an odd width is exactly φ = 0.
double equirect_phi(int i, int width) { return kPi * static_cast<double>(width - 2 * i - 1) / width; }

// Δμ of every texel of row j: (2π/W)(cos θ_top − cos θ_bottom)/(4π).
double equirect_row_solid_angle(int j, int width, int height) {
  return cos_difference(kPi * j / height, kPi * (j + 1.0) / height) / (2.0 * width);
}

glm::dvec3 spherical_direction(double theta, double phi) {
  const double st = std::sin(theta);
  return {st * std::cos(phi), st * std::sin(phi), std::cos(theta)};
}

void check_direction(const glm::dvec3& d) {
  if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z)) {
    throw std::invalid_argument("direction contains NaN or infinity");
  }
  if (d.x == 0.0 && d.y == 0.0 && d.z == 0.0) throw std::invalid_argument("direction is the zero vector");
}

// (row, column) of the equirect texel holding d (any length > 0).
std::pair<int, int> equirect_cell(const glm::dvec3& d, int width, int height) {
  const double phi = std::atan2(d.y, d.x);
  const double u = 0.5 - phi / (2.0 * kPi);  // in [0, 1]
  int i = static_cast<int>(std::floor(u * width));
  if (i >= width) i -= width;
  i = std::clamp(i, 0, width - 1);
  const double theta = std::atan2(std::hypot(d.x, d.y), d.z);  // in [0, π]
  const int j = std::clamp(static_cast<int>(std::floor(theta / kPi * height)), 0, height - 1);
  return {j, i};
}

// ---- cube geometry (environment.h: the OpenGL face table on Blender's axes) ----

// The (unnormalised) direction of face coordinates (a, b) = (sc, tc) in [−1, 1]² on face f.
glm::dvec3 cube_face_direction(int face, double a, double b) {
  switch (face) {
    case 0: return {1.0, -b, -a};
    case 1: return {-1.0, -b, a};
    case 2: return {a, 1.0, b};
    case 3: return {a, -1.0, -b};
    case 4: return {a, -b, 1.0};
    default: return {-a, -b, -1.0};
  }
}

struct FaceCoordinates {
  int face;
  double a, b;  // sc/|ma|, tc/|ma| in [−1, 1]
};

FaceCoordinates cube_face_coordinates(const glm::dvec3& d) {
  const double ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
  if (ax >= ay && ax >= az) {
    return d.x > 0.0 ? FaceCoordinates{0, -d.z / ax, -d.y / ax} : FaceCoordinates{1, d.z / ax, -d.y / ax};
  }
  if (ay >= az) {
    return d.y > 0.0 ? FaceCoordinates{2, d.x / ay, d.z / ay} : FaceCoordinates{3, d.x / ay, -d.z / ay};
  }
  return d.z > 0.0 ? FaceCoordinates{4, d.x / az, -d.y / az} : FaceCoordinates{5, -d.x / az, -d.y / az};
}

// Face coordinate of grid line k of an n-texel face: 2k/n − 1.
double cube_edge(int k, int n) { return 2.0 * k / n - 1.0; }

// Solid angle (steradians) of the face-coordinate rectangle [a0, a1] × [b0, b1]:
// ∫∫ da db / (1 + a² + b²)^{3/2} = F(a1,b1) − F(a0,b1) − F(a1,b0) + F(a0,b0), F = atan2(a b, √(a²+b²+1)).
double cube_rectangle_solid_angle(double a0, double a1, double b0, double b1) {
  auto f = [](double a, double b) { return std::atan2(a * b, std::sqrt(a * a + b * b + 1.0)); };
  return f(a1, b1) - f(a0, b1) - f(a1, b0) + f(a0, b0);
}

double cube_texel_solid_angle(int i, int j, int n) {
  return cube_rectangle_solid_angle(cube_edge(i, n), cube_edge(i + 1, n), cube_edge(j, n), cube_edge(j + 1, n)) /
         (4.0 * kPi);
}

glm::dvec3 cube_texel_direction(int face, int i, int j, int n) {
  return glm::normalize(cube_face_direction(face, (2.0 * i + 1.0) / n - 1.0, (2.0 * j + 1.0) / n - 1.0));
}

// Texel index t = (f n + j) n + i of the cube texel holding d.
int64_t cube_index(const glm::dvec3& d, int n) {
  const FaceCoordinates c = cube_face_coordinates(d);
  const int i = std::clamp(static_cast<int>(std::floor((c.a + 1.0) * 0.5 * n)), 0, n - 1);
  const int j = std::clamp(static_cast<int>(std::floor((c.b + 1.0) * 0.5 * n)), 0, n - 1);
  return (static_cast<int64_t>(c.face) * n + j) * n + i;
}

// ---- pixels ----

void check_image_size(int width, int height, int64_t texels, const std::string& origin) {
  if (width < 1 || height < 1) {
    throw std::invalid_argument(origin + ": the image is empty (" + std::to_string(width) + " x " +
                                std::to_string(height) + " pixels)");
  }
  if (width > kMaxImageSide || height > kMaxImageSide || texels > kMaxTexels) {
    throw std::invalid_argument(origin + ": the image is too large (" + std::to_string(width) + " x " +
                                std::to_string(height) + ")");
  }
}

// Throws for NaN or infinite values, naming the pixel.
void check_finite_pixels(const std::vector<float>& rgb, int width, int height, const std::string& origin,
                         const char* face = nullptr) {
  for (size_t k = 0; k < rgb.size(); ++k) {
    if (std::isfinite(rgb[k])) continue;
    const size_t pixel = k / 3, channel = k % 3;
    const size_t x = pixel % static_cast<size_t>(width), y = (pixel / width) % static_cast<size_t>(height);
    std::string where = origin + ": pixel (x=" + std::to_string(x) + ", y=" + std::to_string(y) + " from the top";
    if (face != nullptr) where += std::string(", face ") + face;
    else if (pixel / (static_cast<size_t>(width) * height) > 0) where += std::string(", face ") + kFaceNames[pixel / (static_cast<size_t>(width) * height) % 6];
    throw std::invalid_argument(where + ") channel " + "RGB"[channel] + " is " +
                                (std::isnan(rgb[k]) ? "NaN" : "infinite") + ": environment maps must be finite");
  }
}

// The exact sRGB decoding curve (IEC 61966-2-1).
double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

bool names_linear_space(std::string name) {
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char ch) { return std::tolower(ch); });
  return name.find("linear") != std::string::npos;
}

struct LoadedImage {
  int width = 0, height = 0;
  std::vector<float> rgb;
};

// Reads subimage 0 of a file as linear RGB floats, rows top-first (environment.h: load()).
LoadedImage read_image_file(const std::string& path) {
  const std::string origin = "environment map '" + path + "'";
  // Alpha is ignored: ask for the stored (unassociated) colour, never colour × alpha.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) {
    std::string message = OIIO::geterror();
    if (message.empty()) message = "unknown OpenImageIO error";
    throw std::runtime_error("cannot open " + origin + ": " + message);
  }
  const OIIO::ImageSpec spec = in->spec();
  const int64_t texels = static_cast<int64_t>(spec.width) * spec.height;
  check_image_size(spec.width, spec.height, texels, origin);
  if (spec.depth > 1) throw std::invalid_argument(origin + ": volume images are not environment maps");
  const int channels = spec.nchannels;
  if (channels < 1) throw std::invalid_argument(origin + ": the image has no channels");
  std::vector<float> data(static_cast<size_t>(texels) * channels);
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, data.data())) {
    std::string message = in->geterror();
    if (message.empty()) message = OIIO::geterror();
    if (message.empty()) message = "unknown OpenImageIO error";
    throw std::runtime_error("cannot read " + origin + ": " + message);
  }
  in->close();

  const bool decode_srgb = !spec.format.is_floating_point() &&
                           !names_linear_space(spec.get_string_attribute("oiio:ColorSpace"));
  LoadedImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.rgb.resize(static_cast<size_t>(texels) * 3);
  const bool grey = channels < 3;  // grey, or grey + alpha
  for (int64_t p = 0; p < texels; ++p) {
    const float* src = data.data() + p * channels;
    for (int c = 0; c < 3; ++c) {
      float v = src[grey ? 0 : c];
      if (decode_srgb && std::isfinite(v)) v = static_cast<float>(srgb_to_linear(v));
      image.rgb[3 * p + c] = v;
    }
  }
  check_finite_pixels(image.rgb, image.width, image.height, origin);
  return image;
}

// ---- SH projection ----

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

// Coefficient-major RGB: out[3 i + c]. Cost ∝ W H (order+1) + H (order+1)²; bit-identical for any
// thread count: every row's azimuthal sums are computed by one thread, then combined in row order.
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

  // y_l,±m(θ, φ) = P̄_lm(θ) {cos, sin}(mφ) with P̄_lm = y_l,+m at φ = 0 (spherical_harmonics.h),
  // so one sh_basis call per row gives the associated-Legendre part.
  std::vector<double> out(static_cast<size_t>(k) * 3, 0.0), p(k);
  for (int j = 0; j < height; ++j) {
    const double theta = equirect_theta(j, height);
    sh_basis(order, glm::dvec3(std::sin(theta), 0.0, std::cos(theta)), p.data());
    const double dmu = equirect_row_solid_angle(j, width, height);
    const double* s = sums.data() + static_cast<size_t>(j) * 6 * mc;
    for (int l = 0; l <= order; ++l) {
      const int center = l * l + l;
      for (int m = 0; m <= l; ++m) {
        const double w = p[center + m] * dmu;
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

// Cube maps: y_lm per texel. Fixed blocks of texel rows (independent of the thread count) are
// summed by one thread each, then reduced in block order: bit-identical for any thread count.
std::vector<double> project_cube(const float* rgb, int n, int order, int threads) {
  const int k = sh_count(order);
  const int rows = 6 * n;
  const int rows_per_block = std::max(1, (rows + 63) / 64);
  const int blocks = (rows + rows_per_block - 1) / rows_per_block;
  std::vector<double> partial(static_cast<size_t>(blocks) * 3 * k, 0.0);
  parallel_for(
      static_cast<size_t>(blocks), 1,
      [&](size_t b0, size_t b1) {
        std::vector<double> y(k);
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
              const double dmu = cube_texel_solid_angle(i, j, n);
              const double r = px[0] * dmu, g = px[1] * dmu, b = px[2] * dmu;
              sh_basis(order, cube_texel_direction(face, i, j, n), y.data());
              for (int q = 0; q < k; ++q) {
                ar[q] += y[q] * r;
                ag[q] += y[q] * g;
                ab[q] += y[q] * b;
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

std::vector<double> project(EnvironmentLayout layout, const std::vector<float>& rgb, int width, int height, int order,
                            int threads) {
  return layout == EnvironmentLayout::Equirect ? project_equirect(rgb.data(), width, height, order, threads)
                                                : project_cube(rgb.data(), width, order, threads);
}

void check_output_size(const char* what, int width, int height) {
  check_range(std::string(what) + ": width", width, 1, kMaxTextureSide);
  check_range(std::string(what) + ": height", height, 1, kMaxTextureSide);
}

void check_channel(const char* what, int channel) {
  if (channel < 0 || channel > kLuminance) {
    throw std::invalid_argument(std::string(what) + ": channel must be 0, 1, 2 (R, G, B) or 3 (luminance), got " +
                                std::to_string(channel));
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Windows

RingingWindow ringing_window_from_name(const std::string& name) {
  if (name == "none") return RingingWindow::None;
  if (name == "hanning" || name == "hann") return RingingWindow::Hanning;
  if (name == "lanczos") return RingingWindow::Lanczos;
  throw std::invalid_argument("unknown window '" + name + "' (expected 'none', 'hanning' or 'lanczos')");
}

double ringing_window_factor(RingingWindow window, int l, int order) {
  const double x = static_cast<double>(l) / (order + 1.0);
  switch (window) {
    case RingingWindow::Hanning: return 0.5 * (1.0 + std::cos(kPi * x));
    case RingingWindow::Lanczos: return l == 0 ? 1.0 : std::sin(kPi * x) / (kPi * x);
    default: return 1.0;
  }
}

// ---------------------------------------------------------------------------------------------
// Environment: construction

struct Environment::EnergyCache {
  std::mutex mutex;
  bool ready = false;
  std::vector<double> coefficients;     // order kMaxEnergyOrder, RGB interleaved
  std::vector<double> energies;         // (kMaxEnergyOrder+1) × 4
  std::array<double, 4> norm_squared{};  // of the projected copy
};

Environment Environment::from_texels(EnvironmentLayout layout, int width, int height, std::vector<float> rgb,
                                     const std::string& origin) {
  const int64_t texels = layout == EnvironmentLayout::Equirect ? static_cast<int64_t>(width) * height
                                                                : int64_t(6) * width * width;
  check_image_size(width, height, texels, origin);
  if (layout == EnvironmentLayout::Cube && width != height) {
    throw std::invalid_argument(origin + ": cube faces must be square, got " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  if (rgb.size() != static_cast<size_t>(texels) * 3) {
    throw std::invalid_argument(origin + ": expected " + std::to_string(texels * 3) + " floats (" +
                                (layout == EnvironmentLayout::Cube ? "6 x " : "") + std::to_string(width) + " x " +
                                std::to_string(height) + " x 3), got " + std::to_string(rgb.size()));
  }
  check_finite_pixels(rgb, width, height, origin);

  Environment env;
  env.layout_ = layout;
  env.width_ = width;
  env.height_ = height;
  env.rgb_ = std::move(rgb);
  for (int64_t t = 0; t < texels; ++t) {
    float* px = env.rgb_.data() + 3 * t;
    bool negative = false;
    for (int c = 0; c < 3; ++c) {
      if (px[c] < 0.0f) {
        px[c] = 0.0f;
        negative = true;
      }
    }
    env.clamped_negative_pixels_ += negative ? 1 : 0;
  }
  // Masses and norms (sequential: deterministic).
  for (int64_t t = 0; t < texels; ++t) {
    const double dmu = env.texel_solid_angle(t);
    const float* px = env.rgb_.data() + 3 * t;
    const double v[4] = {px[0], px[1], px[2], luminance(px[0], px[1], px[2])};
    for (int c = 0; c < 4; ++c) {
      env.mass_[c] += v[c] * dmu;
      env.norm_squared_[c] += v[c] * v[c] * dmu;
    }
  }
  env.cache_ = std::make_shared<EnergyCache>();
  return env;
}

Environment Environment::load(const std::string& path) {
  LoadedImage image = read_image_file(path);
  return from_texels(EnvironmentLayout::Equirect, image.width, image.height, std::move(image.rgb),
                     "environment map '" + path + "'");
}

Environment Environment::load_cube(const std::array<std::string, 6>& faces) {
  std::vector<float> rgb;
  int size = 0;
  for (int f = 0; f < 6; ++f) {
    const LoadedImage image = read_image_file(faces[f]);
    const std::string origin = std::string("cube face ") + kFaceNames[f] + " '" + faces[f] + "'";
    if (image.width != image.height) {
      throw std::invalid_argument(origin + " is not square (" + std::to_string(image.width) + " x " +
                                  std::to_string(image.height) + ")");
    }
    if (f == 0) {
      size = image.width;
      rgb.reserve(static_cast<size_t>(size) * size * 18);
    } else if (image.width != size) {
      throw std::invalid_argument(origin + " is " + std::to_string(image.width) + " pixels wide, face +X is " +
                                  std::to_string(size) + ": all faces must have one size");
    }
    rgb.insert(rgb.end(), image.rgb.begin(), image.rgb.end());
  }
  return from_texels(EnvironmentLayout::Cube, size, size, std::move(rgb), "cube map '" + faces[0] + "', ...");
}

Environment Environment::from_equirect_pixels(int width, int height, std::vector<float> rgb) {
  return from_texels(EnvironmentLayout::Equirect, width, height, std::move(rgb), "equirect pixels");
}

Environment Environment::from_cube_pixels(int face_size, std::vector<float> rgb) {
  return from_texels(EnvironmentLayout::Cube, face_size, face_size, std::move(rgb), "cube pixels");
}

// ---------------------------------------------------------------------------------------------
// Environment: geometry

glm::dvec3 Environment::texel_direction(int64_t t) const {
  if (layout_ == EnvironmentLayout::Equirect) {
    const int j = static_cast<int>(t / width_), i = static_cast<int>(t % width_);
    return spherical_direction(equirect_theta(j, height_), equirect_phi(i, width_));
  }
  const int n = width_;
  const int64_t row = t / n;
  return cube_texel_direction(static_cast<int>(row / n), static_cast<int>(t % n), static_cast<int>(row % n), n);
}

double Environment::texel_solid_angle(int64_t t) const {
  if (layout_ == EnvironmentLayout::Equirect) {
    return equirect_row_solid_angle(static_cast<int>(t / width_), width_, height_);
  }
  const int n = width_;
  return cube_texel_solid_angle(static_cast<int>(t % n), static_cast<int>((t / n) % n), n);
}

glm::dvec3 Environment::texel_radiance(int64_t t) const {
  const float* px = rgb_.data() + 3 * t;
  return {px[0], px[1], px[2]};
}

int64_t Environment::texel_index(const glm::dvec3& dir) const {
  check_direction(dir);
  if (layout_ == EnvironmentLayout::Equirect) {
    const auto [j, i] = equirect_cell(dir, width_, height_);
    return static_cast<int64_t>(j) * width_ + i;
  }
  return cube_index(dir, width_);
}

double Environment::mass(int channel) const {
  check_channel("mass", channel);
  return mass_[channel];
}

double Environment::norm_squared(int channel) const {
  check_channel("norm_squared", channel);
  return norm_squared_[channel];
}

Environment Environment::area_averaged(int width, int height) const {
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide) {
    throw std::invalid_argument("area_averaged: sizes must be in [1, 65536], got " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  if (layout_ == EnvironmentLayout::Equirect) {
    const int sw = width_, sh = height_;
    // φ pass, in integer units of 1/(sw width) of a turn: source column i spans [i width, (i+1) width],
    // target column I spans [I sw, (I+1) sw]; the target average divides by sw.
    struct Overlap {
      int source, target;
      double weight;
    };
    std::vector<Overlap> overlaps;
    for (int big_i = 0; big_i < width; ++big_i) {
      const int64_t t0 = static_cast<int64_t>(big_i) * sw, t1 = t0 + sw;
      const int i_begin = static_cast<int>(t0 / width);
      const int i_end = static_cast<int>(std::min<int64_t>(sw, (t1 + width - 1) / width));
      for (int i = i_begin; i < i_end; ++i) {
        const int64_t overlap = std::min<int64_t>(t1, int64_t(i + 1) * width) - std::max<int64_t>(t0, int64_t(i) * width);
        if (overlap > 0) overlaps.push_back({i, big_i, static_cast<double>(overlap) / sw});
      }
    }
    std::vector<double> by_column(static_cast<size_t>(sh) * width * 3, 0.0);
    for (int j = 0; j < sh; ++j) {
      const float* row = rgb_.data() + 3 * static_cast<size_t>(j) * sw;
      double* out = by_column.data() + 3 * static_cast<size_t>(j) * width;
      for (const Overlap& o : overlaps) {
        for (int c = 0; c < 3; ++c) out[3 * o.target + c] += o.weight * row[3 * o.source + c];
      }
    }
    // θ pass, in integer units of π/(sh height): source row j spans [j height, (j+1) height],
    // target row J spans [J sh, (J+1) sh]; weights are the overlaps' extents in cos θ.
    const double unit = kPi / (static_cast<double>(sh) * height);
    std::vector<float> rgb(static_cast<size_t>(height) * width * 3);
    std::vector<double> acc(static_cast<size_t>(width) * 3);
    for (int big_j = 0; big_j < height; ++big_j) {
      const int64_t t0 = static_cast<int64_t>(big_j) * sh, t1 = t0 + sh;
      const int j_begin = static_cast<int>(t0 / height);
      const int j_end = static_cast<int>(std::min<int64_t>(sh, (t1 + height - 1) / height));
      std::fill(acc.begin(), acc.end(), 0.0);
      double total = 0.0;
      for (int j = j_begin; j < j_end; ++j) {
        const int64_t lo = std::max<int64_t>(t0, int64_t(j) * height), hi = std::min<int64_t>(t1, int64_t(j + 1) * height);
        if (hi <= lo) continue;
        const double w = cos_difference(unit * lo, unit * hi);
        total += w;
        const double* row = by_column.data() + static_cast<size_t>(j) * width * 3;
        for (size_t q = 0; q < acc.size(); ++q) acc[q] += w * row[q];
      }
      float* out = rgb.data() + static_cast<size_t>(big_j) * width * 3;
      for (size_t q = 0; q < acc.size(); ++q) out[q] = static_cast<float>(acc[q] / total);
    }
    return from_texels(EnvironmentLayout::Equirect, width, height, std::move(rgb), "area_averaged");
  }

  if (width != height) {
    throw std::invalid_argument("area_averaged: a cube map needs one face size (width == height), got " +
                                std::to_string(width) + " x " + std::to_string(height));
  }
  const int n = width_, m = width;
  // Face coordinates in integer units of 2/(n m): source texel i spans [i m, (i+1) m], target I
  // spans [I n, (I+1) n]. Every overlap rectangle's exact solid angle weights the average.
  std::vector<double> acc(static_cast<size_t>(6) * m * m * 3, 0.0), total(static_cast<size_t>(6) * m * m, 0.0);
  const double unit = 2.0 / (static_cast<double>(n) * m);
  auto overlapping = [&](int i, std::vector<std::pair<int, std::pair<int64_t, int64_t>>>& ranges) {
    ranges.clear();
    const int64_t s0 = int64_t(i) * m, s1 = s0 + m;
    for (int64_t big = s0 / n; big < m && big * n < s1; ++big) {
      const int64_t lo = std::max<int64_t>(s0, big * n), hi = std::min<int64_t>(s1, (big + 1) * n);
      if (hi > lo) ranges.push_back({static_cast<int>(big), {lo, hi}});
    }
  };
  std::vector<std::vector<std::pair<int, std::pair<int64_t, int64_t>>>> spans(n);
  for (int i = 0; i < n; ++i) overlapping(i, spans[i]);
  for (int f = 0; f < 6; ++f) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const float* px = rgb_.data() + 3 * ((static_cast<size_t>(f) * n + j) * n + i);
        for (const auto& [big_j, range_b] : spans[j]) {
          for (const auto& [big_i, range_a] : spans[i]) {
            const double omega = cube_rectangle_solid_angle(-1.0 + unit * range_a.first, -1.0 + unit * range_a.second,
                                                             -1.0 + unit * range_b.first, -1.0 + unit * range_b.second);
            const size_t target = (static_cast<size_t>(f) * m + big_j) * m + big_i;
            total[target] += omega;
            for (int c = 0; c < 3; ++c) acc[3 * target + c] += omega * px[c];
          }
        }
      }
    }
  }
  std::vector<float> rgb(acc.size());
  for (size_t t = 0; t < total.size(); ++t) {
    for (int c = 0; c < 3; ++c) rgb[3 * t + c] = static_cast<float>(acc[3 * t + c] / total[t]);
  }
  return from_texels(EnvironmentLayout::Cube, m, m, std::move(rgb), "area_averaged");
}

// ---------------------------------------------------------------------------------------------
// Environment: spherical harmonics

std::vector<double> Environment::sh(int order, int threads) const {
  check_order("Environment::sh: order", order, kMaxProjectionOrder);
  return project(layout_, rgb_, width_, height_, order, threads);
}

const Environment::EnergyCache& Environment::energy_cache() const {
  EnergyCache& cache = *cache_;
  std::lock_guard<std::mutex> lock(cache.mutex);
  if (cache.ready) return cache;
  // The reference copy (environment.h, band_energies).
  const Environment* source = this;
  Environment reduced;
  if (layout_ == EnvironmentLayout::Equirect && texel_count() > kReferenceEquirectTexels) {
    const double scale = std::sqrt(static_cast<double>(texel_count()) / kReferenceEquirectTexels);
    reduced = area_averaged(std::max(1, static_cast<int>(width_ / scale)), std::max(1, static_cast<int>(height_ / scale)));
    source = &reduced;
  } else if (layout_ == EnvironmentLayout::Cube && width_ > kReferenceCubeFace) {
    reduced = area_averaged(kReferenceCubeFace, kReferenceCubeFace);
    source = &reduced;
  }
  std::vector<double> coefficients =
      project(source->layout_, source->rgb_, source->width_, source->height_, kMaxEnergyOrder, 0);
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

std::vector<float> Environment::band_limited(int order, int width, int height, RingingWindow window,
                                             BandLimitedReport* report) const {
  check_order("Environment::band_limited: order", order, kMaxEnergyOrder);
  check_output_size("Environment::band_limited", width, height);
  std::vector<double> coefficients;
  if (order <= kMaxProjectionOrder) {
    coefficients = sh(order);
  } else {
    const auto& all = energy_cache().coefficients;
    coefficients.assign(all.begin(), all.begin() + 3 * sh_count(order));
  }
  return band_limited_texture(coefficients, order, width, height, window, report);
}

std::vector<double> Environment::band_energies(int lmax) const {
  check_order("Environment::band_energies: lmax", lmax, kMaxEnergyOrder);
  const auto& energies = energy_cache().energies;
  return std::vector<double>(energies.begin(), energies.begin() + 4 * (lmax + 1));
}

double Environment::low_frequency_error(int order, int channel) const {
  check_order("Environment::low_frequency_error: order", order, kMaxEnergyOrder);
  check_channel("Environment::low_frequency_error", channel);
  const EnergyCache& cache = energy_cache();
  const double norm2 = cache.norm_squared[channel];
  if (!(norm2 > 0.0)) return 0.0;
  double kept = 0.0;
  for (int l = 0; l <= order; ++l) kept += cache.energies[4 * l + channel];
  return std::sqrt(std::max(0.0, norm2 - kept) / norm2);
}

double Environment::lobe_filtered_error(const ZonalLobe& lobe, int order) const {
  check_order("Environment::lobe_filtered_error: order", order, kMaxEnergyOrder);
  const std::vector<double> w = lobe.coefficients(kMaxEnergyOrder);
  const auto& energies = energy_cache().energies;
  double missed = 0.0, total = 0.0;  // summed separately: no cancellation
  for (int l = 0; l <= kMaxEnergyOrder; ++l) {
    const double term = w[l] * w[l] * energies[4 * l + kLuminance];
    total += term;
    if (l > order) missed += term;
  }
  if (!(total > 0.0)) return 0.0;
  return std::sqrt(missed / total);
}

int Environment::smallest_order(const ZonalLobe& lobe, double target_error, int max_order) const {
  check_order("Environment::smallest_order: max_order", max_order, kMaxEnergyOrder);
  if (!(target_error >= 0.0) || !std::isfinite(target_error)) {
    throw std::invalid_argument("Environment::smallest_order: target_error must be finite and >= 0");
  }
  for (int s = 0; s <= max_order; ++s) {
    if (lobe_filtered_error(lobe, s) <= target_error) return s;
  }
  return -1;
}

SphericalDesign Environment::channel_design(int channel, int degree) const {
  check_channel("Environment::channel_design", channel);
  check_order("Environment::channel_design: degree", degree, kMaxDesignDegree);
  if (!(mass_[channel] > 0.0)) {
    throw std::invalid_argument("Environment::channel_design: channel " + std::to_string(channel) +
                                " is black everywhere: its measure L dμ is empty");
  }
  const Environment* source = this;
  Environment reduced;
  if (layout_ == EnvironmentLayout::Equirect && (width_ > kDesignEquirectWidth || height_ > kDesignEquirectHeight)) {
    reduced = area_averaged(std::min(width_, kDesignEquirectWidth), std::min(height_, kDesignEquirectHeight));
    source = &reduced;
  } else if (layout_ == EnvironmentLayout::Cube && width_ > kDesignCubeFace) {
    reduced = area_averaged(kDesignCubeFace, kDesignCubeFace);
    source = &reduced;
  }
  std::vector<glm::dvec3> dirs;
  std::vector<double> weights;
  for (int64_t t = 0; t < source->texel_count(); ++t) {
    const glm::dvec3 l = source->texel_radiance(t);
    const double value = channel == kLuminance ? luminance(l.x, l.y, l.z) : l[channel];
    if (!(value > 0.0)) continue;
    dirs.push_back(source->texel_direction(t));
    weights.push_back(value * source->texel_solid_angle(t));
  }
  return weighted_design(dirs, weights, degree);
}

// ---------------------------------------------------------------------------------------------
// Free functions

std::vector<float> band_limited_texture(const std::vector<double>& sh_coefficients, int order, int width, int height,
                                        RingingWindow window, BandLimitedReport* report) {
  check_order("band_limited_texture: order", order, kMaxEnergyOrder);
  check_output_size("band_limited_texture", width, height);
  const int k = sh_count(order), mc = order + 1;
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
  const AzimuthTables azimuth(width, mc);
  std::vector<float> rgb(static_cast<size_t>(width) * height * 3);
  // Per-row statistics, reduced in row order afterwards.
  std::vector<std::array<double, 6>> row_extrema(height);
  std::vector<int64_t> row_negative(height, 0);
  parallel_for(static_cast<size_t>(height), 4, [&](size_t j0, size_t j1) {
    std::vector<double> p(k), a(6 * static_cast<size_t>(mc));
    for (size_t j = j0; j < j1; ++j) {
      const double theta = equirect_theta(static_cast<int>(j), height);
      sh_basis(order, glm::dvec3(std::sin(theta), 0.0, std::cos(theta)), p.data());
      // a[c mc + m] = Σ_l σ_l L_l,+m P̄_lm;  a[(3+c) mc + m] = Σ_l σ_l L_l,−m P̄_lm.
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
      std::array<double, 6> extrema = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                                       std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                                       -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
      int64_t negative = 0;
      float* out = rgb.data() + j * 3 * static_cast<size_t>(width);
      for (int i = 0; i < width; ++i) {
        const double* ct = azimuth.cos.data() + static_cast<size_t>(i) * mc;
        const double* st = azimuth.sin.data() + static_cast<size_t>(i) * mc;
        bool below = false;
        for (int c = 0; c < 3; ++c) {
          const double* ac = a.data() + c * mc;
          const double* as = a.data() + (3 + c) * mc;
          double v = 0.0;
          for (int m = 0; m < mc; ++m) v += ac[m] * ct[m] + as[m] * st[m];
          out[3 * i + c] = static_cast<float>(v);
          extrema[c] = std::min(extrema[c], v);
          extrema[3 + c] = std::max(extrema[3 + c], v);
          below = below || v < 0.0;
        }
        negative += below ? 1 : 0;
      }
      row_extrema[j] = extrema;
      row_negative[j] = negative;
    }
  });
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

// ---------------------------------------------------------------------------------------------
// EnvironmentSampler

EnvironmentSampler::EnvironmentSampler(const Environment& environment)
    : layout_(environment.layout()), width_(environment.width()), height_(environment.height()) {
  const bool equirect = layout_ == EnvironmentLayout::Equirect;
  rows_ = equirect ? height_ : 6 * width_;
  columns_ = width_;
  const int64_t texels = environment.texel_count();
  if (equirect) {
    row_solid_angle_.resize(height_);
    for (int j = 0; j < height_; ++j) row_solid_angle_[j] = equirect_row_solid_angle(j, width_, height_);
  }
  const double total_luminance = environment.mass(kLuminance);
  const double uniform = total_luminance > 0.0 ? kUniformShare : 1.0;
  probability_.resize(static_cast<size_t>(texels));
  double sum = 0.0;
  for (int64_t t = 0; t < texels; ++t) {
    const double dmu = equirect ? row_solid_angle_[t / width_] : environment.texel_solid_angle(t);
    const glm::dvec3 l = environment.texel_radiance(t);
    double p = uniform * dmu;
    if (uniform < 1.0) p += (1.0 - uniform) * luminance(l.x, l.y, l.z) * dmu / total_luminance;
    probability_[t] = p;
    sum += p;
  }
  for (double& p : probability_) p /= sum;  // Σ = 1 up to rounding
  row_cdf_.assign(rows_ + 1, 0.0);
  column_cdf_.resize(static_cast<size_t>(texels));
  for (int r = 0; r < rows_; ++r) {
    const size_t base = static_cast<size_t>(r) * columns_;
    double row = 0.0;
    for (int c = 0; c < columns_; ++c) {
      row += probability_[base + c];
      column_cdf_[base + c] = row;
    }
    for (int c = 0; c < columns_; ++c) column_cdf_[base + c] /= row;
    column_cdf_[base + columns_ - 1] = 1.0;
    row_cdf_[r + 1] = row_cdf_[r] + row;
  }
  const double total = row_cdf_[rows_];
  for (double& c : row_cdf_) c /= total;
  row_cdf_[rows_] = 1.0;
}

glm::dvec3 EnvironmentSampler::sample(double u1, double u2, double* pdf) const {
  constexpr double kBelowOne = 1.0 - std::numeric_limits<double>::epsilon() / 2;
  u1 = std::isfinite(u1) ? std::clamp(u1, 0.0, kBelowOne) : 0.0;
  u2 = std::isfinite(u2) ? std::clamp(u2, 0.0, kBelowOne) : 0.0;
  // Row by u1, column by u2; what is left of each (rescaled to [0, 1)) places the point inside.
  int r = static_cast<int>(std::upper_bound(row_cdf_.begin(), row_cdf_.end(), u1) - row_cdf_.begin()) - 1;
  r = std::clamp(r, 0, rows_ - 1);
  const double v1 = std::clamp((u1 - row_cdf_[r]) / (row_cdf_[r + 1] - row_cdf_[r]), 0.0, 1.0);
  const auto row_begin = column_cdf_.begin() + static_cast<size_t>(r) * columns_;
  int c = static_cast<int>(std::upper_bound(row_begin, row_begin + columns_, u2) - row_begin);
  c = std::clamp(c, 0, columns_ - 1);
  const double below = c > 0 ? row_begin[c - 1] : 0.0;
  const double v2 = std::clamp((u2 - below) / (row_begin[c] - below), 0.0, 1.0);
  const int64_t t = static_cast<int64_t>(r) * columns_ + c;

  glm::dvec3 dir;
  if (layout_ == EnvironmentLayout::Equirect) {
    // Uniform in cos θ and in φ inside the texel: uniform in solid angle.
    const double z_top = std::cos(kPi * r / height_), z_bottom = std::cos(kPi * (r + 1.0) / height_);
    const double z = std::clamp(z_top + v1 * (z_bottom - z_top), -1.0, 1.0);
    const double phi = kPi - 2.0 * kPi * (c + v2) / width_;
    const double s = std::sqrt(std::max(0.0, (1.0 - z) * (1.0 + z)));
    dir = glm::dvec3(s * std::cos(phi), s * std::sin(phi), z);
    if (pdf != nullptr) *pdf = probability_[t] / row_solid_angle_[r];
  } else {
    const int n = width_, face = r / n, j = r % n;
    const double a = cube_edge(c, n) + v2 * (2.0 / n), b = cube_edge(j, n) + v1 * (2.0 / n);
    dir = glm::normalize(cube_face_direction(face, a, b));
    if (pdf != nullptr) {
      const double q = 1.0 + a * a + b * b;
      *pdf = probability_[t] * 4.0 * kPi * q * std::sqrt(q) / ((2.0 / n) * (2.0 / n));
    }
  }
  return dir;
}

double EnvironmentSampler::pdf(const glm::dvec3& dir) const {
  check_direction(dir);
  if (layout_ == EnvironmentLayout::Equirect) {
    const auto [j, i] = equirect_cell(dir, width_, height_);
    return probability_[static_cast<size_t>(j) * width_ + i] / row_solid_angle_[j];
  }
  return pdf_in_texel(cube_index(dir, width_), dir);
}

double EnvironmentSampler::pdf_in_texel(int64_t t, const glm::dvec3& dir) const {
  const FaceCoordinates f = cube_face_coordinates(dir);
  const double q = 1.0 + f.a * f.a + f.b * f.b;
  const double side = 2.0 / width_;
  return probability_[static_cast<size_t>(t)] * 4.0 * kPi * q * std::sqrt(q) / (side * side);
}

}  // namespace sd
