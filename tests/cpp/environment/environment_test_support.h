// Helpers shared by the environment tests (header-only, namespace sd::test): reference maps written
// independently of the library, random band-limited functions, scratch files, Blender's HDRIs.
#pragma once

#include "sdlighting/environment.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdtesting/sphere.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

namespace sd::test {

inline constexpr double kExact = 1e-12;
inline constexpr double kPi = 3.14159265358979323846;
inline const std::string kBlenderWorlds = "/usr/share/blender/datafiles/studiolights/world/";
inline const char* const kBlenderHdris[] = {"city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset"};

using Radiance = std::function<glm::dvec3(const glm::dvec3&)>;
// ---- references written independently of the library ----

inline std::vector<float> equirect_pixels(int width, int height, const Radiance& f) {
  std::vector<float> rgb(static_cast<size_t>(width) * height * 3);
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const glm::dvec3 v = f(equirect_pixel_direction(i, j, width, height));
      for (int c = 0; c < 3; ++c) rgb[3 * (static_cast<size_t>(j) * width + i) + c] = static_cast<float>(v[c]);
    }
  }
  return rgb;
}

// The OpenGL face table inverted by hand: face coordinates sc = 2s − 1, tc = 2t − 1 of face f.
inline glm::dvec3 cube_pixel_direction(int face, int i, int j, int n) {
  const double sc = 2.0 * (i + 0.5) / n - 1.0, tc = 2.0 * (j + 0.5) / n - 1.0;
  const glm::dvec3 table[6] = {{1.0, -tc, -sc}, {-1.0, -tc, sc}, {sc, 1.0, tc},
                               {sc, -1.0, -tc}, {sc, -tc, 1.0}, {-sc, -tc, -1.0}};
  return glm::normalize(table[face]);
}

inline std::vector<float> cube_pixels(int n, const Radiance& f) {
  std::vector<float> rgb(static_cast<size_t>(6) * n * n * 3);
  for (int face = 0; face < 6; ++face) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const glm::dvec3 v = f(cube_pixel_direction(face, i, j, n));
        for (int c = 0; c < 3; ++c) rgb[3 * ((static_cast<size_t>(face) * n + j) * n + i) + c] = static_cast<float>(v[c]);
      }
    }
  }
  return rgb;
}

// A sharp map: a small very bright disc (the sun) on a dim sky.
inline Radiance sun_map(const glm::dvec3& sun, double radius_degrees) {
  const double cos_radius = std::cos(radius_degrees * kPi / 180.0);
  return [=](const glm::dvec3& d) {
    const double sky = 0.2 + 0.1 * d.z;
    return glm::dot(d, sun) > cos_radius ? glm::dvec3(500.0, 400.0, 300.0) : glm::dvec3(sky, sky, 1.5 * sky);
  };
}

inline double luminance(const glm::dvec3& v) { return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z; }

// A random positive band-limited RGB function of order s: coefficients c[3 i + ch].
struct BandLimited {
  int order;
  std::vector<double> c;
  glm::dvec3 operator()(const glm::dvec3& d) const {
    const std::vector<double> y = sh_basis(order, d);
    glm::dvec3 v(0.0);
    for (int i = 0; i < sh_count(order); ++i) v += y[i] * glm::dvec3(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
    return v;
  }
};

inline BandLimited random_band_limited(int order, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  BandLimited f{order, std::vector<double>(3 * sh_count(order))};
  std::array<double, 3> bound = {0.0, 0.0, 0.0};
  for (int l = 1; l <= order; ++l) {
    for (int m = -l; m <= l; ++m) {
      for (int ch = 0; ch < 3; ++ch) {
        const double v = normal(rng) / (l + 1.0);
        f.c[3 * sh_index(l, m) + ch] = v;
        bound[ch] += std::abs(v) * std::sqrt(2.0 * l + 1.0);  // |y_lm| <= sqrt(2l+1)
      }
    }
  }
  for (int ch = 0; ch < 3; ++ch) f.c[ch] = 0.5 + bound[ch];  // positive everywhere: nothing clamped
  return f;
}

// `count` floats uniform in [0, max), drawn from rng in order: random pixels of a test map.
inline std::vector<float> random_pixels(size_t count, float max, std::mt19937_64& rng) {
  std::uniform_real_distribution<float> uniform(0.0f, max);
  std::vector<float> pixels(count);
  for (float& v : pixels) v = uniform(rng);
  return pixels;
}

inline double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

inline double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

// Relative coefficient error of the projection of a sampled band-limited function.
inline double recovery_error(const BandLimited& f, const std::vector<double>& projected) {
  return max_abs_difference(projected, f.c) / max_abs(f.c);
}

// Σ_texels L y_lm Δμ written directly over the texels (the definition of sh()).
// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n, independent of the library's rules).
inline void gauss_legendre(int n, std::vector<double>& t, std::vector<double>& w) {
  t.assign(n, 0.0);
  w.assign(n, 0.0);
  for (int k = 0; k < n; ++k) {
    double x = std::cos(kPi * (k + 0.75) / (n + 0.5));
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = x;
      for (int l = 2; l <= n; ++l) {
        const double p2 = ((2.0 * l - 1.0) * x * p1 - (l - 1.0) * p0) / l;
        p0 = p1, p1 = p2;
      }
      const double dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) {
        w[k] = 2.0 / ((1.0 - x * x) * dp * dp);
        break;
      }
    }
    t[k] = x;
  }
}

