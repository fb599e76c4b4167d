// Prints the lobe designs the library builds: for each lobe and degree, the nodes found by
// gradient projection next to the lower bound (⌊k/2⌋+1)² and the Gauss product count, with the
// certified residuals and build times.
#include "sdlighting/zonal_design.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  using Clock = std::chrono::steady_clock;
  const int max_degree = argc > 1 ? std::stoi(argv[1]) : 12;
  struct Row {
    std::string name;
    sd::ZonalLobe lobe;
  };
  const std::vector<Row> lobes = {{"lambert", sd::ZonalLobe::lambert()},   {"phong 1", sd::ZonalLobe::phong(1)},
                                  {"phong 8", sd::ZonalLobe::phong(8)},     {"phong 32", sd::ZonalLobe::phong(32)},
                                  {"phong 128", sd::ZonalLobe::phong(128)}, {"phong 1000", sd::ZonalLobe::phong(1000)}};
  std::printf("%-11s %6s %6s %9s %6s %10s %9s %10s %10s %9s %7s\n", "lobe", "degree", "bound", "gradient", "gauss",
              "grad/bound", "grad res", "gauss res", "grad ms", "gauss ms", "min t");
  for (const Row& row : lobes) {
    const sd::ZonalWeight weight = sd::ZonalWeight::from_lobe(row.lobe);
    for (int degree = 2; degree <= max_degree; ++degree) {
      auto t0 = Clock::now();
      const sd::SphericalDesign gauss = sd::zonal_design(weight, degree, sd::DesignMethod::Gauss);
      auto t1 = Clock::now();
      const sd::SphericalDesign gradient = sd::zonal_design(weight, degree, sd::DesignMethod::Gradient);
      auto t2 = Clock::now();
      const int bound = sd::design_lower_bound(degree);
      const double ms_gauss = std::chrono::duration<double, std::milli>(t1 - t0).count();
      const double ms_grad = std::chrono::duration<double, std::milli>(t2 - t1).count();
      double min_t = 1.0;
      for (const auto& x : gradient.nodes) min_t = std::min(min_t, x.z);
      std::printf("%-11s %6d %6d %9d %6d %10.2f %9.1e %10.1e %10.1f %9.2f %7.3f\n", row.name.c_str(), degree, bound,
                  gradient.size(), gauss.size(), double(gradient.size()) / bound, gradient.residual, gauss.residual,
                  ms_grad, ms_gauss, min_t);
      std::fflush(stdout);
    }
  }
  return 0;
}
