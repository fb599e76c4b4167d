#include "shading_test_support.h"
#include "sdlighting/zonal_design.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <vector>

namespace sd {
namespace {

constexpr double kEqualFormulas = 1e-9;  // relative: two exact formulas of the same quantity

using test::expect_relative_equal;
using test::inputs;
using test::random_scene;
using test::Scene;

const Material kMaterials[] = {Material::lambert(), Material::phong(8.0), Material::phong(32.0)};

TEST(Shading, MsdTheorem21EqualsGauntPrt) {  // (12) = (10)
  for (int s : {2, 4}) {
    const Scene scene = random_scene(300, s, 2, 1);
    for (const Material& material : kMaterials) {
      const ShadingInputs in = inputs(scene, material);
      const SphericalDesign design = zonal_design(ZonalWeight::from_lobe(material.lobe()), s + 2);
      std::vector<double> msd(3 * scene.count), prt(3 * scene.count);
      shade_msd_lobe(in, 2, scene.visibility.data(), design, msd.data());
      shade_prt_gaunt(in, 2, scene.visibility.data(), prt.data());
      expect_relative_equal(msd, prt, kEqualFormulas);
    }
  }
}

TEST(Shading, MsdTheorem22EqualsProductMatrixPrt) {  // (13) = (8)-(9)
  const int s = 4, s_v = 2, rays = 400;
  const Scene scene = random_scene(40, s, s_v, 2);
  const test::RayVisibility rays_v = test::random_ray_visibility(scene.count, s, s_v, rays, 3);
  for (const Material& material : kMaterials) {
    const ShadingInputs in = inputs(scene, material);
    std::vector<double> msd(3 * scene.count), prt(3 * scene.count);
    shade_msd_visibility(in, s_v, rays_v.designs(), msd.data());
    shade_prt_matrix(in, s_v, rays_v.matrices.data(), prt.data());
    expect_relative_equal(msd, prt, kEqualFormulas);
  }
}

TEST(Shading, UnshadowedEqualsTheLobeIntegralOfTheBandLimitedLight) {
  // ∫ L̃(x) w(a·x) dμ by a zonal Gauss rule of high degree around a: an independent path to Funk–Hecke.
  const Scene scene = random_scene(20, 4, 0, 4);
  for (const Material& material : kMaterials) {
    const ShadingInputs in = inputs(scene, material);
    std::vector<double> fast(3 * scene.count);
    shade_unshadowed(in, fast.data());
    const SphericalDesign rule = zonal_design(ZonalWeight::from_lobe(material.lobe()), 8, DesignMethod::Gauss);
    std::vector<double> y(sh_count(4));
    for (size_t p = 0; p < scene.count; ++p) {
      double axis[3];
      lobe_axis(material, &scene.normals[3 * p], &scene.views[3 * p], axis);
      const glm::dvec3 a(axis[0], axis[1], axis[2]);
      const glm::dvec3 helper = std::abs(a.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
      const glm::dvec3 t1 = glm::normalize(glm::cross(helper, a)), t2 = glm::cross(a, t1);
      double expected[3] = {0, 0, 0};
      for (int nu = 0; nu < rule.size(); ++nu) {
        const glm::dvec3& x = rule.nodes[nu];
        sh_basis(4, x.x * t1 + x.y * t2 + x.z * a, y.data());
        for (int i = 0; i < sh_count(4); ++i)
          for (int c = 0; c < 3; ++c) expected[c] += rule.weights[nu] * scene.light[3 * i + c] * y[i];
      }
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(fast[3 * p + c], expected[c], 1e-11 * (1.0 + std::abs(expected[c])));
    }
  }
}

TEST(Shading, UnoccludedTransferReducesToUnshadowed) {
  // With V = 1: T = ŵ_l y_lm(n) for (2), M = identity for (8)-(9), AO = 1.
  const Scene scene = random_scene(50, 4, 4, 5);
  const int k = sh_count(4);
  std::vector<double> transfer(scene.count * k), identity(scene.count * k * k, 0.0), ao(scene.count, 1.0);
  const auto w = ZonalLobe::lambert().coefficients(4);
  std::vector<double> y(k);
  for (size_t p = 0; p < scene.count; ++p) {
    sh_basis(4, glm::dvec3(scene.normals[3 * p], scene.normals[3 * p + 1], scene.normals[3 * p + 2]), y.data());
    for (int l = 0; l <= 4; ++l)
      for (int m = -l; m <= l; ++m) transfer[p * k + sh_index(l, m)] = w[l] * y[sh_index(l, m)];
    for (int i = 0; i < k; ++i) identity[p * k * k + i * k + i] = 1.0;
  }
  const ShadingInputs in = inputs(scene, Material::lambert());
  std::vector<double> unshadowed(3 * scene.count), other(3 * scene.count);
  shade_unshadowed(in, unshadowed.data());
  shade_prt_diffuse(in, transfer.data(), other.data());
  expect_relative_equal(other, unshadowed, 1e-12);
  shade_prt_matrix(in, 4, identity.data(), other.data());
  expect_relative_equal(other, unshadowed, 1e-12);
  shade_ambient_occlusion(in, ao.data(), other.data());
  expect_relative_equal(other, unshadowed, 1e-12);
}

TEST(Shading, RejectsBadInput) {
  const Scene scene = random_scene(4, 2, 2, 6);
  std::vector<double> out(12);
  ShadingInputs in = inputs(scene, Material::lambert());
  in.light_order = 17;
  EXPECT_THROW(shade_unshadowed(in, out.data()), std::invalid_argument);
  in = inputs(scene, Material::phong(8.0));
  EXPECT_THROW(shade_prt_diffuse(in, scene.visibility.data(), out.data()), std::invalid_argument);
  const SphericalDesign low = zonal_design(ZonalWeight::from_lobe(ZonalLobe::phong(8.0)), 2);
  EXPECT_THROW(shade_msd_lobe(in, 2, scene.visibility.data(), low, out.data()), std::invalid_argument);
  in.view_dirs = nullptr;
  EXPECT_THROW(shade_unshadowed(in, out.data()), std::invalid_argument);
  EXPECT_THROW(Material::from_name("ward", 1.0), std::invalid_argument);
  EXPECT_THROW(Material::from_name("phong", -2.0), std::invalid_argument);
}

}  // namespace
}  // namespace sd
