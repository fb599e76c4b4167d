#include "bake/coincidence.h"

#include <algorithm>
#include <array>
#include <numeric>
#include <utility>

namespace sd {
namespace {

// The triangle turned so that its smallest index comes first: equal for every rotation of one
// winding, different for the other.
Triangle rotated_to_smallest(const Triangle& t) {
  const int first = static_cast<int>(std::min_element(t.begin(), t.end()) - t.begin());
  return {t[first], t[(first + 1) % 3], t[(first + 2) % 3]};
}

}  // namespace

std::vector<unsigned> coincident_representatives(const std::vector<glm::dvec3>& points) {
  std::vector<unsigned> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](unsigned a, unsigned b) {
    const glm::dvec3 &p = points[a], &q = points[b];
    if (p.x != q.x) return p.x < q.x;
    if (p.y != q.y) return p.y < q.y;
    if (p.z != q.z) return p.z < q.z;
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<unsigned> representative(points.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    const bool same = i > 0 && points[order[i]] == points[order[i - 1]];
    representative[order[i]] = same ? representative[order[i - 1]] : order[i];
  }
  return representative;
}

std::vector<Triangle> welded_triangles(const std::vector<Triangle>& triangles,
                                       const std::vector<unsigned>& representative) {
  std::vector<Triangle> welded(triangles);
  for (Triangle& t : welded) {
    for (int k = 0; k < 3; ++k) t[k] = representative[t[k]];
  }
  return welded;
}

std::vector<std::int64_t> first_copies(const std::vector<Triangle>& welded) {
  std::vector<std::pair<Triangle, std::int64_t>> keyed(welded.size());
  for (std::size_t t = 0; t < welded.size(); ++t) keyed[t] = {rotated_to_smallest(welded[t]), static_cast<std::int64_t>(t)};
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::int64_t> first(welded.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    const bool repeat = i > 0 && keyed[i].first == keyed[i - 1].first;
    first[keyed[i].second] = repeat ? first[keyed[i - 1].second] : keyed[i].second;
  }
  return first;
}

std::vector<std::int64_t> reversed_twins(const std::vector<Triangle>& welded) {
  std::vector<std::pair<Triangle, std::int64_t>> keyed;  // (the winding's key, triangle), sorted
  keyed.reserve(welded.size());
  for (std::size_t t = 0; t < welded.size(); ++t) {
    const Triangle& w = welded[t];
    if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0]) continue;
    keyed.emplace_back(rotated_to_smallest(w), static_cast<std::int64_t>(t));
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::int64_t> twin(welded.size(), -1);
  for (const auto& [key, t] : keyed) {
    if (twin[t] >= 0) continue;
    const Triangle reversed = rotated_to_smallest({key[0], key[2], key[1]});
    auto it = std::lower_bound(keyed.begin(), keyed.end(), std::make_pair(reversed, std::int64_t{-1}));
    for (; it != keyed.end() && it->first == reversed; ++it) {
      if (twin[it->second] < 0) {
        twin[t] = it->second;
        twin[it->second] = t;
        break;
      }
    }
  }
  return twin;
}

}  // namespace sd
