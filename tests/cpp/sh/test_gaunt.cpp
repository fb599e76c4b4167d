#include "sdlighting/gaunt.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdtesting/sphere.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <tuple>

namespace sd {
namespace {

constexpr double kExact = 1e-12;

using Triple = std::tuple<int, int, int>;
using test::product_rule;
using test::random_direction;
using test::SphereRule;

std::map<Triple, double> as_map(const std::vector<GauntEntry>& entries) {
  std::map<Triple, double> map;
  for (const GauntEntry& e : entries) map[{e.a, e.b, e.c}] = e.value;
  return map;
}

double lookup(const std::map<Triple, double>& map, int a, int b, int c) {
  const auto it = map.find({a, b, c});
  return it == map.end() ? 0.0 : it->second;
}

// Brute force, independent of the library's factorised rule: a full two-dimensional product
// rule (Gauss–Legendre in z × equispaced φ) of more than enough degree, summing sh_basis values.
// Its azimuths start 0.3 of a spacing from φ = 0.
constexpr double kBrutePhiOffset = 0.3;

TEST(Gaunt, ClosedFormValues) {
  const auto g = as_map(gaunt_coefficients(2, 2, 2));
  // y_10 = √3 z, y_11 = √3 x, y_1,-1 = √3 y; moments <z²> = 1/3, <z⁴> = 1/5, <x²z²> = 1/15.
  EXPECT_NEAR(lookup(g, sh_index(1, 0), sh_index(1, 0), sh_index(2, 0)), 2.0 / std::sqrt(5.0), kExact);
  EXPECT_NEAR(lookup(g, sh_index(1, 1), sh_index(1, 1), sh_index(2, 0)), -1.0 / std::sqrt(5.0), kExact);
  EXPECT_NEAR(lookup(g, sh_index(1, -1), sh_index(1, 1), sh_index(2, -2)), std::sqrt(15.0) / 5.0,
              kExact);
  EXPECT_NEAR(lookup(g, sh_index(1, 0), sh_index(1, 1), sh_index(2, 1)), std::sqrt(15.0) / 5.0, kExact);
  // Parity and the m rule forbid these.
  EXPECT_EQ(lookup(g, sh_index(1, 0), sh_index(1, 0), sh_index(1, 0)), 0.0);
  EXPECT_EQ(lookup(g, sh_index(1, 1), sh_index(1, -1), sh_index(2, 2)), 0.0);
}

TEST(Gaunt, ConstantHarmonicGivesOrthonormality) {
  const int oa = 3, ob = 6, oc = 5;
  const auto entries = gaunt_coefficients(oa, ob, oc);
  const auto g = as_map(entries);
  for (int b = 0; b < sh_count(ob); ++b)
    for (int c = 0; c < sh_count(oc); ++c) EXPECT_NEAR(lookup(g, 0, b, c), b == c, kExact);
  for (int a = 0; a < sh_count(oa); ++a)
    for (int c = 0; c < sh_count(oc); ++c) EXPECT_NEAR(lookup(g, a, 0, c), a == c, kExact);
}

TEST(Gaunt, SymmetricUnderPermutations) {
  const int order = 6;
  const auto g = as_map(gaunt_coefficients(order, order, order));
  for (const auto& [key, value] : g) {
    const auto [a, b, c] = key;
    for (const Triple& p : {Triple{a, c, b}, Triple{b, a, c}, Triple{b, c, a}, Triple{c, a, b},
                            Triple{c, b, a}}) {
      EXPECT_NEAR(lookup(g, std::get<0>(p), std::get<1>(p), std::get<2>(p)), value, kExact);
    }
  }
}

TEST(Gaunt, SortedUniqueAndWithinOrders) {
  const int oa = 4, ob = 3, oc = 5;
  const auto entries = gaunt_coefficients(oa, ob, oc);
  ASSERT_FALSE(entries.empty());
  for (size_t i = 0; i < entries.size(); ++i) {
    const GauntEntry& e = entries[i];
    EXPECT_LT(e.a, sh_count(oa));
    EXPECT_LT(e.b, sh_count(ob));
    EXPECT_LT(e.c, sh_count(oc));
    EXPECT_GT(std::abs(e.value), 1e-13);
    if (i > 0) {
      const GauntEntry& p = entries[i - 1];
      EXPECT_LT(std::tie(p.a, p.b, p.c), std::tie(e.a, e.b, e.c));
    }
  }
}

// With order_c >= order_a + order_b the expansion of a product is complete.
TEST(Gaunt, ExpandsProductsExactly) {
  const int oa = 6, ob = 5, oc = 11;
  const auto entries = gaunt_coefficients(oa, ob, oc);
  std::mt19937_64 rng(13);
  const int ka = sh_count(oa), kb = sh_count(ob);
  for (int trial = 0; trial < 10; ++trial) {
    const glm::dvec3 x = random_direction(rng);
    const std::vector<double> y = sh_basis(oc, x);
    std::vector<double> expansion(size_t(ka) * kb, 0.0);
    for (const GauntEntry& e : entries) expansion[size_t(e.a) * kb + e.b] += e.value * y[e.c];
    for (int a = 0; a < ka; ++a)
      for (int b = 0; b < kb; ++b)
        EXPECT_NEAR(expansion[size_t(a) * kb + b], y[a] * y[b], kExact) << a << "," << b;
  }
}

TEST(Gaunt, MatchesBruteForceIntegralIncludingZeros) {
  const int oa = 3, ob = 4, oc = 6;
  const auto g = as_map(gaunt_coefficients(oa, ob, oc));
  // Degree 3 + 4 + 6 = 13 suffices; 30 makes the rule unrelated to the library's.
  const SphereRule rule = product_rule(30, kBrutePhiOffset);
  const int ka = sh_count(oa), kb = sh_count(ob), kc = sh_count(oc);
  std::vector<double> brute(size_t(ka) * kb * kc, 0.0);
  for (size_t q = 0; q < rule.dirs.size(); ++q) {
    const std::vector<double> y = sh_basis(oc, rule.dirs[q]);
    for (int a = 0; a < ka; ++a)
      for (int b = 0; b < kb; ++b) {
        const double wab = rule.weights[q] * y[a] * y[b];
        for (int c = 0; c < kc; ++c) brute[(size_t(a) * kb + b) * kc + c] += wab * y[c];
      }
  }
  for (int a = 0; a < ka; ++a)
    for (int b = 0; b < kb; ++b)
      for (int c = 0; c < kc; ++c)
        EXPECT_NEAR(lookup(g, a, b, c), brute[(size_t(a) * kb + b) * kc + c], kExact)
            << a << "," << b << "," << c;
}

TEST(Gaunt, HighOrderValuesMatchBruteForce) {
  const auto g = as_map(gaunt_coefficients(16, 8, 24));
  const SphereRule rule = product_rule(60, kBrutePhiOffset);
  const Triple probes[] = {
      {sh_index(16, 16), sh_index(8, -8), sh_index(24, -24)},
      {sh_index(16, -5), sh_index(8, 3), sh_index(20, -2)},
      {sh_index(12, 7), sh_index(7, -4), sh_index(11, -3)},
      {sh_index(16, 0), sh_index(8, 0), sh_index(10, 0)},
      {sh_index(15, -9), sh_index(6, -6), sh_index(19, 15)},
  };
  for (const Triple& t : probes) {
    const auto [a, b, c] = t;
    double brute = 0.0;
    for (size_t q = 0; q < rule.dirs.size(); ++q) {
      const std::vector<double> y = sh_basis(24, rule.dirs[q]);
      brute += rule.weights[q] * y[a] * y[b] * y[c];
    }
    EXPECT_GT(std::abs(brute), 1e-3) << "probe should be a non-trivial coefficient";
    EXPECT_NEAR(lookup(g, a, b, c), brute, kExact) << a << "," << b << "," << c;
  }
}

TEST(Gaunt, OrderZero) {
  const auto entries = gaunt_coefficients(0, 0, 0);
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_NEAR(entries[0].value, 1.0, kExact);
  EXPECT_TRUE(gaunt_coefficients(2, 0, 1).size() == 4u);  // only y_a · 1 · y_a for l_a <= 1
}

TEST(Gaunt, RejectsNegativeOrders) {
  EXPECT_THROW(gaunt_coefficients(-1, 2, 2), std::invalid_argument);
  EXPECT_THROW(gaunt_coefficients(2, -1, 2), std::invalid_argument);
  EXPECT_THROW(gaunt_coefficients(2, 2, -1), std::invalid_argument);
}

}  // namespace
}  // namespace sd
