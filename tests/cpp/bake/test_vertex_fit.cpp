// Least-squares vertex values (sdlighting/vertex_fit.h): exact cases, the minimizer of a case
// solved by hand, thread independence, and bad input.
#include "sdlighting/vertex_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace sd {
namespace {

constexpr double kExact = 1e-12;

// A 4 x 4 grid of vertices on the unit square, two triangles per cell.
struct Grid {
  std::vector<glm::dvec3> points;
  std::vector<Triangle> triangles;
};

Grid grid() {
  Grid g;
  const int n = 4;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) g.points.emplace_back(i / 3.0, j / 3.0, 0.0);
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const std::int64_t a = j * n + i;
      g.triangles.push_back({a, a + 1, a + n + 1});
      g.triangles.push_back({a, a + n + 1, a + n});
    }
  }
  return g;
}

// Samples at the vertices and at three inner points of every triangle, of f(p) (two channels: f
// and 2 f).
MeshSamples sample(const Grid& g, double (*f)(const glm::dvec3&), std::vector<double>& values) {
  MeshSamples s;
  for (std::size_t v = 0; v < g.points.size(); ++v) {
    const auto i = static_cast<std::int64_t>(v);
    s.triangles.push_back({i, i, i});
    s.barycentric.emplace_back(1.0, 0.0, 0.0);
  }
  for (const Triangle& t : g.triangles) {
    for (const glm::dvec3 b : {glm::dvec3(0.6, 0.2, 0.2), glm::dvec3(0.2, 0.6, 0.2), glm::dvec3(0.2, 0.2, 0.6)}) {
      s.triangles.push_back(t);
      s.barycentric.push_back(b);
    }
  }
  for (std::size_t k = 0; k < s.triangles.size(); ++k) {
    const Triangle& t = s.triangles[k];
    const glm::dvec3& b = s.barycentric[k];
    const glm::dvec3 p = b.x * g.points[t[0]] + b.y * g.points[t[1]] + b.z * g.points[t[2]];
    s.weights.push_back(1.0);
    values.push_back(f(p));
    values.push_back(2.0 * f(p));
  }
  return s;
}

double linear(const glm::dvec3& p) { return 2.0 * p.x - p.y + 0.5; }
double bump(const glm::dvec3& p) { return std::sin(3.0 * p.x) * std::cos(2.0 * p.y); }

// Differences of neighbours along the grid's rows: zero for a function constant along them only.
std::vector<PenaltyRow> row_differences(const Grid& g) {
  std::vector<PenaltyRow> rows;
  for (std::int64_t v = 0; v + 1 < static_cast<std::int64_t>(g.points.size()); ++v) {
    if ((v + 1) % 4 != 0) rows.push_back({{v, v + 1, 0, 0}, {1.0, -1.0, 0.0, 0.0}});
  }
  return rows;
}

TEST(VertexFit, ReproducesALinearSignalExactly) {
  const Grid g = grid();
  std::vector<double> values;
  const MeshSamples s = sample(g, linear, values);
  const std::vector<double> x = fit_vertex_values(g.points.size(), s, values, 2, {}, 0.0);
  for (std::size_t v = 0; v < g.points.size(); ++v) {
    EXPECT_NEAR(x[2 * v], linear(g.points[v]), kExact);
    EXPECT_NEAR(x[2 * v + 1], 2.0 * linear(g.points[v]), kExact);
  }
}

TEST(VertexFit, MinimizesTheWeightedSquaredErrorOfTheInterpolation) {
  // One triangle: corners sampled at 0 with weight w, the centroid at 1 with weight c. By symmetry
  // every corner takes x, and 3 w x^2 + c (x - 1)^2 is least at x = c / (3 w + c).
  MeshSamples s;
  const double w = 0.25, c = 2.0;
  for (std::int64_t v = 0; v < 3; ++v) {
    s.triangles.push_back({v, v, v});
    s.barycentric.emplace_back(1.0, 0.0, 0.0);
    s.weights.push_back(w);
  }
  s.triangles.push_back({0, 1, 2});
  s.barycentric.emplace_back(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0);
  s.weights.push_back(c);
  const std::vector<double> x = fit_vertex_values(3, s, {0.0, 0.0, 0.0, 1.0}, 1, {}, 0.0);
  for (double value : x) EXPECT_NEAR(value, c / (3.0 * w + c), kExact);
}

TEST(VertexFit, APenaltyPullsTowardsWhatItLeavesFree) {
  // A bumpy signal and penalties on row differences: the fit's rows flatten as smoothness grows,
  // and a huge smoothness leaves each row constant.
  const Grid g = grid();
  std::vector<double> values;
  const MeshSamples s = sample(g, bump, values);
  const std::vector<PenaltyRow> rows = row_differences(g);
  auto spread = [&](double smoothness) {
    const std::vector<double> x = fit_vertex_values(g.points.size(), s, values, 2, rows, smoothness);
    double worst = 0.0;
    for (const PenaltyRow& r : rows) worst = std::max(worst, std::abs(x[2 * r.vertices[0]] - x[2 * r.vertices[1]]));
    return worst;
  };
  const double none = spread(0.0), some = spread(1.0), much = spread(1e8);
  EXPECT_GT(none, some);
  EXPECT_GT(some, much);
  EXPECT_LT(much, 1e-6);
}

