// Tests of where the bake's rays start (src/bake/traced_scene.h): through bake_transfer's ambient
// occlusion at vertices whose exact visible fraction is known. 4096 rays of the rotated spherical
// Fibonacci rule resolve these piecewise-constant fractions to about 3e-3; the origin offset
// (1e-3 of the shortest edge) moves them by less.
#include "sdlighting/visibility.h"
#include "sdtesting/meshes.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <utility>
#include <vector>

namespace sd {
namespace {

constexpr int kRays = 4096;
constexpr double kFraction = 1e-2;  // Monte Carlo plus origin offset, for fractions of the sphere

using test::Mesh;

OccluderMesh occluder(const Mesh& m) { return OccluderMesh{m.vertices, m.triangles}; }

std::vector<double> ambient_occlusion(const Mesh& m, const OccluderMesh& occluders = {}, bool offset_origins = true) {
  TransferOptions options;
  options.rays = kRays;
  options.offset_origins = offset_origins;
  return bake_transfer(m.vertices, m.normals, m.triangles, options, occluders).ambient_occlusion;
}

// The mesh split at every face corner, each copy with its face's normal (a flat-shaded mesh as the
// add-on bakes it, or a glTF import).
Mesh split_at_corners(const Mesh& welded) {
  Mesh split;
  for (const Triangle& t : welded.triangles) {
    const glm::dvec3 &a = welded.vertices[t[0]], &b = welded.vertices[t[1]], &c = welded.vertices[t[2]];
    const glm::dvec3 normal = glm::normalize(glm::cross(b - a, c - a));
    const auto first = static_cast<std::int64_t>(split.vertices.size());
    for (int k = 0; k < 3; ++k) {
      split.vertices.push_back(welded.vertices[t[k]]);
      split.normals.push_back(normal);
    }
    split.triangles.push_back({first, first + 1, first + 2});
  }
  return split;
}

// A floor plate whose vertex 0 lies on the edge x = 0 where wall_at_x0 rises (split: it carries
// the plate's normal).
Mesh floor_plate() {
  Mesh plate;
  plate.vertices = {{0, 0, 0}, {0, -100, 0}, {100, -100, 0}, {100, 100, 0}, {0, 100, 0}};
  plate.normals.assign(5, glm::dvec3(0, 0, 1));
  plate.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}};
  return plate;
}

OccluderMesh wall_at_x0() {
  return {{{0, -100, 0}, {0, 100, 0}, {0, 100, 100}, {0, -100, 100}}, {{0, 1, 2}, {0, 2, 3}}};
}

TEST(RayOrigins, BoxStandingOnAFloorLeaksNoLightUnderIt) {
  // A bottom corner sees the upper half-space minus the box's octant: 1/2 − 1/8. Its averaged
  // normal points into the floor, so p + εn started below the floor and saw 1/2.
  const std::vector<double> ao = ambient_occlusion(test::solid_box({0, 0, 0}, {1, 1, 1}), test::ground_quad(1000.0, 0.0));
  for (int corner = 0; corner < 4; ++corner) EXPECT_NEAR(ao[corner], 0.375, kFraction) << "bottom corner " << corner;
  for (int corner = 4; corner < 8; ++corner) EXPECT_NEAR(ao[corner], 0.5, kFraction) << "top corner " << corner;
}

TEST(RayOrigins, SplitVertexAtTheFootOfAWallSeesTheOpenQuarter) {
  // floor_plate's vertex 0 at the wall's foot: the open quarter-space x > 0, z > 0 is a quarter of
  // the sphere; p + εn lay in the wall's plane and read as fully blocked.
  EXPECT_NEAR(ambient_occlusion(floor_plate(), wall_at_x0())[0], 0.25, kFraction);
}

