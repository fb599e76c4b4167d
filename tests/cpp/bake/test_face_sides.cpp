// Tests of which sides of a mesh's faces the baked copy needs (sdlighting/face_sides.h). The
// answers are exact: the closed pieces are told by topology and volume, the open faces' backs by
// rays that either all meet a surface from behind or do not.
#include "sdlighting/face_sides.h"
#include "sdtesting/meshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace sd {
namespace {

using test::Mesh;

std::vector<Triangle> reversed(std::vector<Triangle> triangles) {
  for (Triangle& t : triangles) std::swap(t[1], t[2]);
  return triangles;
}

std::vector<FaceSides> all(std::size_t count, FaceSides side) { return std::vector<FaceSides>(count, side); }

// The mesh as a triangle soup: every triangle with its own three vertices.
Mesh soup(const Mesh& m) {
  Mesh out;
  for (const Triangle& t : m.triangles) {
    const auto first = static_cast<std::int64_t>(out.vertices.size());
    for (int k = 0; k < 3; ++k) out.vertices.push_back(m.vertices[t[k]]);
    out.triangles.push_back({first, first + 1, first + 2});
  }
  return out;
}

TEST(FaceSidesClosed, AClosedSolidNeedsItsFrontsOnly) {
  const Mesh sphere = test::icosphere(2);
  EXPECT_EQ(face_sides(sphere.vertices, sphere.triangles), all(sphere.triangles.size(), FaceSides::kFront));
}

TEST(FaceSidesClosed, ASolidTurnedInsideOutIsFlipped) {
  const Mesh sphere = test::icosphere(2);
  EXPECT_EQ(face_sides(sphere.vertices, reversed(sphere.triangles)),
            all(sphere.triangles.size(), FaceSides::kFlipped));
}

TEST(FaceSidesClosed, OnlyTheFacesWoundInwardAreFlipped) {
  // Every other face reversed, and the mesh split into a triangle soup (as a flat-shaded import):
  // the pieces are joined through points, not vertex indices.
  Mesh sphere = soup(test::icosphere(2));
  for (std::size_t t = 0; t < sphere.triangles.size(); t += 2) std::swap(sphere.triangles[t][1], sphere.triangles[t][2]);
  const std::vector<FaceSides> sides = face_sides(sphere.vertices, sphere.triangles);
  for (std::size_t t = 0; t < sides.size(); ++t) {
    EXPECT_EQ(sides[t], t % 2 == 0 ? FaceSides::kFlipped : FaceSides::kFront) << "triangle " << t;
  }
}

TEST(FaceSidesClosed, AFaceGivenTwiceIsOneFace) {
  // A closed solid with some of its faces repeated (as the add-on joins sampled faces with the
  // whole mesh): still closed, nothing looked at by rays.
  Mesh sphere = test::icosphere(2);
  const std::size_t count = sphere.triangles.size();
  for (std::size_t t = 0; t < count; t += 3) sphere.triangles.push_back(sphere.triangles[t]);
  EXPECT_EQ(face_sides(sphere.vertices, sphere.triangles), all(sphere.triangles.size(), FaceSides::kFront));
}

TEST(FaceSidesOpen, AHollowOpenAtASmallHoleKeepsItsFronts) {
  // A ball with one face missing (a head open at its eyes): its inside is seen through the hole
  // by few of its rays, and nothing gets a reverse copy - nor in a turned and mirrored copy.
  Mesh ball = test::icosphere(2);
  ball.triangles.pop_back();
  EXPECT_EQ(face_sides(ball.vertices, ball.triangles), all(ball.triangles.size(), FaceSides::kFront));
  const double c = std::cos(0.7), s = std::sin(0.7);
  for (glm::dvec3& p : ball.vertices) p = glm::dvec3(-(c * p.x - s * p.y), s * p.x + c * p.y, p.z);
  for (Triangle& t : ball.triangles) std::swap(t[1], t[2]);
  EXPECT_EQ(face_sides(ball.vertices, ball.triangles), all(ball.triangles.size(), FaceSides::kFront));
}

TEST(FaceSidesOpen, AHollowOpenWideIsSeenInside) {
  // The ball without its top (a bowl): every face of it, also those deep inside, gets a reverse copy.
  Mesh bowl = test::icosphere(2);
  std::vector<Triangle> kept;
  for (const Triangle& t : bowl.triangles) {
    if (bowl.vertices[t[0]].z + bowl.vertices[t[1]].z + bowl.vertices[t[2]].z < 1.5) kept.push_back(t);
  }
  bowl.triangles = kept;
  EXPECT_EQ(face_sides(bowl.vertices, bowl.triangles), all(bowl.triangles.size(), FaceSides::kBoth));
}

TEST(FaceSidesOpen, APlaneIsSeenFromBothSides) {
  const Mesh up = test::square_fan(1.0, 0.0), down = test::square_fan(1.0, 0.0, false);
  EXPECT_EQ(face_sides(up.vertices, up.triangles), all(4, FaceSides::kBoth));
  EXPECT_EQ(face_sides(down.vertices, down.triangles), all(4, FaceSides::kBoth));
}

TEST(FaceSidesOpen, ABoxWithoutALidIsSeenInsideToo) {
  Mesh box = test::solid_box({0, 0, 0}, {1, 1, 1});
  box.triangles.erase(box.triangles.begin() + 2, box.triangles.begin() + 4);  // the top face
  EXPECT_EQ(face_sides(box.vertices, box.triangles), all(10, FaceSides::kBoth));
}

TEST(FaceSidesOpen, ABackInsideASolidIsHidden) {
  // A plane inside a closed cube: every ray from behind it meets the cube's walls from inside.
  // (test::box is wound inward, as a room's walls.)
  const Mesh plane = test::square_fan(0.5, 0.0);
  const OccluderMesh room = test::box(2.0), solid{room.vertices, reversed(room.triangles)};
  EXPECT_EQ(face_sides(plane.vertices, plane.triangles, solid), all(4, FaceSides::kFront));
  // ... but not inside a room, whose walls face the plane.
  EXPECT_EQ(face_sides(plane.vertices, plane.triangles, room), all(4, FaceSides::kBoth));
}

TEST(FaceSidesOpen, BackToBackFacesAreASheetAlready) {
  Mesh plane = test::square_fan(1.0, 0.0);
  const std::vector<Triangle> back = reversed(plane.triangles);
  plane.triangles.insert(plane.triangles.end(), back.begin(), back.end());
  EXPECT_EQ(face_sides(plane.vertices, plane.triangles), all(8, FaceSides::kSheet));
}

TEST(FaceSidesOpen, AFaceWithoutAreaHasNoSide) {
  const std::vector<glm::dvec3> points{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
  EXPECT_EQ(face_sides(points, {{0, 1, 2}, {0, 0, 3}}), all(2, FaceSides::kFront));
}

TEST(FaceSidesInput, BadIndicesAreRefused) {
  EXPECT_THROW(face_sides({{0, 0, 0}}, {{0, 1, 2}}), std::invalid_argument);
}

}  // namespace
}  // namespace sd
