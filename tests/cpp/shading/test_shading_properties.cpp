// Randomized shading identities (issue 12, item 8): on random light, normals, views, Ṽ and
// ray-sampled visibility of random orders s <= 4, s' <= 2, random non-integer Phong exponents and
// a random environment rotation, MSD (12) equals PRT (10) and MSD (13) equals PRT (8)-(9) to 1e-9
// relative — the seed's Theorems 2.1 and 2.2. Fixed seeds; each case's seed in the failure message.
#include "sdlighting/sh_rotation.h"
#include "sdlighting/zonal_design.h"
#include "shading_test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace sd {
namespace {

constexpr double kEqualFormulas = 1e-9;  // relative: two exact formulas of the same quantity
constexpr int kCases = 12;

// Orders, material and environment rotation of case `seed`; scene.light becomes L(g x)'s.
struct Case {
  test::Scene scene;
  Material material;
};

Case random_case(unsigned seed, int max_vertices) {
  std::mt19937_64 rng(seed);
  const int s = static_cast<int>(rng() % 5), s_v = static_cast<int>(rng() % 3);
  const size_t count = 5 + rng() % max_vertices;
  // Lambert, or Phong with σ log-uniform in [0.1, 1000] (not an integer in practice).
  const Material material =
      rng() % 4 == 0 ? Material::lambert() : Material::phong(std::pow(10.0, std::uniform_real_distribution<>(-1, 3)(rng)));
  Case c{test::random_scene(count, s, s_v, static_cast<unsigned>(rng())), material};
  c.scene.light = rotated_sh(c.scene.light, s, test::random_rotation(rng));
  return c;
}

std::string describe(const Case& c) {
  return " s=" + std::to_string(c.scene.s) + " s'=" + std::to_string(c.scene.s_v) + " vertices=" +
         std::to_string(c.scene.count) + (c.material.glossy ? " phong " + std::to_string(c.material.exponent) : " lambert");
}

TEST(ShadingProperties, MsdTheorem21EqualsGauntPrtOnRandomScenes) {  // (12) = (10)
  for (unsigned seed = 0; seed < kCases; ++seed) {
    const Case c = random_case(seed, 60);
    SCOPED_TRACE("seed " + std::to_string(seed) + describe(c));
    const test::Scene& scene = c.scene;
    const ShadingInputs in = test::inputs(scene, c.material);
    const SphericalDesign design = zonal_design(ZonalWeight::from_lobe(c.material.lobe()), scene.s + scene.s_v);
    std::vector<double> msd(3 * scene.count), prt(3 * scene.count);
    shade_msd_lobe(in, scene.s_v, scene.visibility.data(), design, msd.data());
    shade_prt_gaunt(in, scene.s_v, scene.visibility.data(), prt.data());
    test::expect_relative_equal(msd, prt, kEqualFormulas);
  }
}

TEST(ShadingProperties, MsdTheorem22EqualsProductMatrixPrtOnRandomScenes) {  // (13) = (8)-(9)
  for (unsigned seed = 0; seed < kCases; ++seed) {
    const Case c = random_case(100 + seed, 25);
    SCOPED_TRACE("seed " + std::to_string(100 + seed) + describe(c));
    const test::Scene& scene = c.scene;
    const int rays = 100 + static_cast<int>(seed * 37 % 300);
    const test::RayVisibility visibility = test::random_ray_visibility(scene.count, scene.s, scene.s_v, rays, seed);
    const ShadingInputs in = test::inputs(scene, c.material);
    std::vector<double> msd(3 * scene.count), prt(3 * scene.count);
    shade_msd_visibility(in, scene.s_v, visibility.designs(), msd.data());
    shade_prt_matrix(in, scene.s_v, visibility.matrices.data(), prt.data());
    test::expect_relative_equal(msd, prt, kEqualFormulas);
  }
}

}  // namespace
}  // namespace sd
