#include "bake/traced_scene.h"

#include "bake/classify_sides.h"
#include "bake/coincidence.h"

#include "util/parallel_for.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace sd {
namespace {

struct BoundingBox {
  glm::dvec3 lo{0.0}, hi{0.0};
  explicit BoundingBox(const std::vector<glm::dvec3>& points) {
    if (points.empty()) return;
    lo = hi = points[0];
    for (const auto& p : points) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  }
  glm::dvec3 centre() const { return 0.5 * (lo + hi); }
  double diagonal() const { return glm::length(hi - lo); }
};

double faceless_offset(const std::vector<glm::dvec3>& points, const OccluderMesh& occluders) {
  for (double diagonal : {BoundingBox(points).diagonal(), BoundingBox(occluders.vertices).diagonal()}) {
    if (diagonal > 0.0) return kFacelessOffset * diagonal;
  }
  return 1e-6;  // a single point and nothing else: any offset is as good
}

std::vector<glm::dvec3> shifted(const std::vector<glm::dvec3>& points, const glm::dvec3& by) {
  std::vector<glm::dvec3> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) out[i] = points[i] - by;
  return out;
}

// The triangles around each vertex (compressed rows), degenerate ones left out: they have no side.
struct Fans {
  std::vector<std::size_t> offsets;  // [N+1]
  std::vector<unsigned> triangles;

  Fans(std::size_t vertex_count, const std::vector<Triangle>& mesh, const std::vector<double>& areas)
      : offsets(vertex_count + 1, 0) {
    for (std::size_t t = 0; t < mesh.size(); ++t) {
      if (areas[t] > 0.0) {
        for (int k = 0; k < 3; ++k) ++offsets[mesh[t][k] + 1];
      }
    }
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    triangles.resize(offsets.back());
    std::vector<std::size_t> fill(offsets.begin(), offsets.end() - 1);
    for (std::size_t t = 0; t < mesh.size(); ++t) {
      if (areas[t] > 0.0) {
        for (int k = 0; k < 3; ++k) triangles[fill[mesh[t][k]]++] = static_cast<unsigned>(t);
      }
    }
  }
};

// How the probes read every surface (classify_sides): the object's and the occluders' faces of a
// closed solid by their outward winding, every other face as a sheet, whose both sides are free.
void orient_surfaces(EmbreeScene& scene, const std::vector<glm::dvec3>& points, const std::vector<Triangle>& triangles,
                     const std::vector<unsigned>& traced_id, int object, const OccluderMesh& occluders, int others,
                     const ParallelOptions& parallel) {
  if (triangles.empty() && occluders.triangles.empty()) return;  // nothing to orient (probe points alone)
  std::vector<glm::dvec3> all(points);
  all.insert(all.end(), occluders.vertices.begin(), occluders.vertices.end());
  std::vector<Triangle> faces(triangles);
  std::vector<SceneFace> in_scene;
  for (std::size_t t = 0; t < triangles.size(); ++t) in_scene.push_back({object, traced_id[t]});
  const auto base = static_cast<std::int64_t>(points.size());
  for (std::size_t t = 0; t < occluders.triangles.size(); ++t) {
    const Triangle& o = occluders.triangles[t];
    faces.push_back({o[0] + base, o[1] + base, o[2] + base});
    in_scene.push_back({others, static_cast<unsigned>(t)});
  }
  glm::dvec3 lo = all[0], hi = all[0];
  for (const auto& p : all) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  ParallelOptions unreported(parallel.threads);  // quick beside the origins, which report progress
  unreported.cancel = parallel.cancel;
  const std::vector<FaceSides> sides = classify_sides(all, faces, scene, in_scene, reach_past(lo, hi), unreported);
  std::vector<std::int8_t> object_orientation(traced_id.empty() ? 0 : *std::max_element(traced_id.begin(), traced_id.end()) + 1);
  std::vector<std::int8_t> other_orientation(occluders.triangles.size());
  for (std::size_t t = 0; t < faces.size(); ++t) {
    const std::int8_t orientation = probe_orientation(sides[t]);
    if (t < triangles.size()) {
      object_orientation[traced_id[t]] = orientation;
    } else {
      other_orientation[t - triangles.size()] = orientation;
    }
  }
  scene.orient(object, std::move(object_orientation));
  scene.orient(others, std::move(other_orientation));
}

}  // namespace

