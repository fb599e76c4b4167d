"""Upper limits of the panel's settings, from the native module's exported constants (each limit
is stated once, in sdnative). Without sdnative the settings have no upper limits: nothing can be
baked or shaded then, and the panel says why.
"""

from dataclasses import dataclass
from typing import Optional

# The panel's own cap on rays per vertex, below sdnative's: a bake thread holds the SH basis at its
# escaping rays, rays x (s+1)^2 doubles (65536 rays at s = 16: 150 MB; sdnative's 2^24: 38 GB).
PANEL_MAX_RAYS = 65536


@dataclass(frozen=True)
class Limits:
    light_order: Optional[int] = None       # s, for every method (None: unknown)
    visibility_order: Optional[int] = None  # s'
    rays: Optional[int] = None              # rays per vertex
    phong_exponent: Optional[float] = None  # sigma


def from_module(sdnative):
    """The limits of an sdnative module (None: no limits). Any s and s' within them can be baked
    and shaded by every method: s by the shader, the transfer bake and the environment's
    projection; s + s' as the degree of a design."""
    if sdnative is None:
        return Limits()
    visibility = int(sdnative.MAX_VISIBILITY_ORDER)
    light = min(int(sdnative.MAX_SHADING_ORDER), int(sdnative.MAX_TRANSFER_ORDER),
                int(sdnative.MAX_PROJECTION_ORDER), int(sdnative.MAX_DESIGN_DEGREE) - visibility)
    return Limits(light, visibility, min(int(sdnative.MAX_RAYS_PER_VERTEX), PANEL_MAX_RAYS),
                  float(sdnative.MAX_PHONG_EXPONENT))


def maximum(value):
    """A bpy property's keywords for an upper limit that may be unknown."""
    return {} if value is None else {"max": value}
