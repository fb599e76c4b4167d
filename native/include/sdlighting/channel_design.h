// Weighted spherical designs of an environment map's channels (environment.h): quadratures for
// the measure L_c dμ (the seed's comment 3 and Table 2; weighted_design.h builds them).
#pragma once

#include "sdlighting/environment.h"
#include "sdlighting/spherical_design.h"

namespace sd {

/// A weighted spherical design of `degree` (0..kMaxDesignDegree) for one channel (0..2 or
/// kLuminance) of the environment, i.e. for the measure L_c dμ (the seed's comment 3 and
/// Table 2): sd::weighted_design on an area-averaged copy of about 2000 texels (equirect
/// 64 × 32, cube face 18; the map itself when it is already that small), with nodes at texel
/// centres and weights L_c Δμ, so the design's moments are those of the copy: they match the
/// full map's L_lm up to the box filter's attenuation (about l(l+1)h²/24, h ≈ 0.1 rad: ~1 %
/// at l = 4). Certified to kDesignTolerance against the copy's moments. Throws
/// std::invalid_argument for a bad channel or degree or a black channel, std::runtime_error
/// if no design certifies.
SphericalDesign channel_design(const Environment& environment, int channel, int degree);

}  // namespace sd