TEST(VertexFit, ThreadsChangeNothing) {
  const Grid g = grid();
  std::vector<double> values;
  const MeshSamples s = sample(g, bump, values);
  std::vector<double> wide;   // 20 channels: blocks of columns on several threads
  for (std::size_t k = 0; k < s.triangles.size(); ++k) {
    for (int c = 0; c < 20; ++c) wide.push_back(values[2 * k] * (c + 1));
  }
  EXPECT_EQ(fit_vertex_values(g.points.size(), s, wide, 20, row_differences(g), 0.1, 1),
            fit_vertex_values(g.points.size(), s, wide, 20, row_differences(g), 0.1, 2));
}

TEST(VertexFit, ProgressCountsTheBlocksAndCancels) {
  const Grid g = grid();
  std::vector<double> values;
  const MeshSamples s = sample(g, bump, values);
  std::vector<double> wide;   // 20 channels: 3 blocks
  for (std::size_t k = 0; k < s.triangles.size(); ++k) {
    for (int c = 0; c < 20; ++c) wide.push_back(values[2 * k] * (c + 1));
  }
  std::vector<std::size_t> seen;
  const std::vector<double> x = fit_vertex_values(g.points.size(), s, wide, 20, {}, 0.0, 2,
                                                  [&](std::size_t done, std::size_t total) {
                                                    EXPECT_EQ(total, 3u);
                                                    seen.push_back(done);
                                                    return true;
                                                  });
  ASSERT_GE(seen.size(), 2u);
  EXPECT_EQ(seen.front(), 0u);
  EXPECT_EQ(seen.back(), 3u);
  EXPECT_EQ(x, fit_vertex_values(g.points.size(), s, wide, 20, {}, 0.0, 2));
  // Cancelled before the factorization, and while the blocks are solved.
  EXPECT_THROW(fit_vertex_values(g.points.size(), s, wide, 20, {}, 0.0, 2, [](std::size_t, std::size_t) { return false; }),
               BakeCancelled);
  int calls = 0;
  EXPECT_THROW(fit_vertex_values(g.points.size(), s, wide, 20, {}, 0.0, 2,
                                 [&](std::size_t, std::size_t) { return ++calls < 2; }),
               BakeCancelled);
}

TEST(VertexFit, BadInputIsRejected) {
  const Grid g = grid();
  std::vector<double> values;
  const MeshSamples s = sample(g, linear, values);
  const std::size_t n = g.points.size();
  EXPECT_THROW(fit_vertex_values(n - 1, s, values, 2, {}, 0.0), std::invalid_argument);   // index out of range
  EXPECT_THROW(fit_vertex_values(n, s, values, 3, {}, 0.0), std::invalid_argument);       // values' size
  MeshSamples negative = s;
  negative.weights[0] = -1.0;
  EXPECT_THROW(fit_vertex_values(n, negative, values, 2, {}, 0.0), std::invalid_argument);
  std::vector<double> nan = values;
  nan[3] = std::nan("");
  EXPECT_THROW(fit_vertex_values(n, s, nan, 2, {}, 0.0), std::invalid_argument);
  EXPECT_THROW(fit_vertex_values(n, s, values, 2, {}, -0.5), std::invalid_argument);
  EXPECT_THROW(fit_vertex_values(n, s, values, 2, {{{0, 99, 0, 0}, {1.0, -1.0, 0.0, 0.0}}}, 1.0),
               std::invalid_argument);
}

TEST(VertexFit, UndeterminedVerticesAreAnError) {
  // A vertex no sample reaches; then two that only a difference penalty reaches (their mean is free).
  MeshSamples s;
  s.triangles.push_back({0, 0, 0});
  s.barycentric.emplace_back(1.0, 0.0, 0.0);
  s.weights.push_back(1.0);
  EXPECT_THROW(fit_vertex_values(2, s, {1.0}, 1, {}, 0.0), std::runtime_error);
  EXPECT_THROW(fit_vertex_values(3, s, {1.0}, 1, {{{1, 2, 0, 0}, {1.0, -1.0, 0.0, 0.0}}}, 1.0), std::runtime_error);
  // Tied to the sampled vertex, they are determined.
  const std::vector<double> x = fit_vertex_values(3, s, {1.0}, 1,
                                                  {{{0, 1, 0, 0}, {1.0, -1.0, 0.0, 0.0}},
                                                   {{1, 2, 0, 0}, {1.0, -1.0, 0.0, 0.0}}}, 1.0);
  for (double value : x) EXPECT_NEAR(value, 1.0, 1e-9);
}

}  // namespace
}  // namespace sd
