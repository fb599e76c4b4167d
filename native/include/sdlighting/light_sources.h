// Bright compact sources of an environment map (issue 29): a sun, a lamp or a softbox that SH
// truncation blurs, taken out of the map so that they can be shaded and shadowed on their own; the
// rest of the map (the remainder) goes to SH as before.
//
// What is taken out is measured, not set: inside a source the map is clipped to a luminance
// threshold t (its colour kept), so source + remainder = the map texel by texel and the remainder
// is never negative. The threshold is chosen by the seed's low-frequency measure ε(s) (the
// condition before Theorem 1.1: |B − B̄| <= ε ‖L‖ ‖ρ̂‖; environment_error.h): the remainder's
// energy above order s, relative to the whole map's norm, ‖P_{>s} R_t‖ / ‖L‖ on luminance. Of the
// thresholds down a ladder of √2 steps, the highest whose remainder comes within
// kSourceErrorSlack of the least ε any of them reaches with sources no wider than
// kMaxSourceExtent; none when the sources would not take half the map's energy above the order
// (ε² halved: its high-frequency light is not in a few compact places, a noisy sky).
#pragma once

#include "sdlighting/environment.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace sd {

/// The widest source taken out (radians, from its direction to its farthest texel centre): a sun
/// with its glow, a lamp, a studio softbox; wider bright regions (a bright sky) stay in the map.
constexpr double kMaxSourceExtent = 0.1745;   // 10 degrees
/// The least share of the map's luminance mass a source carries (fainter ones cast no shadow worth
/// their cost and stay in the map).
constexpr double kMinSourceShare = 0.01;
/// A threshold is taken when its remainder's ε is within this factor of the least one.
constexpr double kSourceErrorSlack = 1.25;

/// One source: the light the map holds above the threshold over a connected set of texels.
struct LightSource {
  glm::dvec3 direction{0.0, 0.0, 1.0};   ///< unit: the mean direction, weighted by the luminance taken out
  glm::dvec3 major_axis{1.0, 0.0, 0.0};  ///< unit, ⊥ direction: the axis it extends along most
  /// Semi-axes (radians) of the uniform ellipse with its second moments about `direction`
  /// (each texel counted with its own size): a disc of radius ρ gives ρ and ρ.
  double major_radius = 0.0, minor_radius = 0.0;
  double extent = 0.0;        ///< radians from direction to its farthest texel centre
  double solid_angle = 0.0;   ///< Σ Δμ of its texels, in units of dμ (the sphere: 1)
  glm::dvec3 power{0.0};      ///< ∫ (L − remainder) dμ over it per channel (units of Environment::mass)
  int64_t texels = 0;
};

/// The sources of a map and what remains of it.
struct SourceSplit {
  std::vector<LightSource> sources;   ///< brightest first (luminance power); at most max_sources
  Environment remainder;              ///< the map with each source's texels clipped to `threshold`
  double threshold = 0.0;             ///< the luminance clipped to (0: no source)
  double error_before = 0.0;          ///< ‖P_{>s} L‖ / ‖L‖ (luminance): the map's ε(s)
  double error_after = 0.0;           ///< ‖P_{>s} R‖ / ‖L‖: what the remainder leaves above order s
};

/// Finds up to `max_sources` compact bright sources of an equirect map for shading at SH order
/// `order` (see the file comment) and splits them off: sources + remainder = the map, texel by
/// texel (masses to rounding). Texels are connected to their eight neighbours, across the seam and
/// across each pole. The SH projections run on every hardware thread. Throws std::invalid_argument for a cube map,
/// order outside [0, 32] or max_sources outside [1, 16].
SourceSplit extract_light_sources(const Environment& environment, int order = 8, int max_sources = 4);

}  // namespace sd
