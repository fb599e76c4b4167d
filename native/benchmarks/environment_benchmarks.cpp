// Times of the environment-map precompute (sdlighting/sh_projection.h, environment_error.h,
// ringing.h): SH projection of a 2048 × 1024 equirect map at orders 4, 8 and 16 on 1 and 2
// threads, a 512 × 256 band-limited texture at order 8 (with the projection of the 2048 × 1024
// map, and from coefficients alone), the order-64 band energies of a 1024 × 512 map (Blender's
// HDRI size), and the sampler's tables. After the Google Benchmark table, prints the 1 → 2 thread
// speedup of the projection (median of 7 runs each).
#include "sdlighting/environment.h"
#include "sdlighting/environment_error.h"
#include "sdlighting/environment_sampler.h"
#include "sdlighting/ringing.h"
#include "sdlighting/sh_projection.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <thread>
#include <vector>

namespace {

const sd::Environment& test_map(int width, int height) {
  static std::vector<std::pair<std::pair<int, int>, sd::Environment>> cache;
  for (const auto& [size, env] : cache) {
    if (size.first == width && size.second == height) return env;
  }
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> uniform(0.0f, 2.0f);
  std::vector<float> rgb(static_cast<size_t>(width) * height * 3);
  for (float& v : rgb) v = uniform(rng);
  cache.push_back({{width, height}, sd::Environment::from_equirect_pixels(width, height, std::move(rgb))});
  return cache.back().second;
}

void BM_Projection2048x1024(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0)), threads = static_cast<int>(state.range(1));
  const sd::Environment& env = test_map(2048, 1024);
  for (auto _ : state) benchmark::DoNotOptimize(sd::sh(env, order, threads));
  state.SetLabel("order " + std::to_string(order) + ", " + std::to_string(threads) + " thread(s)");
}
BENCHMARK(BM_Projection2048x1024)
    ->Args({4, 1})->Args({4, 2})->Args({8, 1})->Args({8, 2})->Args({16, 1})->Args({16, 2})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BandLimited512x256(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const sd::Environment& env = test_map(2048, 1024);
  for (auto _ : state) {
    sd::BandLimitedReport report;
    benchmark::DoNotOptimize(sd::band_limited(env, order, 512, 256, sd::RingingWindow::Hanning, &report));
  }
}
BENCHMARK(BM_BandLimited512x256)->Arg(8)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BandLimitedTextureFromCoefficients512x256(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const std::vector<double> coefficients = sd::sh(test_map(2048, 1024), order);
  for (auto _ : state) {
    sd::BandLimitedReport report;
    benchmark::DoNotOptimize(sd::band_limited_texture(coefficients, order, 512, 256, sd::RingingWindow::Hanning, &report));
  }
}
BENCHMARK(BM_BandLimitedTextureFromCoefficients512x256)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BandEnergiesOrder64_1024x512(benchmark::State& state) {
  const sd::Environment& base = test_map(1024, 512);
  for (auto _ : state) {
    sd::Environment fresh = base.area_averaged(1024, 512);  // a copy with an empty energy cache
    benchmark::DoNotOptimize(sd::lobe_filtered_error(fresh, sd::ZonalLobe::phong(32.0), 4));
  }
}
BENCHMARK(BM_BandEnergiesOrder64_1024x512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SamplerTables2048x1024(benchmark::State& state) {
  const sd::Environment& env = test_map(2048, 1024);
  for (auto _ : state) benchmark::DoNotOptimize(sd::EnvironmentSampler(env));
}
BENCHMARK(BM_SamplerTables2048x1024)->Unit(benchmark::kMillisecond)->UseRealTime();

double median_seconds(const sd::Environment& env, int order, int threads) {
  std::vector<double> times;
  for (int k = 0; k < 7; ++k) {
    const auto start = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(sd::sh(env, order, threads));
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  const sd::Environment& env = test_map(2048, 1024);
  std::printf("\nSH projection of a 2048 x 1024 map, median of 7 (hardware threads: %u):\n",
              std::thread::hardware_concurrency());
  for (int order : {4, 8, 16}) {
    const double one = median_seconds(env, order, 1), two = median_seconds(env, order, 2);
    std::printf("  order %2d: 1 thread %7.1f ms, 2 threads %7.1f ms, speedup %.2fx\n", order, 1e3 * one, 1e3 * two,
                one / two);
  }
  return 0;
}
