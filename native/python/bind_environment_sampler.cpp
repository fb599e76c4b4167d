// Bindings of the importance sampler of environment maps (sdlighting/environment_sampler.h).
#include "array_checks.h"
#include "bindings.h"
#include "sdlighting/environment.h"
#include "sdlighting/environment_sampler.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <glm/vec3.hpp>

#include <vector>

namespace sdpy {

void bind_environment_sampler(py::module_& m) {
  py::class_<sd::EnvironmentSampler>(m, "EnvironmentSampler", R"doc(Importance sampling of an Environment for
Monte Carlo reference integrals: a texel is chosen with probability 0.99 Y dmu / sum(Y dmu) +
0.01 dmu (luminance times solid angle with a 1 % uniform floor, so every direction has a positive
density), then a point uniformly inside it (uniform in phi and cos(theta) in an equirect texel,
uniform in face coordinates in a cube texel). Densities are with respect to dmu = dx/(4 pi):
mean(f(x) / pdf(x)) estimates integral f dmu.)doc")
      .def(py::init([](const sd::Environment& e) {
             py::gil_scoped_release release;
             return sd::EnvironmentSampler(e);
           }),
           py::arg("environment"))
      .def(
          "sample",
          [](const sd::EnvironmentSampler& s, const DoubleArray& u) {
            if (u.ndim() != 2 || u.shape(1) != 2) value_error("u must have shape (N, 2), got " + shape_string(u));
            const py::ssize_t n = u.shape(0);
            check_finite("u", u.data(), static_cast<size_t>(2 * n));
            py::array_t<double> dirs({n, py::ssize_t(3)}), pdf(n);
            const double* in = u.data();
            double* d = dirs.mutable_data();
            double* p = pdf.mutable_data();
            {
              py::gil_scoped_release release;
              for (py::ssize_t i = 0; i < n; ++i) {
                const glm::dvec3 dir = s.sample(in[2 * i], in[2 * i + 1], p + i);
                d[3 * i] = dir.x, d[3 * i + 1] = dir.y, d[3 * i + 2] = dir.z;
              }
            }
            return py::make_tuple(std::move(dirs), std::move(pdf));
          },
          py::arg("u"),
          "Maps uniform numbers u of shape (N, 2) in [0, 1) to (dirs (N, 3), pdf (N,)), pdf w.r.t. dmu.")
      .def(
          "pdf",
          [](const sd::EnvironmentSampler& s, const DoubleArray& dirs) {
            const std::vector<glm::dvec3> d = read_directions("dirs", dirs, false);
            py::array_t<double> out(static_cast<py::ssize_t>(d.size()));
            for (size_t i = 0; i < d.size(); ++i) out.mutable_data()[i] = s.pdf(d[i]);
            return out;
          },
          py::arg("dirs"), "The density w.r.t. dmu of sample() at directions of shape (N, 3); returns (N,).");
}

}  // namespace sdpy