TracedScene::TracedScene(const std::vector<glm::dvec3>& vertices, const std::vector<glm::dvec3>& unit_normals,
                         const std::vector<Triangle>& triangles, const OccluderMesh& occluders,
                         const ParallelOptions& parallel, bool offset_origins)
    : centre_(BoundingBox(vertices).centre()) {
  const std::vector<glm::dvec3> points = shifted(vertices, centre_);
  const OccluderMesh shifted_occluders{shifted(occluders.vertices, centre_), occluders.triangles};
  const std::vector<unsigned> representative = coincident_representatives(points);
  const std::vector<Triangle> welded = welded_triangles(triangles, representative);

  // A sheet (a face and its reverse) is traced once, as its first copy; the vertices of the second
  // copy only are its back's.
  const std::vector<std::int64_t> twin = reversed_twins(welded);
  auto hidden = [&](std::size_t t) { return twin[t] >= 0 && static_cast<std::size_t>(twin[t]) < t; };
  std::vector<Triangle> traced;
  std::vector<unsigned> traced_id(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (hidden(t)) continue;
    traced_id[t] = static_cast<unsigned>(traced.size());
    traced.push_back(triangles[t]);
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (hidden(t)) traced_id[t] = traced_id[twin[t]];
  }
  std::vector<std::uint8_t> on_back(points.size(), 0), on_front(points.size(), 0);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) (hidden(t) ? on_back : on_front)[triangles[t][k]] = 1;
  }
  const int object = scene_.add(points, traced);
  const int others = scene_.add(shifted_occluders.vertices, shifted_occluders.triangles);
  scene_.commit();
  orient_surfaces(scene_, points, triangles, traced_id, object, shifted_occluders, others, parallel);

  std::vector<double> areas(triangles.size());
  std::vector<glm::dvec3> centroids(triangles.size()), area_normals(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const glm::dvec3 &a = points[triangles[t][0]], &b = points[triangles[t][1]], &c = points[triangles[t][2]];
    area_normals[t] = 0.5 * glm::cross(b - a, c - a);
    areas[t] = glm::length(area_normals[t]);
    centroids[t] = (a + b + c) / 3.0;
  }
  // The faces through each vertex's point, on each side of the sheets there (one side elsewhere).
  std::vector<double> front_areas(areas), back_areas(areas);
  for (std::size_t t = 0; t < triangles.size(); ++t) (hidden(t) ? front_areas : back_areas)[t] = 0.0;
  const Fans front_fans(points.size(), welded, front_areas), back_fans(points.size(), welded, back_areas);
  const double faceless = faceless_offset(points, shifted_occluders);
  const std::vector<glm::dvec3> fibonacci = spherical_fibonacci(kCandidateDirections);

  origins_.resize(points.size());
  const ParallelOutcome outcome = parallel_for(points.size(), 64, [&](std::size_t begin, std::size_t end) {
    std::vector<unsigned> fan, probed, skipped;
    std::vector<std::size_t> order(fibonacci.size());
    for (std::size_t v = begin; v < end; ++v) {
      const glm::dvec3& p = points[v];
      const glm::dvec3& n = unit_normals[v];
      const unsigned r = representative[v];
      const bool back = on_back[v] != 0 && on_front[v] == 0;   // the sheet's back copy alone
      const Fans& fans = back ? back_fans : front_fans;
      fan.assign(fans.triangles.begin() + fans.offsets[r], fans.triangles.begin() + fans.offsets[r + 1]);
      skipped.resize(fan.size());
      for (std::size_t i = 0; i < fan.size(); ++i) skipped[i] = traced_id[fan[i]];
      const double floor = kOriginFloat * largest_coordinate(p);
      if (fan.empty() || !offset_origins) {
        origins_[v] = p + std::max(faceless, floor) * n;
        continue;
      }
      double shortest = std::numeric_limits<double>::infinity(), area = 0.0;
      glm::dvec3 centre(0.0), faces_normal(0.0);
      for (unsigned t : fan) {
        faces_normal += area_normals[t];
        for (int k = 0; k < 3; ++k) {
          const double edge = glm::length(points[triangles[t][k]] - points[triangles[t][(k + 1) % 3]]);
          if (edge > 0.0) shortest = std::min(shortest, edge);
        }
        centre += areas[t] * centroids[t];
        area += areas[t];
      }
      const double eta = std::max(kOriginOffset * shortest, floor);
      glm::dvec3 into_faces = (centre / area - p) / shortest;
      // Across the normal only, and at most as long: at a convex hard edge the faces beyond it pull
      // back along −n, which left q in the plane of p's own faces.
      into_faces -= glm::dot(into_faces, n) * n;
      const double reach = glm::length(into_faces);
      if (reach > 1.0) into_faces /= reach;

      probed.clear();  // the largest faces, chosen only when a candidate needs them
      auto passes = [&](const glm::dvec3& q) {
        const glm::dvec3 to_p = p - q;
        const double distance = glm::length(to_p);
        const EmbreeScene::Hit through = scene_.first_hit(q, to_p / distance, 2.0 * distance, object, skipped);
        if (through.side == EmbreeScene::Side::kBack) return false;
        // A sheet between q and p separates them; one through p (a floor under the vertex) has no
        // inside to tell q's side by: the probes towards the faces do.
        bool sheet_at_p = false;
        if (through.side == EmbreeScene::Side::kSheet) {
          if (through.t < (1.0 - kSheetTolerance) * distance) return false;
          sheet_at_p = through.t <= (1.0 + kSheetTolerance) * distance;
        }
        // In front of every face around p, a segment from q to a face's centroid can meet those
        // faces only from the front: the probes towards them can fail only at concave vertices.
        if (!sheet_at_p &&
            std::all_of(fan.begin(), fan.end(), [&](unsigned t) { return glm::dot(q - p, area_normals[t]) > 0.0; })) {
          return true;
        }
        if (probed.empty()) {
          probed = fan;
          std::sort(probed.begin(), probed.end(), [&](unsigned a, unsigned b) { return areas[a] > areas[b]; });
          if (probed.size() > static_cast<std::size_t>(kProbedFaces)) probed.resize(kProbedFaces);
        }
        for (unsigned t : probed) {
          const glm::dvec3 to_face = centroids[t] - q;
          const double length = glm::length(to_face);
          const EmbreeScene::Hit hit = scene_.first_hit(q, to_face / length, 1.01 * length);
          if (hit.side == EmbreeScene::Side::kBack) return false;
          if (hit.side == EmbreeScene::Side::kSheet && hit.t < (1.0 - kSheetTolerance) * length) return false;
        }
        return true;
      };
      auto at = [&](const glm::dvec3& u) { return p + eta * glm::normalize(u); };

      const glm::dvec3 first = at(n + into_faces);
      // The given normal first; then the faces' own (a flipped normal points into the solid).
      const glm::dvec3 outward = glm::length(faces_normal) > 0.0 ? glm::normalize(faces_normal) : n;
      glm::dvec3 chosen = first;
      if (!passes(first) && !passes(chosen = at(n)) && !passes(chosen = at(outward))) {
        std::iota(order.begin(), order.end(), std::size_t{0});
        std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
          return glm::dot(fibonacci[a], outward) > glm::dot(fibonacci[b], outward);
        });
        chosen = first;
        for (std::size_t i : order) {
          const glm::dvec3 q = at(fibonacci[i]);
          if (passes(q)) {
            chosen = q;
            break;
          }
        }
      }
      origins_[v] = chosen;
    }
  }, parallel);
  if (!outcome.completed) {
    throw BakeCancelled("cancelled while finding the ray origins (" + std::to_string(outcome.done) + " of " +
                        std::to_string(points.size()) + " vertices)");
  }
}

std::vector<glm::dvec3> TracedScene::object_space_origins() const { return shifted(origins_, -centre_); }

}  // namespace sd
