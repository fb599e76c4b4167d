#include "sdlighting/limits.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdtesting/sphere.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <stdexcept>

namespace sd {
namespace {

constexpr double kExact = 1e-12;

using test::random_direction;
using test::random_rotation;

glm::dmat3 rotation_about_z(double angle) {
  glm::dmat3 r(1.0);
  r[0][0] = std::cos(angle), r[1][0] = -std::sin(angle);
  r[0][1] = std::sin(angle), r[1][1] = std::cos(angle);
  return r;
}

std::vector<double> random_coefficients(int order, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::vector<double> c(sh_count(order));
  for (double& v : c) v = normal(rng);
  return c;
}

double evaluate(int order, const std::vector<double>& c, const glm::dvec3& x) {
  const std::vector<double> y = sh_basis(order, x);
  double sum = 0.0;
  for (int i = 0; i < sh_count(order); ++i) sum += c[i] * y[i];
  return sum;
}

double band_entry(const ShRotation& d, int l, int m, int n) {
  return d.band(l)[(m + l) * (2 * l + 1) + (n + l)];
}

// max over i, j of |Σ_k D_ik D_jk − δ_ij| for band l of d: zero for an orthogonal band.
double band_orthogonality_defect(const ShRotation& d, int l) {
  double worst = 0.0;
  for (int i = -l; i <= l; ++i)
    for (int j = -l; j <= l; ++j) {
      double dot = 0.0;
      for (int k = -l; k <= l; ++k) dot += band_entry(d, l, i, k) * band_entry(d, l, j, k);
      worst = std::max(worst, std::abs(dot - (i == j)));
    }
  return worst;
}

TEST(ShRotation, BandsAreOrthogonalUpToOrder16) {
  const int order = 16;
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    const ShRotation d(random_rotation(rng), order);
    for (int l = 0; l <= order; ++l) EXPECT_LT(band_orthogonality_defect(d, l), kExact) << "l=" << l;
  }
}

TEST(ShRotation, StaysOrthogonalAndExactAtMaximumOrder) {
  std::mt19937_64 rng(5);
  const glm::dmat3 r = random_rotation(rng);
  const ShRotation d(r, kMaxShOrder);
  for (int l : {32, 48, 64}) EXPECT_LT(band_orthogonality_defect(d, l), 1e-10) << "l=" << l;
  // The rotated coefficients still evaluate to the turned function.
  const std::vector<double> c = random_coefficients(kMaxShOrder, rng);
  std::vector<double> rotated(c.size());
  d.apply(c.data(), rotated.data());
  double norm = 0.0;
  for (double v : c) norm += v * v;
  norm = std::sqrt(norm);
  for (int point = 0; point < 5; ++point) {
    const glm::dvec3 x = random_direction(rng);
    EXPECT_NEAR(evaluate(kMaxShOrder, rotated, x), evaluate(kMaxShOrder, c, glm::transpose(r) * x), 1e-9 * norm);
  }
}

// The defining property: D(R) c are the coefficients of x ↦ f(Rᵀ x).
TEST(ShRotation, RotatedCoefficientsEvaluateToRotatedFunction) {
  std::mt19937_64 rng(3);
  for (int order : {1, 2, 5, 16}) {
    for (int trial = 0; trial < 5; ++trial) {
      const glm::dmat3 r = random_rotation(rng);
      const std::vector<double> c = random_coefficients(order, rng);
      std::vector<double> rotated(c.size());
      ShRotation(r, order).apply(c.data(), rotated.data());
      double norm = 0.0;
      for (double v : c) norm += v * v;
      norm = std::sqrt(norm);
      for (int point = 0; point < 20; ++point) {
        const glm::dvec3 x = random_direction(rng);
        EXPECT_NEAR(evaluate(order, rotated, x), evaluate(order, c, glm::transpose(r) * x),
                    1e-11 * norm)
            << "order=" << order;
      }
    }
  }
}

TEST(ShRotation, PreservesBandEnergy) {
  const int order = 16;
  std::mt19937_64 rng(17);
  for (int trial = 0; trial < 10; ++trial) {
    const std::vector<double> c = random_coefficients(order, rng);
    std::vector<double> rotated(c.size());
    ShRotation(random_rotation(rng), order).apply(c.data(), rotated.data());
    for (int l = 0; l <= order; ++l) {
      double before = 0.0, after = 0.0;
      for (int m = -l; m <= l; ++m) {
        before += c[sh_index(l, m)] * c[sh_index(l, m)];
        after += rotated[sh_index(l, m)] * rotated[sh_index(l, m)];
      }
      EXPECT_NEAR(after, before, kExact * std::max(1.0, before)) << "l=" << l;
    }
  }
}

TEST(ShRotation, IsAHomomorphism) {
  const int order = 16;
  std::mt19937_64 rng(23);
  for (int trial = 0; trial < 5; ++trial) {
    const glm::dmat3 r1 = random_rotation(rng), r2 = random_rotation(rng);
    const ShRotation d1(r1, order), d2(r2, order), d12(r1 * r2, order);
    for (int l = 0; l <= order; ++l) {
      double worst = 0.0;
      for (int i = -l; i <= l; ++i)
        for (int j = -l; j <= l; ++j) {
          double product = 0.0;
          for (int k = -l; k <= l; ++k) product += band_entry(d1, l, i, k) * band_entry(d2, l, k, j);
          worst = std::max(worst, std::abs(product - band_entry(d12, l, i, j)));
        }
      EXPECT_LT(worst, kExact) << "l=" << l;
    }
  }
}

TEST(ShRotation, IdentityGivesIdentity) {
  const int order = 16;
  const ShRotation d(glm::dmat3(1.0), order);
  EXPECT_EQ(d.order(), order);
  for (int l = 0; l <= order; ++l)
    for (int i = -l; i <= l; ++i)
      for (int j = -l; j <= l; ++j) EXPECT_NEAR(band_entry(d, l, i, j), i == j, kExact);
}

TEST(ShRotation, RotationAboutZHasClosedForm) {
  const double alpha = 0.7;
  const ShRotation d(rotation_about_z(alpha), 16);
  // Band 1 in the order (y, z, x): turning by α about z maps x ↦ cos α x + sin α y.
  const double expected_band1[3][3] = {{std::cos(alpha), 0.0, std::sin(alpha)},
                                       {0.0, 1.0, 0.0},
                                       {-std::sin(alpha), 0.0, std::cos(alpha)}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(d.band(1)[i * 3 + j], expected_band1[i][j], kExact);
  // Every band: f(φ − α) mixes only cos mφ and sin mφ of the same m.
  for (int l = 0; l <= 16; ++l)
    for (int i = -l; i <= l; ++i)
      for (int j = -l; j <= l; ++j) {
        double expected = 0.0;
        if (i == 0 && j == 0) expected = 1.0;
        if (i != 0 && std::abs(i) == std::abs(j)) {
          const double ca = std::cos(std::abs(i) * alpha), sa = std::sin(std::abs(i) * alpha);
          if (i == j) expected = ca;
          else expected = i < 0 ? sa : -sa;  // D[-m][+m] = sin mα, D[+m][-m] = -sin mα
        }
        EXPECT_NEAR(band_entry(d, l, i, j), expected, kExact) << "l=" << l << " " << i << "," << j;
      }
}

TEST(ShRotation, ApplyHandlesInterleavedChannels) {
  const int order = 8, channels = 3;
  std::mt19937_64 rng(29);
  const ShRotation d(random_rotation(rng), order);
  const int k = sh_count(order);
  std::vector<double> interleaved = random_coefficients(order, rng);
  interleaved.resize(size_t(k) * channels);
  for (double& v : interleaved) v = std::normal_distribution<double>()(rng);
  std::vector<double> out(interleaved.size());
  d.apply(interleaved.data(), out.data(), channels);
  for (int c = 0; c < channels; ++c) {
    std::vector<double> single(k), single_out(k);
    for (int i = 0; i < k; ++i) single[i] = interleaved[size_t(i) * channels + c];
    d.apply(single.data(), single_out.data());
    for (int i = 0; i < k; ++i) EXPECT_NEAR(out[size_t(i) * channels + c], single_out[i], kExact);
  }
  EXPECT_THROW(d.apply(interleaved.data(), out.data(), 0), std::invalid_argument);
}

// EulerShRotation against ShRotation: random rotations and those where the Euler angles degenerate
// - β = 0 (a turn about z) and β = π exactly, β within 1e-10 of either, and turns about z whose
// third column carries only rounding (A Aᵀ Rz, A random), where the angles taken from it alone
// would be noise - at bands 0, 1, 5 and 12 of 12, with one, three and seven channels; and the
// bands and channels it refuses.
TEST(EulerShRotation, AgreesWithTheRecurrence) {
  const int order = 12;
  std::mt19937_64 rng(31);
  glm::dmat3 half_turn_about_x(1.0);
  half_turn_about_x[1][1] = half_turn_about_x[2][2] = -1.0;
  glm::dmat3 slight_turn_about_x(1.0);
  slight_turn_about_x[1][2] = 1e-10, slight_turn_about_x[2][1] = -1e-10;  // orthogonal to rounding
  std::vector<glm::dmat3> rotations = {glm::dmat3(1.0), rotation_about_z(2.1), half_turn_about_x,
                                       rotation_about_z(0.4) * half_turn_about_x,
                                       rotation_about_z(0.3) * slight_turn_about_x * rotation_about_z(1.2),
                                       rotation_about_z(-2.5) * half_turn_about_x * slight_turn_about_x};
  for (int trial = 0; trial < 4; ++trial) {
    const glm::dmat3 a = random_rotation(rng);
    const glm::dmat3 rounded = a * (glm::transpose(a) * rotation_about_z(0.7 + trial));
    rotations.push_back(rounded);
    rotations.push_back(rounded * half_turn_about_x);
  }
  for (int trial = 0; trial < 8; ++trial) rotations.push_back(random_rotation(rng));
  const EulerShRotation turn(order);
  EXPECT_EQ(turn.order(), order);
  for (const glm::dmat3& r : rotations) {
    const ShRotation d(r, order);
    for (int channels : {1, 3, 7}) {
      for (int bands : {0, 1, 5, order}) {
        std::vector<double> data(size_t(sh_count(bands)) * channels);
        for (double& v : data) v = std::normal_distribution<double>()(rng);
        std::vector<double> expected(data.size());
        d.apply(data.data(), expected.data(), channels, bands);
        turn.apply(r, data.data(), channels, bands);
        for (size_t i = 0; i < data.size(); ++i) {
          EXPECT_NEAR(data[i], expected[i], kExact) << "bands " << bands << ", channels " << channels << ", " << i;
        }
      }
    }
  }
  std::vector<double> data(size_t(sh_count(order + 1)));
  EXPECT_THROW(turn.apply(glm::dmat3(1.0), data.data(), 1, order + 1), std::invalid_argument);
  EXPECT_THROW(turn.apply(glm::dmat3(1.0), data.data(), 1, -1), std::invalid_argument);
  EXPECT_THROW(turn.apply(glm::dmat3(1.0), data.data(), 0, order), std::invalid_argument);
}

TEST(ShRotation, OrderZeroIsTheScalar) {
  const ShRotation d(rotation_about_z(1.0), 0);
  const double in = 2.5;
  double out = 0.0;
  d.apply(&in, &out);
  EXPECT_EQ(out, 2.5);
}

TEST(ShRotation, RejectsInvalidInput) {
  std::mt19937_64 rng(31);
  const glm::dmat3 r = random_rotation(rng);
  EXPECT_THROW(ShRotation(2.0 * r, 4), std::invalid_argument);
  glm::dmat3 reflection(1.0);
  reflection[2][2] = -1.0;
  EXPECT_THROW(ShRotation(reflection, 4), std::invalid_argument);
  EXPECT_THROW(ShRotation(-r, 4), std::invalid_argument);
  glm::dmat3 skewed = r;
  skewed[0][1] += 1e-4;
  EXPECT_THROW(ShRotation(skewed, 4), std::invalid_argument);
  glm::dmat3 nan = r;
  nan[1][2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ShRotation(nan, 4), std::invalid_argument);
  glm::dmat3 inf = r;
  inf[0][0] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ShRotation(inf, 4), std::invalid_argument);
  EXPECT_THROW(ShRotation(r, -1), std::invalid_argument);
  EXPECT_THROW(ShRotation(r, 65), std::invalid_argument);
  EXPECT_NO_THROW(ShRotation(r, 64));
  // Defects far below the 1e-5 tolerance are accepted.
  glm::dmat3 nearly = r;
  nearly[0][1] += 1e-12;
  EXPECT_NO_THROW(ShRotation(nearly, 4));
}

TEST(ShRotation, ReflectionsAreNamedAndFloat32RotationsAccepted) {
  std::mt19937_64 rng(32);
  const glm::dmat3 r = random_rotation(rng);
  try {
    ShRotation(-r, 2);
    FAIL() << "a reflection accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("a reflection (det = -1), not a rotation"), std::string::npos) << e.what();
  }
  try {
    glm::dmat3 scaled = r;
    scaled[1] *= 1.001;
    ShRotation(scaled, 2);
    FAIL() << "a scaled matrix accepted";
  } catch (const std::invalid_argument& e) {
    // %g, not std::to_string's "0.000000" or "0.002001".
    EXPECT_NE(std::string(e.what()).find("= 0.002001, tolerance 1e-05"), std::string::npos) << e.what();
  }
  // R rounded to float32 (defect ~1e-7): accepted, and D(R) is as orthogonal and as close to
  // D(R) of the exact rotation as the rounding allows.
  const glm::dmat3 rounded = glm::dmat3(glm::mat3(r));
  const int order = 16;
  const ShRotation exact(r, order), from_float(rounded, order);
  for (int l = 0; l <= order; ++l) {
    EXPECT_LT(band_orthogonality_defect(from_float, l), kExact) << "l=" << l;
    const int size = 2 * l + 1;
    for (int q = 0; q < size * size; ++q) {
      ASSERT_NEAR(from_float.band(l)[q], exact.band(l)[q], 1e-6 * (l + 1)) << "l=" << l;
    }
  }
}

}  // namespace
}  // namespace sd
