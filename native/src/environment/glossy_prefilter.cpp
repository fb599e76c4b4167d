// The split sum's two factors (glossy_prefilter.h): the environment prefiltered by the GGX lobe, and
// the lobe's directional albedo.
#include "sdlighting/glossy_prefilter.h"

#include "sdlighting/limits.h"

#include "environment/texel_layout.h"
#include "util/parallel_for.h"

#include <glm/geometric.hpp>
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace sd {
namespace {

constexpr int kMaxSamples = 4096;
constexpr int kMinSourceWidth = 8;   // the coarsest map of the source pyramid
constexpr double kMinAlpha = 1e-4;
// Each level samples its lobe within these angles of r and sums the rest exactly over a map
// kTailWidth wide (sampled_lobe, convolved_map): its texels (1.4 degrees) are under half the window's
// width, so the tail's weight varies little across one.
constexpr double kCoreInnerDegrees = 3.0, kCoreOuterDegrees = 6.0;
constexpr int kTailWidth = 256;
// Maps narrower than this are resampled to it for the tails: texels wider than the window can
// leave a texel's whole hemisphere inside it, with no tail to sum.
constexpr int kMinTailWidth = 64;

/// GGX α of a Principled roughness r: r², kept off 0 so that D stays finite.
double ggx_alpha(double roughness) { return std::max(roughness * roughness, kMinAlpha); }

/// Hammersley point i of n: ((i + ½) / n, the radical inverse of i in base 2).
std::array<double, 2> hammersley(int i, int n) {
  uint32_t bits = static_cast<uint32_t>(i);
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return {(i + 0.5) / n, bits * 2.3283064365386963e-10};
}

/// A GGX-distributed half vector around +z for the point u: n·h from the inverted CDF of D (n·h).
glm::dvec3 ggx_half_vector(const std::array<double, 2>& u, double alpha) {
  const double a2 = alpha * alpha;
  const double cos2 = (1.0 - u[0]) / (1.0 + (a2 - 1.0) * u[0]);
  const double cos_theta = std::sqrt(cos2), sin_theta = std::sqrt(std::max(0.0, 1.0 - cos2));
  const double phi = 2.0 * kPi * u[1];
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

/// D(h) of GGX at n·h (per steradian).
double ggx_distribution(double n_dot_h, double alpha) {
  const double a2 = alpha * alpha;
  const double d = (a2 - 1.0) * n_dot_h * n_dot_h + 1.0;
  return a2 / (kPi * d * d);
}

/// The lobe's weight D(h) (r·l) at c = r·l > 0 with n = v = r: (r·h)² = (1 + c) / 2 for the half
/// vector of two unit vectors.
double lobe_weight(double c, double alpha) { return ggx_distribution(std::sqrt(0.5 * (1.0 + c)), alpha) * c; }

/// The share of the lobe a level samples at c = r·l: 1 within kCoreInnerDegrees of r, 0
/// beyond kCoreOuterDegrees, smooth between (smoothstep in c), so that the tail's sum, 1 − the
/// share, varies no faster than the window as r moves.
double core_share(double c) {
  static const double inner = std::cos(kCoreInnerDegrees * kPi / 180.0), outer = std::cos(kCoreOuterDegrees * kPi / 180.0);
  const double t = std::clamp((c - outer) / (inner - outer), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

/// One sample of a level: the direction l in the frame of r (r = +z), its weight (r·l) core_share,
/// and the source map it is read from (a fractional level of the pyramid).
struct LobeSample {
  glm::dvec3 direction;
  double weight;
  double source_level;
};

/// A level's lobe: its core's samples, and the core's part of the lobe's weight
/// ∫ D(h) (r·l)⁺ core_share dl / ∫ D(h) (r·l)⁺ dl (the tail has the rest).
struct SampledLobe {
  std::vector<LobeSample> samples;
  double core_part;
};

/// The core of a level of roughness r: GGX half vectors h within half of kCoreOuterDegrees of n
/// (the inverse CDF of D (n·h) over that cap), l = 2 (v·h) h − v with v = n = +z. Each one's solid
/// angle 1 / (n pdf(l)), pdf(l) = D(h) / 4 / P(cap) where v = n, chooses the source map whose texels
/// are about that large (filtered importance sampling, Křivánek and Colbert 2008, without their +1
/// towards the smoother map, which spread a bright source over the lobe). Only the core is
/// sampled: samples far from r are few, each read from a coarse map, and put a bright source's
/// light into the dark map around it (msd-notes, "Glossy light").
SampledLobe sampled_lobe(double roughness, int samples, double finest_texel_solid_angle, int coarsest) {
  const double alpha = ggx_alpha(roughness), a2 = alpha * alpha;
  // P(tan² θ_h < t) = t / (α² + t) for GGX half vectors
  const double tan2 = std::pow(std::tan(0.5 * kCoreOuterDegrees * kPi / 180.0), 2.0);
  const double cap = tan2 / (a2 + tan2);
  SampledLobe lobe;
  for (int i = 0; i < samples; ++i) {
    std::array<double, 2> u = hammersley(i, samples);
    u[0] *= cap;
    const glm::dvec3 h = ggx_half_vector(u, alpha);
    const glm::dvec3 l(2.0 * h.z * h.x, 2.0 * h.z * h.y, 2.0 * h.z * h.z - 1.0);
    const double solid_angle = 4.0 * cap / (samples * ggx_distribution(h.z, alpha));
    const double level = 0.5 * std::log2(solid_angle / finest_texel_solid_angle);
    lobe.samples.push_back({l, l.z * core_share(l.z), std::clamp(level, 0.0, static_cast<double>(coarsest))});
  }
  // The two parts by a midpoint rule in θ_l (steps of 0.0014 degrees).
  constexpr int kSteps = 1 << 16;
  double core = 0.0, whole = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const double theta = 0.5 * kPi * (i + 0.5) / kSteps;
    const double w = lobe_weight(std::cos(theta), alpha) * std::sin(theta);
    core += w * core_share(std::cos(theta));
    whole += w;
  }
  lobe.core_part = core / whole;
  return lobe;
}

/// Area-averaged copies of the map, each half the size of the one before, down to kMinSourceWidth.
std::vector<Environment> source_pyramid(const Environment& environment) {
  std::vector<Environment> pyramid{environment};
  const bool cube = environment.layout() == EnvironmentLayout::Cube;
  for (;;) {
    const Environment& last = pyramid.back();
    const int width = last.width() / 2;
    if ((cube ? 4 * width : width) < kMinSourceWidth || last.height() < 2) break;
    pyramid.push_back(last.area_averaged(width, cube ? width : last.height() / 2));
  }
  return pyramid;
}

/// A direction's place on an equirect map of any size: u = (π − φ) / 2π, the column as a fraction
/// of the width (any real: it wraps), and v = θ / π, the row's.
struct EquirectPoint {
  double u, v;
};

EquirectPoint equirect_point(const glm::dvec3& d) {
  return {(kPi - std::atan2(d.y, d.x)) / (2.0 * kPi), std::acos(std::clamp(d.z, -1.0, 1.0)) / kPi};
}

/// An equirect map at p: bilinear between the four nearest texel centres (wrapped at the seam,
/// clamped at the poles).
glm::dvec3 bilinear_radiance(const Environment& map, const EquirectPoint& p) {
  const int width = map.width(), height = map.height();
  const double x = p.u * width - 0.5, y = p.v * height - 0.5;
  const double x0 = std::floor(x), y0 = std::floor(y);
  const double fx = x - x0, fy = y - y0;
  const float* pixels = map.pixels().data();
  const auto texel = [&](int i, int j) {
    i = ((i % width) + width) % width;
    j = std::clamp(j, 0, height - 1);
    const float* px = pixels + 3 * (static_cast<int64_t>(j) * width + i);
    return glm::dvec3(px[0], px[1], px[2]);
  };
  const int i = static_cast<int>(x0), j = static_cast<int>(y0);
  const glm::dvec3 top = (1.0 - fx) * texel(i, j) + fx * texel(i + 1, j);
  const glm::dvec3 bottom = (1.0 - fx) * texel(i, j + 1) + fx * texel(i + 1, j + 1);
  return (1.0 - fy) * top + fy * bottom;
}

/// The map at the unit direction d: bilinear on an equirect map, the nearest texel of a cube map.
glm::dvec3 filtered_radiance(const Environment& map, const glm::dvec3& d) {
  return map.layout() == EnvironmentLayout::Equirect ? bilinear_radiance(map, equirect_point(d)) : map.radiance(d);
}

/// The pyramid's radiance at `at` (a direction, or an EquirectPoint on an equirect pyramid) on
/// fractional level `level`: the two maps around it, blended.
template <class Place>
glm::dvec3 pyramid_radiance(const std::vector<Environment>& pyramid, const Place& at, double level) {
  const auto read = [&at](const Environment& map) {
    if constexpr (std::is_same_v<Place, EquirectPoint>)
      return bilinear_radiance(map, at);
    else
      return filtered_radiance(map, at);
  };
  const int below = static_cast<int>(level);
  const double t = level - below;
  const glm::dvec3 a = read(pyramid[below]);
  return t > 0.0 && below + 1 < static_cast<int>(pyramid.size()) ? a + t * (read(pyramid[below + 1]) - a) : a;
}

/// The tangent frame of r (t1 = z × r / |z × r|, t2 = r × t1; r off the poles): it turns with r
/// about the z axis, so along a row of an equirect level the lobe's samples are one pattern turned
/// by the texels' φ, and on an equirect map each texel reads its row's first pattern shifted by
/// whole columns (prefilter_ggx finds the pattern's places once per row).
void azimuthal_frame(const glm::dvec3& r, glm::dvec3& t1, glm::dvec3& t2) {
  t1 = glm::normalize(glm::dvec3(-r.y, r.x, 0.0));
  t2 = glm::cross(r, t1);
}

/// The equirect map the tails are summed over: the map box-filtered to kTailWidth wide, or itself
/// where it is narrower down to kMinTailWidth; a cube map, or a narrower equirect one, is resampled
/// to that width (4 x 4 directions per texel, read as filtered_radiance reads them from the
/// pyramid's map of about that size).
Environment tail_map(const std::vector<Environment>& pyramid) {
  const auto wide = [](const Environment& m) { return (m.layout() == EnvironmentLayout::Cube ? 4 : 1) * m.width(); };
  size_t i = 0;
  while (i + 1 < pyramid.size() && wide(pyramid[i + 1]) >= kTailWidth) ++i;
  const Environment& map = pyramid[i];
  if (map.layout() == EnvironmentLayout::Equirect && map.width() >= kMinTailWidth)
    return map.width() > kTailWidth ? map.area_averaged(kTailWidth, kTailWidth / 2) : map;
  const int width = map.layout() == EnvironmentLayout::Cube ? kTailWidth : kMinTailWidth, height = width / 2;
  constexpr int kSub = 4;
  std::vector<float> rgb(static_cast<size_t>(width) * height * 3);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      glm::dvec3 sum(0.0);
      for (int b = 0; b < kSub; ++b)
        for (int a = 0; a < kSub; ++a)
          sum += filtered_radiance(map, spherical_direction(kPi * (j + (b + 0.5) / kSub) / height,
                                                            kPi - 2.0 * kPi * (i + (a + 0.5) / kSub) / width));
      for (int c = 0; c < 3; ++c) rgb[3 * (static_cast<size_t>(j) * width + i) + c] = static_cast<float>(sum[c] / (kSub * kSub));
    }
  return Environment::from_equirect_pixels(width, height, std::move(rgb));
}

/// ∫ L(l) k(r·l) dl / ∫ k(r·l) dl at the centre r of every texel of an equirect map, for a kernel
/// k(c) >= 0 that is 0 for c <= 0 and positive somewhere on the hemisphere. Between a row of r and a
/// row of l the weight depends only on their columns' difference, so each output row is a sum of
/// circular convolutions along the input rows: by FFT (Eigen's), O(H² W log W) for H rows of W.
/// Both cores.
template <typename Kernel>
Environment convolved_map(const Environment& map, Kernel kernel) {
  const int width = map.width(), height = map.height(), spectrum = width / 2 + 1;
  using Spectrum = std::vector<std::complex<double>>;
  std::vector<std::array<Spectrum, 3>> rows(height);   // the input rows' spectra per channel
  {
    Eigen::FFT<double> fft;
    fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
    std::vector<double> row(width);
    for (int j = 0; j < height; ++j)
      for (int c = 0; c < 3; ++c) {
        for (int i = 0; i < width; ++i) row[i] = map.pixels()[3 * (static_cast<size_t>(j) * width + i) + c];
        fft.fwd(rows[j][c], row);
      }
  }
  // cos of the columns' azimuth differences, and of the rows' polar angles: the same for every pair
  std::vector<double> cos_azimuth(width), cos_polar(height), sin_polar(height);
  for (int d = 0; d < width; ++d) cos_azimuth[d] = std::cos(2.0 * kPi * d / width);
  for (int j = 0; j < height; ++j) {
    cos_polar[j] = std::cos(equirect_theta(j, height));
    sin_polar[j] = std::sin(equirect_theta(j, height));
  }
  std::vector<float> out(static_cast<size_t>(width) * height * 3);
  parallel_for(static_cast<size_t>(height), 1, [&](size_t begin, size_t end) {
    Eigen::FFT<double> fft;
    fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
    std::vector<double> weights(width), channel(width);
    Spectrum weight_spectrum;
    for (size_t j = begin; j < end; ++j) {
      std::array<Spectrum, 3> sum;
      sum.fill(Spectrum(spectrum));
      double total = 0.0;
      for (int jj = 0; jj < height; ++jj) {
        const double cos_part = cos_polar[j] * cos_polar[jj], sin_part = sin_polar[j] * sin_polar[jj];
        if (cos_part + sin_part <= 0.0) continue;   // the row lies below r's horizon
        const double solid_angle = map.texel_solid_angle(static_cast<int64_t>(jj) * width);
        double row_total = 0.0;
        for (int d = 0; d < width; ++d) {
          weights[d] = kernel(cos_part + sin_part * cos_azimuth[d]) * solid_angle;
          row_total += weights[d];
        }
        if (row_total == 0.0) continue;
        total += row_total;
        // the weights are even in d (cos), so their spectrum is real and correlation is convolution
        fft.fwd(weight_spectrum, weights);
        for (int c = 0; c < 3; ++c)
          for (int f = 0; f < spectrum; ++f) sum[c][f] += weight_spectrum[f] * rows[jj][c][f];
      }
      for (int c = 0; c < 3; ++c) {
        fft.inv(channel, sum[c], width);
        for (int i = 0; i < width; ++i)
          out[3 * (j * width + i) + c] = static_cast<float>(std::max(channel[i] / total, 0.0));
      }
    }
  });
  return Environment::from_equirect_pixels(width, height, std::move(out));
}

/// Direction of texel (i, j) of an equirect level whose rows run bottom-first.
glm::dvec3 level_direction(int i, int j, int width, int height) {
  return spherical_direction(equirect_theta(height - 1 - j, height), equirect_phi(i, width));
}

}  // namespace

void PrefilterLayout::check() const {
  if (width0 < 4 || width0 > kMaxTextureSide || (width0 & (width0 - 1)) != 0)
    throw std::invalid_argument("prefilter layout: width0 must be a power of two in [4, " +
                                std::to_string(kMaxTextureSide) + "], got " + std::to_string(width0));
  if (levels < 3 || levels > 30 || (width0 >> (levels - 3)) < 4)
    throw std::invalid_argument("prefilter layout: levels must be >= 3 with width0 >> (levels - 3) >= 4, got " +
                                std::to_string(levels) + " levels of width " + std::to_string(width0));
}

std::vector<float> prefilter_ggx(const Environment& environment, const PrefilterLayout& layout, int samples) {
  layout.check();
  if (samples < 1 || samples > kMaxSamples)
    throw std::invalid_argument("prefilter_ggx: samples must be in [1, " + std::to_string(kMaxSamples) + "], got " +
                                std::to_string(samples));
  const std::vector<Environment> pyramid = source_pyramid(environment);
  const bool equirect = environment.layout() == EnvironmentLayout::Equirect;
  const double finest = 4.0 * kPi / static_cast<double>(environment.texel_count());
  const int coarsest = static_cast<int>(pyramid.size()) - 1;
  const int atlas_width = layout.atlas_width();
  std::vector<float> atlas(static_cast<size_t>(atlas_width) * layout.atlas_height() * 3, 0.0f);

  // Work items: every row of every level, level 0 (the map at the level's texel size) first.
  struct Row {
    int level, j;
  };
  std::vector<Row> rows;
  std::vector<SampledLobe> lobes(layout.levels);
  std::vector<Environment> tails;   // tails[k - 1]: level k's tail (sampled_lobe) at every direction
  const Environment tail_source = tail_map(pyramid);
  for (int k = 0; k < layout.levels; ++k) {
    for (int j = 0; j < layout.level_height(k); ++j) rows.push_back({k, j});
    if (k == 0) continue;
    // Each level a quarter of the texels of the one before: twice the samples, each read from a
    // finer map, for half the work of the level before.
    lobes[k] = sampled_lobe(layout.roughness(k), std::min(samples << std::min(k - 1, 12), kMaxSamples), finest, coarsest);
    const double alpha = ggx_alpha(layout.roughness(k));
    tails.push_back(convolved_map(tail_source, [alpha](double c) {
      return c > 0.0 ? lobe_weight(c, alpha) * (1.0 - core_share(c)) : 0.0;
    }));
  }
  const double level0_source = std::clamp(
      0.5 * std::log2(4.0 * kPi / (static_cast<double>(layout.level_width(0)) * layout.level_height(0)) / finest), 0.0,
      static_cast<double>(coarsest));

  parallel_for(rows.size(), 4, [&](size_t begin, size_t end) {
    for (size_t item = begin; item < end; ++item) {
      const int k = rows[item].level, j = rows[item].j;
      const int width = layout.level_width(k), height = layout.level_height(k);
      const auto origin = layout.level_origin(k);
      float* out = &atlas[(static_cast<size_t>(origin[1] + j) * atlas_width + origin[0]) * 3];
      const std::vector<LobeSample>& samples_k = lobes[k].samples;
      // On an equirect map: the places of the row's first texel's samples (azimuthal_frame)
      std::vector<EquirectPoint> first;
      if (k > 0 && equirect) {
        glm::dvec3 t1, t2;
        const glm::dvec3 r = level_direction(0, j, width, height);
        azimuthal_frame(r, t1, t2);
        for (const LobeSample& s : samples_k)
          first.push_back(equirect_point(s.direction.x * t1 + s.direction.y * t2 + s.direction.z * r));
      }
      for (int i = 0; i < width; ++i) {
        const glm::dvec3 r = level_direction(i, j, width, height);
        glm::dvec3 sum(0.0);
        if (k == 0) {
          sum = pyramid_radiance(pyramid, r, level0_source);
        } else {
          glm::dvec3 t1, t2;
          if (!equirect) azimuthal_frame(r, t1, t2);
          const double shift = static_cast<double>(i) / width;   // φ_i − φ_0 = −2π i / width
          double weight = 0.0;
          for (size_t q = 0; q < samples_k.size(); ++q) {
            const LobeSample& s = samples_k[q];
            sum += s.weight * (equirect ? pyramid_radiance(pyramid, EquirectPoint{first[q].u + shift, first[q].v}, s.source_level)
                                        : pyramid_radiance(pyramid, s.direction.x * t1 + s.direction.y * t2 + s.direction.z * r,
                                                           s.source_level));
            weight += s.weight;
          }
          const double core = lobes[k].core_part;
          sum = core * sum / weight + (1.0 - core) * bilinear_radiance(tails[k - 1], equirect_point(r));
        }
        for (int c = 0; c < 3; ++c) out[3 * i + c] = static_cast<float>(sum[c]);
      }
    }
  });
  return atlas;
}

namespace {

void check_ior(const char* caller, double ior) {
  if (!(ior == 0.0 || (ior > 1.0 && ior <= 1e6)))
    throw std::invalid_argument(std::string(caller) + ": ior must be 0 (Schlick) or in (1, 1e6], got " +
                                std::to_string(ior));
}

/// Unpolarised Fresnel reflectance of a dielectric of relative IOR n > 1 seen from outside at
/// cos θ = c (Walter et al. 2007, eq. 22).
double dielectric_fresnel(double c, double n) {
  const double g = std::sqrt(n * n - 1.0 + c * c);
  const double a = (g - c) / (g + c), b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
  return 0.5 * a * a * (1.0 + b * b);
}

void check_samples(const char* caller, int samples) {
  if (samples < 1 || samples > 1 << 20)
    throw std::invalid_argument(std::string(caller) + ": samples must be in [1, 2^20], got " + std::to_string(samples));
}

void check_lobe_point(const char* caller, double n_dot_v, double roughness, int samples) {
  if (!(n_dot_v > 0.0 && n_dot_v <= 1.0))
    throw std::invalid_argument(std::string(caller) + ": n_dot_v must be in (0, 1], got " + std::to_string(n_dot_v));
  if (!(roughness >= 0.0 && roughness <= 1.0))
    throw std::invalid_argument(std::string(caller) + ": roughness must be in [0, 1], got " + std::to_string(roughness));
  check_samples(caller, samples);
}

void check_table(const char* caller, int size, int samples) {
  if (size < 2 || size > 256)
    throw std::invalid_argument(std::string(caller) + ": size must be in [2, 256], got " + std::to_string(size));
  check_samples(caller, samples);
}

/// f(n·v, roughness) -> std::array<double, N> at n·v = (i + ½) / size and roughness j / (size − 1),
/// row-major, both cores.
template <size_t N, typename F>
std::vector<float> tabulate(int size, F f) {
  std::vector<float> table(static_cast<size_t>(size) * size * N);
  parallel_for(static_cast<size_t>(size), 1, [&](size_t begin, size_t end) {
    for (size_t j = begin; j < end; ++j)
      for (int i = 0; i < size; ++i) {
        const std::array<double, N> value = f((i + 0.5) / size, static_cast<double>(j) / (size - 1));
        std::copy(value.begin(), value.end(), table.begin() + N * (j * size + i));
      }
  });
  return table;
}

/// Calls reflect(l, v·h, weight) for each of `samples` GGX half vectors h around n = +z seen from
/// v = (√(1 − (n·v)²), 0, n·v) whose reflection l lies above the surface, with weight
/// f₁ (n·l) / pdf(l) = G2 (v·h) / ((n·h) (n·v)) (F = 1; Smith height-correlated G2, Heitz 2014,
/// eq. 99); the sum of the weights over `samples` is the lobe's albedo A + B.
template <typename F>
void for_each_reflection(double n_dot_v, double alpha, int samples, F reflect) {
  const double a2 = alpha * alpha;
  const glm::dvec3 v(std::sqrt(1.0 - n_dot_v * n_dot_v), 0.0, n_dot_v);
  const auto lambda_term = [a2](double c) { return std::sqrt(a2 + (1.0 - a2) * c * c); };
  for (int i = 0; i < samples; ++i) {
    const glm::dvec3 h = ggx_half_vector(hammersley(i, samples), alpha);
    const double v_dot_h = glm::dot(v, h);
    const glm::dvec3 l = 2.0 * v_dot_h * h - v;
    if (l.z <= 0.0 || v_dot_h <= 0.0) continue;
    const double g2 = 2.0 * l.z * n_dot_v / (l.z * lambda_term(n_dot_v) + n_dot_v * lambda_term(l.z));
    reflect(l, v_dot_h, g2 * v_dot_h / (h.z * n_dot_v));
  }
}

}  // namespace

std::array<double, 2> environment_brdf(double n_dot_v, double roughness, int samples, double ior) {
  check_lobe_point("environment_brdf", n_dot_v, roughness, samples);
  check_ior("environment_brdf", ior);
  const double normal_fresnel = ior > 0.0 ? dielectric_fresnel(1.0, ior) : 0.0;
  const auto shape = [&](double c) {
    return ior > 0.0 ? (dielectric_fresnel(c, ior) - normal_fresnel) / (1.0 - normal_fresnel) : std::pow(1.0 - c, 5.0);
  };
  double a = 0.0, b = 0.0;
  for_each_reflection(n_dot_v, ggx_alpha(roughness), samples,
                      [&](const glm::dvec3&, double v_dot_h, double weight) {
                        const double fresnel = shape(v_dot_h);
                        a += (1.0 - fresnel) * weight;
                        b += fresnel * weight;
                      });
  return {a / samples, b / samples};
}

std::vector<float> environment_brdf_table(int size, int samples, double ior) {
  check_table("environment_brdf_table", size, samples);
  check_ior("environment_brdf_table", ior);
  return tabulate<2>(size, [&](double n_dot_v, double roughness) { return environment_brdf(n_dot_v, roughness, samples, ior); });
}

double glossy_bend(double n_dot_v, double roughness, int samples, double ior) {
  check_lobe_point("glossy_bend", n_dot_v, roughness, samples);
  check_ior("glossy_bend", ior);
  glm::dvec3 mean(0.0);
  for_each_reflection(n_dot_v, ggx_alpha(roughness), samples, [&](const glm::dvec3& l, double v_dot_h, double weight) {
    mean += (ior > 0.0 ? dielectric_fresnel(v_dot_h, ior) : 1.0) * weight * l;
  });
  // The mean direction's angle θ from n, towards r at θ_r = acos(n·v); mix(n, r, bend) makes
  // tan θ = bend sin θ_r / (1 − bend (1 − cos θ_r)).
  // Within 0.06° of normal incidence r is n and the angle is sampling noise.
  const double tan_mean = std::max(-mean.x / mean.z, 0.0);
  const double sin_r = std::sqrt(1.0 - n_dot_v * n_dot_v);
  return sin_r > 1e-3 ? std::clamp(tan_mean / (sin_r + tan_mean * (1.0 - n_dot_v)), 0.0, 1.0) : 1.0;
}

std::vector<float> glossy_bend_table(int size, int samples, double ior) {
  check_table("glossy_bend_table", size, samples);
  check_ior("glossy_bend_table", ior);
  return tabulate<1>(size, [&](double n_dot_v, double roughness) {
    return std::array<double, 1>{glossy_bend(n_dot_v, roughness, samples, ior)};
  });
}

}  // namespace sd
