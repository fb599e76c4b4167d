// Environment's texel geometry and its area-averaged copies (the layouts of environment.h; the
// formulas themselves are in texel_layout.h).
#include "sdlighting/environment.h"

#include "environment/image_io.h"
#include "environment/texel_layout.h"
#include "sdlighting/limits.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sd {

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


int64_t Environment::texel_index(const glm::dvec3& dir) const {
  check_direction(dir);
  if (layout_ == EnvironmentLayout::Equirect) {
    const auto [j, i] = equirect_cell(dir, width_, height_);
    return static_cast<int64_t>(j) * width_ + i;
  }
  return cube_index(dir, width_);
}

Environment Environment::area_averaged(int width, int height) const {
  check_range("area_averaged: width", width, 1, kMaxImageSide);
  check_range("area_averaged: height", height, 1, kMaxImageSide);
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

}  // namespace sd
