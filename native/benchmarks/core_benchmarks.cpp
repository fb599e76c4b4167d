// Per-call times of the core: SH evaluation, SH rotation, Gaunt tables and design construction
// (lobe designs searched from scratch and continued from a neighbouring exponent).
#include "sdlighting/gaunt.h"
#include "sdlighting/sh_rotation.h"
#include "sdlighting/spherical_harmonics.h"
#include "sdlighting/weighted_design.h"
#include "sdlighting/zonal_design.h"

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <random>
#include <vector>

namespace {

std::vector<glm::dvec3> random_directions(int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<glm::dvec3> dirs(count);
  for (auto& d : dirs) d = glm::normalize(glm::dvec3(normal(rng), normal(rng), normal(rng)));
  return dirs;
}

glm::dmat3 some_rotation() {
  return glm::dmat3(glm::rotate(glm::dmat4(1.0), 0.7, glm::normalize(glm::dvec3(1.0, 2.0, 3.0))));
}

void BM_ShBasis(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const auto dirs = random_directions(1024, 1);
  std::vector<double> out(sd::sh_count(order));
  size_t i = 0;
  for (auto _ : state) {
    sd::sh_basis(order, dirs[i++ & 1023], out.data());
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_ShBasis)->Arg(8)->Arg(16)->Arg(32);

void BM_ShRotationBuild(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const glm::dmat3 r = some_rotation();
  for (auto _ : state) {
    sd::ShRotation rotation(r, order);
    benchmark::DoNotOptimize(rotation.band(order));
  }
}
BENCHMARK(BM_ShRotationBuild)->Arg(4)->Arg(8)->Arg(16);

// What a frame costs: build D(g) and rotate an RGB environment.
void BM_ShRotateEnvironmentRgb(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const glm::dmat3 r = some_rotation();
  std::vector<double> in(3 * sd::sh_count(order), 0.5), out(in.size());
  for (auto _ : state) {
    sd::ShRotation rotation(r, order);
    rotation.apply(in.data(), out.data(), 3);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_ShRotateEnvironmentRgb)->Arg(4)->Arg(8)->Arg(16);

void BM_Gaunt(benchmark::State& state) {
  const int s = static_cast<int>(state.range(0)), s_prime = static_cast<int>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(sd::gaunt_coefficients(s, s_prime, s + s_prime));
}
BENCHMARK(BM_Gaunt)->Args({4, 2})->Args({8, 4})->Unit(benchmark::kMillisecond);

void BM_ZonalDesign(benchmark::State& state) {
  const int degree = static_cast<int>(state.range(0));
  const sd::ZonalWeight weight = sd::ZonalWeight::from_lobe(sd::ZonalLobe::phong(static_cast<double>(state.range(1))));
  for (auto _ : state) benchmark::DoNotOptimize(sd::zonal_design(weight, degree, sd::DesignMethod::Auto));
}
BENCHMARK(BM_ZonalDesign)->Args({4, 8})->Args({6, 8})->Args({8, 32})->Args({10, 8})->Unit(benchmark::kMillisecond);

// One step of the add-on's continuation in σ (σ + 1 times 1.25), against BM_ZonalDesign's search.
void BM_ZonalDesignContinued(benchmark::State& state) {
  const int degree = static_cast<int>(state.range(0));
  const double sigma = static_cast<double>(state.range(1));
  const sd::ZonalWeight from = sd::ZonalWeight::from_lobe(sd::ZonalLobe::phong(sigma));
  const sd::ZonalWeight to = sd::ZonalWeight::from_lobe(sd::ZonalLobe::phong(1.25 * (sigma + 1.0) - 1.0));
  const sd::SphericalDesign start = sd::zonal_design(from, degree);
  for (auto _ : state) benchmark::DoNotOptimize(sd::zonal_design_continued(to, degree, from, start));
}
BENCHMARK(BM_ZonalDesignContinued)->Args({6, 8})->Args({8, 32})->Args({10, 8})->Unit(benchmark::kMillisecond);

// A visibility-like measure: 1024 ray directions of which the upper hemisphere's escape.
void BM_WeightedDesign(benchmark::State& state) {
  const int degree = static_cast<int>(state.range(0));
  std::vector<glm::dvec3> dirs;
  for (const auto& d : random_directions(1024, 2))
    if (d.z > 0.0) dirs.push_back(d);
  const std::vector<double> weights(dirs.size(), 1.0 / 1024.0);
  for (auto _ : state) benchmark::DoNotOptimize(sd::weighted_design(dirs, weights, degree));
}
BENCHMARK(BM_WeightedDesign)->Arg(4)->Arg(6)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