TEST(RayOrigins, AWallFacingAwayIsASheetToo) {
  // The same wall wound the other way (facing away from the plate): an open surface is free on
  // both sides whatever its winding, so the quarter-space behind it is not read as inside a solid.
  OccluderMesh wall = wall_at_x0();
  for (Triangle& t : wall.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(ambient_occlusion(floor_plate(), wall)[0], 0.25, kFraction);
}

TEST(RayOrigins, WithoutTheOffsetTheFailuresAboveReturn) {
  // TransferOptions::offset_origins = false (what benchmark_refine measures the offset against):
  // p + ηn for every vertex leaks under the box and blocks the open quarter at the wall's foot.
  const std::vector<double> ao =
      ambient_occlusion(test::solid_box({0, 0, 0}, {1, 1, 1}), test::ground_quad(1000.0, 0.0), false);
  for (int corner = 0; corner < 4; ++corner) EXPECT_NEAR(ao[corner], 0.5, kFraction) << "bottom corner " << corner;
  EXPECT_NEAR(ambient_occlusion(floor_plate(), wall_at_x0(), false)[0], 0.0, kFraction);
}

TEST(RayOrigins, CornerCopiesOfAFlatShadedBoxAreNeverBlack) {
  // The box of BoxStandingOnAFloorLeaksNoLightUnderIt split at every face corner. A copy that
  // knew only its own face did not skip the other faces through its point in its probes and could
  // start behind one: AO 0 where the point sees 3/8 (bottom) or 1/2 (top). A copy's value lies
  // between the limit along its face (1/4: the half-space in front of it less the floor's side)
  // and its point's.
  const Mesh split = split_at_corners(test::solid_box({0, 0, 0}, {1, 1, 1}));
  const std::vector<double> ao = ambient_occlusion(split, test::ground_quad(1000.0, 0.0));
  for (std::size_t v = 0; v < split.vertices.size(); ++v) {
    const double point = split.vertices[v].z == 0.0 ? 0.375 : 0.5;
    EXPECT_GE(ao[v], 0.25 - kFraction) << "copy " << v;
    EXPECT_LE(ao[v], point + kFraction) << "copy " << v;
  }
}

TEST(RayOrigins, EndCapsOfALongThinBarAreNeverBlack) {
  // A bar 2 long and 0.04 x 0.02 across, split at its corners, in free space: a copy on an end cap
  // sees the half-space in front of its cap, 1/2, and at most its corner's 7/8. The faces through
  // a cap's corner include the long sides, whose centroids lie far along the bar: the pull into the
  // faces pointed back along the cap's normal and cancelled it, the origin fell into the cap's
  // plane and every ray met the cap (AO 0 on the caps of a railing in the accuracy report's house).
  const Mesh bar = split_at_corners(test::solid_box({0, 0, 0}, {2.0, 0.04, 0.02}));
  const std::vector<double> ao = ambient_occlusion(bar);
  for (std::size_t v = 0; v < bar.vertices.size(); ++v) {
    EXPECT_GE(ao[v], 0.5 - kFraction) << "copy " << v << " with normal x " << bar.normals[v].x;
    EXPECT_LE(ao[v], 0.875 + kFraction) << "copy " << v;
  }
}

TEST(RayOrigins, ASheetIsOneSurfaceWithAnOriginOnEachSide) {
  // One object: a box standing on a floor given with both windings (a sheet, as the add-on bakes
  // a floor seen from below: the reverse copy with its own vertices and normals). The box's
  // bottom corners see 1/2 − 1/8 as on a one-sided floor; traced as two surfaces, the reverse copy
  // read as met from behind at every corner and its origin fell below the floor (1/2). The floor's
  // copies start on their own sides.
  Mesh mesh = test::solid_box({10, 10, 0}, {11, 11, 1});
  const Mesh up = test::square_fan(1000.0, 0.0), down = test::square_fan(1000.0, 0.0, false);
  for (const Mesh* floor : {&up, &down}) {
    const auto base = static_cast<std::int64_t>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), floor->vertices.begin(), floor->vertices.end());
    mesh.normals.insert(mesh.normals.end(), floor->normals.begin(), floor->normals.end());
    for (const Triangle& t : floor->triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  TransferOptions options;
  options.rays = kRays;
  const TransferBake bake = bake_transfer(mesh.vertices, mesh.normals, mesh.triangles, options);
  for (int corner = 0; corner < 4; ++corner) EXPECT_NEAR(bake.ambient_occlusion[corner], 0.375, kFraction) << corner;
  for (int v = 8; v < 13; ++v) EXPECT_GT(bake.ray_origins[v].z, 0.0) << "front copy " << v;
  for (int v = 13; v < 18; ++v) EXPECT_LT(bake.ray_origins[v].z, 0.0) << "back copy " << v;
  EXPECT_NEAR(bake.ambient_occlusion[13], 0.5, kFraction) << "the back copy's centre";
}

TEST(RayOrigins, ThinSlabBlocksItsLowerHalf) {
  // Two plates 1e-3 of their edge apart, facing away from each other: from the centre of the top
  // one, the lower half-space is blocked; an origin between the plates would see only the gap.
  Mesh slab = test::square_fan(1.0, 0.0);
  const Mesh bottom = test::square_fan(1.0, -1e-3, false);
  for (std::size_t i = 0; i < bottom.vertices.size(); ++i) {
    slab.vertices.push_back(bottom.vertices[i]);
    slab.normals.push_back(bottom.normals[i]);
  }
  for (const Triangle& t : bottom.triangles) slab.triangles.push_back({t[0] + 5, t[1] + 5, t[2] + 5});
  const std::vector<double> ao = ambient_occlusion(slab);
  EXPECT_NEAR(ao[0], 0.5, kFraction);
  EXPECT_NEAR(ao[5], 0.5, kFraction);
}

TEST(RayOrigins, FlippedNormalsStillStartOutsideTheSolid) {
  // Each corner of a box sees 7/8 of the sphere. With the normals flipped into the box, p + εn
  // started inside it and saw nothing; the probes find a point outside instead.
  Mesh inward = test::solid_box({0, 0, 0}, {1, 1, 1});
  for (auto& n : inward.normals) n = -n;
  for (double ao : ambient_occlusion(inward)) EXPECT_NEAR(ao, 0.875, kFraction);
}

TEST(RayOrigins, NeitherPositionNorScaleChangesTheResult) {
  // The bake traces in coordinates centred on the object and offsets by the local edge length, so a
  // box 10⁶ of its size away from the origin, or scaled by 10⁻⁴ or 10⁴, bakes the same values
  // (the rays are the same; only float32 rounding of the geometry differs). Before, a mesh 10⁴
  // of its size away lost 0.07 of its ambient occlusion and at 10⁶ 0.78.
  const Mesh unit = test::solid_box({0, 0, 0}, {1, 1, 1});
  const std::vector<double> reference = ambient_occlusion(unit, test::ground_quad(10.0, 0.0));
  for (const auto& [scale, shift] : {std::pair{1.0, glm::dvec3(1e6, -2e6, 3e6)}, std::pair{1e-4, glm::dvec3(0.0)},
                                     std::pair{1e4, glm::dvec3(0.0)}, std::pair{1e4, glm::dvec3(5e9, 0, 0)}}) {
    auto moved = [&, scale = scale, shift = shift](std::vector<glm::dvec3> points) {
      for (auto& p : points) p = scale * p + shift;
      return points;
    };
    Mesh object = unit;
    object.vertices = moved(object.vertices);
    OccluderMesh ground = test::ground_quad(10.0, 0.0);
    ground.vertices = moved(ground.vertices);
    const std::vector<double> ao = ambient_occlusion(object, ground);
    for (std::size_t v = 0; v < ao.size(); ++v) {
      EXPECT_NEAR(ao[v], reference[v], 2.0 / kRays) << "scale " << scale << ", shift x " << shift.x << ", vertex " << v;
    }
  }
}

TEST(RayOrigins, EnclosedVertexSeesNothing) {
  // A face of a box inside a closed box: no origin in free space exists, nothing escapes.
  const Mesh inner = test::square_fan(0.1, 0.0);
  const std::vector<double> ao = ambient_occlusion(inner, test::box(1.0));
  for (double value : ao) EXPECT_EQ(value, 0.0);
}

TEST(RayOrigins, CancellingWhileTheyAreFoundStopsTheBake) {
  // Finding the origins is the bake's first phase: progress reports no vertex done yet, and
  // returning false there cancels before any ray is traced.
  const test::Mesh m = test::icosphere(4);
  TransferOptions options;
  options.rays = 64;
  std::vector<std::size_t> reported;
  options.progress = [&](std::size_t done, std::size_t) {
    reported.push_back(done);
    return reported.size() < 2;
  };
  EXPECT_THROW(bake_transfer(m.vertices, m.normals, m.triangles, options), BakeCancelled);
  EXPECT_EQ(reported, (std::vector<std::size_t>{0, 0}));
}

TEST(RayOrigins, OriginsAreReturnedCloseToTheirVertices) {
  const Mesh m = test::solid_box({0, 0, 0}, {1, 1, 1});
  TransferOptions options;
  options.rays = 16;
  const TransferBake bake = bake_transfer(m.vertices, m.normals, m.triangles, options);
  ASSERT_EQ(bake.ray_origins.size(), m.vertices.size());
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    const glm::dvec3 offset = bake.ray_origins[v] - m.vertices[v];
    EXPECT_NEAR(glm::length(offset), 1e-3, 1e-9);             // 1e-3 × the shortest edge (1)
    EXPECT_GT(glm::dot(offset, m.normals[v]), 0.0);            // out of the box
  }
}

}  // namespace
}  // namespace sd
