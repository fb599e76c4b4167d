// Bindings of the bright sources split off a map (sdlighting/light_sources.h):
// Environment.light_sources.
//
// Errors: a cube map, an order or a source count out of range raise ValueError. The search runs
// without the GIL.
#include "bindings.h"
#include "environment_class.h"
#include "sdlighting/light_sources.h"

#include <pybind11/pybind11.h>

#include <optional>

namespace sdpy {
namespace {

py::tuple vec3(const glm::dvec3& v) { return py::make_tuple(v.x, v.y, v.z); }

}  // namespace

void bind_light_sources(py::module_& m) {
  py::class_<sd::Environment> env = environment_class(m);
  env.def(
      "light_sources",
      [](const sd::Environment& e, int order, int max_sources) {
        std::optional<sd::SourceSplit> split;
        {
          py::gil_scoped_release release;
          split.emplace(sd::extract_light_sources(e, order, max_sources));
        }
        py::list sources;
        for (const sd::LightSource& s : split->sources) {
          py::dict d;
          d["direction"] = vec3(s.direction);
          d["major_axis"] = vec3(s.major_axis);
          d["major_radius"] = s.major_radius;
          d["minor_radius"] = s.minor_radius;
          d["extent"] = s.extent;
          d["solid_angle"] = s.solid_angle;
          d["power"] = vec3(s.power);
          d["texels"] = s.texels;
          sources.append(d);
        }
        py::dict out;
        out["sources"] = sources;
        out["remainder"] = split->remainder;
        out["threshold"] = split->threshold;
        out["error_before"] = split->error_before;
        out["error_after"] = split->error_after;
        return out;
      },
      py::arg("order") = 8, py::arg("max_sources") = 4,
      R"doc(The map's compact bright sources (a sun, lamps, softboxes) split off for shading at SH
order `order` (light_sources.h: the threshold chosen by the remainder's energy above that order):
{"sources": [{"direction", "major_axis" (unit 3-tuples), "major_radius", "minor_radius" (radians:
the equivalent ellipse), "extent" (radians to its farthest texel), "solid_angle" (units of dmu: the
sphere is 1), "power" (RGB, units of mass()), "texels"}, ...] brightest first, "remainder" (an
Environment: the map clipped to "threshold" inside the sources; sources + remainder = the map),
"threshold" (0: none), "error_before", "error_after" (||P_{>s} L|| / ||L|| of the map and of the
remainder, luminance)}. ValueError for a cube map, order outside [0, 32], max_sources outside
[1, 16].)doc");
}

}  // namespace sdpy
