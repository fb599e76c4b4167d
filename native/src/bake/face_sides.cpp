#include "sdlighting/face_sides.h"

#include "sdlighting/visibility.h"

#include "bake/classify_sides.h"
#include "bake/coincidence.h"
#include "bake/traced_scene.h"
#include "util/parallel_for.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <string>

namespace sd {
namespace {

// A triangle's side of an undirected edge between welded points a < b.
struct EdgeUse {
  std::int64_t a, b;
  std::uint32_t triangle;
  bool forward;  // the triangle runs a -> b
  bool operator<(const EdgeUse& o) const { return a != o.a ? a < o.a : (b != o.b ? b < o.b : triangle < o.triangle); }
};

// A link between two triangles across an edge that only they share.
struct Link {
  std::uint32_t other;
  bool agree;  // their windings agree across the edge (they run it in opposite directions)
};

// The triangles joined edge to edge (through edges shared by exactly two), each wound relative to
// the first of its piece, and whether a piece is closed and orientable.
struct Pieces {
  std::vector<std::int64_t> piece;       // per triangle; -1 for one left out
  std::vector<std::uint8_t> reversed;    // per triangle: wound against its piece's orientation
  std::vector<std::uint8_t> closed;      // per piece

  Pieces(const std::vector<Triangle>& welded, const std::vector<std::uint8_t>& left_out)
      : piece(welded.size(), -1), reversed(welded.size(), 0) {
    std::vector<EdgeUse> uses;
    uses.reserve(3 * welded.size());
    for (std::size_t t = 0; t < welded.size(); ++t) {
      if (left_out[t]) continue;
      for (int k = 0; k < 3; ++k) {
        const std::int64_t u = welded[t][k], v = welded[t][(k + 1) % 3];
        uses.push_back({std::min(u, v), std::max(u, v), static_cast<std::uint32_t>(t), u < v});
      }
    }
    std::sort(uses.begin(), uses.end());
    std::vector<std::vector<Link>> links(welded.size());
    std::vector<std::uint8_t> open(welded.size(), 0);  // beside a border or a non-manifold edge
    for (std::size_t i = 0; i < uses.size();) {
      std::size_t j = i;
      while (j < uses.size() && uses[j].a == uses[i].a && uses[j].b == uses[i].b) ++j;
      if (j - i == 2) {
        const bool agree = uses[i].forward != uses[i + 1].forward;
        links[uses[i].triangle].push_back({uses[i + 1].triangle, agree});
        links[uses[i + 1].triangle].push_back({uses[i].triangle, agree});
      } else {
        for (std::size_t k = i; k < j; ++k) open[uses[k].triangle] = 1;
      }
      i = j;
    }
    std::deque<std::uint32_t> queue;
    for (std::size_t start = 0; start < welded.size(); ++start) {
      if (left_out[start] || piece[start] >= 0) continue;
      const auto id = static_cast<std::int64_t>(closed.size());
      bool is_closed = true;
      piece[start] = id;
      queue.push_back(static_cast<std::uint32_t>(start));
      while (!queue.empty()) {
        const std::uint32_t t = queue.front();
        queue.pop_front();
        if (open[t]) is_closed = false;
        for (const Link& link : links[t]) {
          const std::uint8_t wound = reversed[t] ^ (link.agree ? 0 : 1);
          if (piece[link.other] < 0) {
            piece[link.other] = id;
            reversed[link.other] = wound;
            queue.push_back(link.other);
          } else if (reversed[link.other] != wound) {
            is_closed = false;  // not orientable: no inside
          }
        }
      }
      closed.push_back(is_closed ? 1 : 0);
    }
  }
};

}  // namespace

std::vector<FaceSides> classify_sides(const std::vector<glm::dvec3>& points, const std::vector<Triangle>& triangles,
                                      const EmbreeScene& scene, const std::vector<SceneFace>& in_scene, double reach,
                                      const ParallelOptions& parallel) {
  std::vector<FaceSides> sides(triangles.size(), FaceSides::kFront);
  const std::vector<Triangle> welded = welded_triangles(triangles, coincident_representatives(points));
  // A face given twice in one winding is one face: only its first copy is looked at (and its
  // repeats take its answer at the end), so that it joins no piece twice.
  const std::vector<std::int64_t> first = first_copies(welded);
  std::vector<Triangle> unique;
  std::vector<std::int64_t> unique_index(triangles.size(), -1);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (first[t] != static_cast<std::int64_t>(t)) continue;
    unique_index[t] = static_cast<std::int64_t>(unique.size());
    unique.push_back(welded[t]);
  }
  const std::vector<std::int64_t> unique_twin = reversed_twins(unique);
  std::vector<glm::dvec3> area_normals(triangles.size());
  std::vector<std::uint8_t> left_out(triangles.size(), 0);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const glm::dvec3 &a = points[triangles[t][0]], &b = points[triangles[t][1]], &c = points[triangles[t][2]];
    area_normals[t] = 0.5 * glm::cross(b - a, c - a);
    const Triangle& w = welded[t];
    const bool degenerate = !(glm::length(area_normals[t]) > 0.0) || w[0] == w[1] || w[1] == w[2] || w[2] == w[0];
    const bool sheet = unique_index[t] >= 0 && unique_twin[unique_index[t]] >= 0;
    if (sheet) sides[t] = FaceSides::kSheet;
    left_out[t] = degenerate || sheet || unique_index[t] < 0;
  }

  // Closed pieces: the outside is where the signed volume says. A closed piece without volume
  // (flat, folded onto itself) has no inside and is looked at as an open one.
  const Pieces pieces(welded, left_out);
  std::vector<double> volume(pieces.closed.size(), 0.0), area(pieces.closed.size(), 0.0);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (pieces.piece[t] < 0 || !pieces.closed[pieces.piece[t]]) continue;
    const double signed_volume = glm::dot(points[triangles[t][0]], area_normals[t]) / 3.0;
    volume[pieces.piece[t]] += pieces.reversed[t] ? -signed_volume : signed_volume;
    area[pieces.piece[t]] += glm::length(area_normals[t]);
  }
  // Open pieces: a sample of each one's faces looks at its backs.
  std::vector<std::vector<std::uint32_t>> open_faces(pieces.closed.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (left_out[t]) continue;
    const std::int64_t p = pieces.piece[t];
    if (pieces.closed[p] && std::abs(volume[p]) > 1e-9 * std::pow(area[p], 1.5)) {
      const bool outward = (pieces.reversed[t] != 0) == (volume[p] < 0.0);
      sides[t] = outward ? FaceSides::kFront : FaceSides::kFlipped;
    } else {
      open_faces[p].push_back(static_cast<std::uint32_t>(t));
    }
  }
  std::vector<std::uint32_t> looked_at, looked_piece;  // the sampled faces (evenly over each piece)
  for (std::size_t p = 0; p < open_faces.size(); ++p) {
    const std::vector<std::uint32_t>& faces = open_faces[p];
    const std::size_t count = std::min(faces.size(), static_cast<std::size_t>(kSideFaces));
    for (std::size_t i = 0; i < count; ++i) {
      looked_at.push_back(faces[i * faces.size() / count]);
      looked_piece.push_back(static_cast<std::uint32_t>(p));
    }
  }
  // The back hemisphere's half of a Fibonacci set and its mirror image across the face frame's
  // (tangent, normal) plane: a mirrored mesh, whose frames are mirrored, then traces the mirrored rays.
  std::vector<glm::dvec3> directions;
  for (const glm::dvec3& d : spherical_fibonacci(kSideRays)) {
    if (d.z >= 0.0) continue;
    directions.push_back(d);
    directions.emplace_back(d.x, -d.y, d.z);
  }

  std::vector<std::uint32_t> free_rays(looked_at.size(), 0);  // per sampled face: not met from behind
  const ParallelOutcome outcome = parallel_for(looked_at.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t t = looked_at[i];
      const glm::dvec3 &a = points[triangles[t][0]], &b = points[triangles[t][1]], &c = points[triangles[t][2]];
      const double shortest = std::min({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
      const glm::dvec3 centroid = (a + b + c) / 3.0;
      const glm::dvec3 n = glm::normalize(area_normals[t]);
      const double eta = std::max(kOriginOffset * shortest, kOriginFloat * largest_coordinate(centroid));
      const glm::dvec3 behind = centroid - eta * n;
      // The rays in the face's own frame, from its first point (the lowest welded index): turning
      // or mirroring the mesh turns them with it, so it does not change the answer.
      const Triangle& w = welded[t];
      const int corner = static_cast<int>(std::min_element(w.begin(), w.end()) - w.begin());
      const glm::dvec3 tangent = glm::normalize(points[triangles[t][corner]] - centroid);
      const glm::dvec3 bitangent = glm::cross(n, tangent);
      const std::vector<unsigned> own{in_scene[t].primitive};
      for (const glm::dvec3& local : directions) {
        const glm::dvec3 d = local.x * tangent + local.y * bitangent + local.z * n;
        // coplanar hits count as one within the face's own offset, not a fraction of the reach
        if (scene.first_hit(behind, d, reach, in_scene[t].geometry, own, eta).side != EmbreeScene::Side::kBack) {
          ++free_rays[i];
        }
      }
    }
  }, parallel);
  if (!outcome.completed) {
    throw BakeCancelled("cancelled while looking at the faces' backs (" + std::to_string(outcome.done) + " of " +
                        std::to_string(looked_at.size()) + " faces)");
  }
  std::vector<double> free_share(open_faces.size(), 0.0), sampled(open_faces.size(), 0.0);
  for (std::size_t i = 0; i < looked_at.size(); ++i) {
    free_share[looked_piece[i]] += free_rays[i];
    sampled[looked_piece[i]] += static_cast<double>(directions.size());
  }
  for (std::size_t p = 0; p < open_faces.size(); ++p) {
    const bool seen = sampled[p] > 0.0 && free_share[p] >= kSeenShare * sampled[p];
    for (std::uint32_t t : open_faces[p]) sides[t] = seen ? FaceSides::kBoth : FaceSides::kFront;
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) sides[t] = sides[first[t]];
  return sides;
}

