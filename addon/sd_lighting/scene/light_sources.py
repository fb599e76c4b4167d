"""The environment's bright compact sources as the panel names them (issue 29): a sun, lamps,
softboxes that sdnative's Environment.light_sources splits off the map (native light_sources.h
says how they are found). The live shading still lights them through SH with the rest of the
map, which blurs their shadows: the panel says so, with how much of the light they carry.

Nothing here needs Blender.
"""

import math

from .lobes import LUMINANCE


def found(split, mass):
    """[(width in degrees, elevation in degrees, share of the map's luminance)] of
    Environment.light_sources' dict `split`, brightest first; `mass`: the map's luminance mass."""
    out = []
    for source in split["sources"]:
        power = sum(w * p for w, p in zip(LUMINANCE, source["power"]))
        elevation = math.degrees(math.asin(max(-1.0, min(1.0, source["direction"][2]))))
        out.append((math.degrees(2.0 * source["major_radius"]), elevation, power / mass if mass > 0.0 else 0.0))
    return out


def lines(sources):
    """The panel's lines for found()'s list (None: still being found)."""
    if sources is None:
        return ["Finding the map's bright sources"]
    if not sources:
        return ["No sun or lamp in the map: its light is soft"]
    share = sum(s for _, _, s in sources)
    head = "%s: %.0f %% of the light; SH blurs their shadows" % (
        "1 bright source" if len(sources) == 1 else "%d bright sources" % len(sources), 100.0 * share)
    return [head] + ["%.1f\u00b0 wide at %.0f\u00b0 elevation, %.0f %%" % (width, elevation, 100.0 * s)
                     for width, elevation, s in sources]