// L_lm = Σ_texels L ∫_texel y_lm dμ by a 12 × 12 Gauss–Legendre product rule on every texel: in
// (θ, φ) with the area element sin θ dθ dφ for equirect maps, in the face coordinates (a, b) with
// da db / (1 + a² + b²)^{3/2} for cube maps (texels of at least 1/4 of a face side: error < 1e-12).
inline std::vector<double> brute_force_sh(const Environment& env, int order) {
  constexpr int kPoints = 12;
  std::vector<double> x, w;
  gauss_legendre(kPoints, x, w);
  for (int q = 0; q < kPoints; ++q) {  // to [0, 1]
    x[q] = 0.5 * (x[q] + 1.0);
    w[q] *= 0.5;
  }
  const int width = env.width(), height = env.height();
  std::vector<double> out(3 * sh_count(order), 0.0);
  for (int64_t t = 0; t < env.texel_count(); ++t) {
    std::vector<double> integral(sh_count(order), 0.0);
    for (int qa = 0; qa < kPoints; ++qa) {
      for (int qb = 0; qb < kPoints; ++qb) {
        glm::dvec3 d;
        double area;
        if (env.layout() == EnvironmentLayout::Equirect) {
          const int j = static_cast<int>(t / width), i = static_cast<int>(t % width);
          const double theta = kPi * (j + x[qa]) / height, phi = kPi - 2.0 * kPi * (i + x[qb]) / width;
          d = glm::dvec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
          area = std::sin(theta) * (kPi / height) * (2.0 * kPi / width) / (4.0 * kPi);
        } else {
          const int64_t row = t / width;
          const int face = static_cast<int>(row / width), j = static_cast<int>(row % width), i = static_cast<int>(t % width);
          const double a = 2.0 * (i + x[qa]) / width - 1.0, b = 2.0 * (j + x[qb]) / width - 1.0;
          // The OpenGL face table of environment.h: face coordinates (sc, tc) to a direction.
          const glm::dvec3 faces[6] = {{1, -b, -a}, {-1, -b, a}, {a, 1, b}, {a, -1, -b}, {a, -b, 1}, {-a, -b, -1}};
          d = glm::normalize(faces[face]);
          area = std::pow(1.0 + a * a + b * b, -1.5) * (2.0 / width) * (2.0 / width) / (4.0 * kPi);
        }
        const std::vector<double> y = sh_basis(order, d);
        for (int i = 0; i < sh_count(order); ++i) integral[i] += w[qa] * w[qb] * area * y[i];
      }
    }
    const glm::dvec3 l = env.texel_radiance(t);
    for (int i = 0; i < sh_count(order); ++i)
      for (int c = 0; c < 3; ++c) out[3 * i + c] += integral[i] * l[c];
  }
  return out;
}

inline std::vector<double> band1_vector(const std::vector<double>& c, int channel) {
  // (L_11, L_1−1, L_10) ∝ (x, y, z) of the light's centroid (y_11 = √3 x, y_1−1 = √3 y, y_10 = √3 z).
  return {c[3 * sh_index(1, 1) + channel], c[3 * sh_index(1, -1) + channel], c[3 * sh_index(1, 0) + channel]};
}

inline glm::dvec3 normalized(const std::vector<double>& v) { return glm::normalize(glm::dvec3(v[0], v[1], v[2])); }

// A per-process scratch directory, removed at exit.
struct ScratchDirectory {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("sd_env_tests_" + std::to_string(::getpid()));
  ScratchDirectory() { std::filesystem::create_directories(path); }
  ~ScratchDirectory() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

inline std::string temp_path(const std::string& name) {
  static ScratchDirectory scratch;
  return (scratch.path / name).string();
}

template <typename T>
inline void write_image(const std::string& path, int width, int height, int channels, const std::vector<T>& data,
                 OIIO::TypeDesc type) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(width, height, channels, type);
  spec.attribute("oiio:UnassociatedAlpha", 1);  // store colour as given, not divided by alpha
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(type, data.data())) << out->geterror();
  ASSERT_TRUE(out->close());
}

inline bool have_blender_hdris() { return std::filesystem::exists(kBlenderWorlds + "sunset.exr"); }

}  // namespace sd::test