std::int8_t probe_orientation(FaceSides sides) {
  switch (sides) {
    case FaceSides::kFront: return 1;
    case FaceSides::kFlipped: return -1;
    default: return 0;
  }
}

std::vector<FaceSides> face_sides(const std::vector<glm::dvec3>& vertices, const std::vector<Triangle>& triangles,
                                  const OccluderMesh& occluders, const FaceSidesOptions& options) {
  check_points("vertices", vertices);
  check_triangles("triangles", triangles, vertices.size(), "vertices");
  check_points("occluder_vertices", occluders.vertices);
  check_triangles("occluder_triangles", occluders.triangles, occluders.vertices.size(), "occluder_vertices");
  if (triangles.empty()) return {};
  // Centred, as the bake traces (traced_scene.h), so float32 keeps the object's precision.
  glm::dvec3 lo = vertices[0], hi = vertices[0];
  for (const auto& p : vertices) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::dvec3 centre = 0.5 * (lo + hi);
  std::vector<glm::dvec3> points(vertices.size()), occluder_points(occluders.vertices.size());
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = vertices[i] - centre;
  for (std::size_t i = 0; i < occluder_points.size(); ++i) {
    occluder_points[i] = occluders.vertices[i] - centre;
    lo = glm::min(lo, occluders.vertices[i]);
    hi = glm::max(hi, occluders.vertices[i]);
  }
  EmbreeScene scene;
  const int object = scene.add(points, triangles);
  scene.add(occluder_points, occluders.triangles);
  scene.commit();
  std::vector<SceneFace> in_scene(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) in_scene[t] = {object, static_cast<unsigned>(t)};
  ParallelOptions parallel(options.threads);
  parallel.progress = options.progress;
  parallel.cancel = options.cancel;
  return classify_sides(points, triangles, scene, in_scene, reach_past(lo, hi), parallel);
}

}  // namespace sd
