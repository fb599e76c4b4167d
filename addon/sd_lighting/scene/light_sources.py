"""The environment's bright compact sources (issue 29): a sun, lamps, softboxes that sdnative's
Environment.light_sources splits off the map (native light_sources.h says how they are found), as
the panel names them and as the live shading lights them.

With Sharp Source Shadows on, a surface is lit by the remainder of the map through SH and by each
source on its own (diffuse light, and glossy light: a small one's highlight on its own, a wider
one's share of the prefiltered light), shadowed per pixel through a shadow map rendered from the
source's direction (live/source_shadows.py). The
maps are orthographic over the bounding sphere of what casts shadows; this module computes their
frames and the shader's rows of each source.

Nothing here needs Blender.
"""

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .lobes import LUMINANCE

SPLIT_ORDER = 8          # the SH order the sources are split off for (the panel's default order)
SHADOW_MAP_SIZE = 2048   # texels along each side of a source's shadow map
SOURCE_ROWS = 5          # vec4 rows per source in the shader's block (shadow_rows)
# The widest source (its ellipse's major semi-axis) whose glossy highlight is shaded on its own, from
# points of its own texels (a sun, a lamp): wider ones (softboxes, windows) stay in the prefiltered
# atlas, where a sharp lobe sees their own shape (msd-notes, "Bright sources").
HIGHLIGHT_RADIUS = math.radians(1.0)
HIGHLIGHT_POINTS = 16    # the directions a highlight is shaded at (with_highlight_points)


def found(split, mass):
    """[(width in degrees, elevation in degrees, share of the map's luminance)] of
    Environment.light_sources' dict `split`, brightest first; `mass`: the map's luminance mass."""
    out = []
    for source in split["sources"]:
        power = sum(w * p for w, p in zip(LUMINANCE, source["power"]))
        elevation = math.degrees(math.asin(max(-1.0, min(1.0, source["direction"][2]))))
        out.append((math.degrees(2.0 * source["major_radius"]), elevation, power / mass if mass > 0.0 else 0.0))
    return out


def lines(sources, sharp=False):
    """The panel's lines for found()'s list (None: still being found); sharp: whether the live
    shading shadows them on their own (Sharp Source Shadows)."""
    if sources is None:
        return ["Finding the map's bright sources"]
    if not sources:
        return ["No sun or lamp in the map: its light is soft"]
    share = sum(s for _, _, s in sources)
    head = "%s: %.0f %% of the light; %s" % (
        "1 bright source" if len(sources) == 1 else "%d bright sources" % len(sources), 100.0 * share,
        "shadowed per pixel" if sharp else "SH blurs their shadows")
    return [head] + ["%.1f\u00b0 wide at %.0f\u00b0 elevation, %.0f %%" % (width, elevation, 100.0 * s)
                     for width, elevation, s in sources]


@dataclass(frozen=True)
class Source:
    """One source as the shading uses it, in the environment's frame (before its rotation g)."""
    direction: tuple      # unit, towards the source
    major_axis: tuple     # unit, perpendicular to it: the axis it extends along most
    major_radius: float   # radians: the semi-axes of the uniform ellipse of its second moments
    minor_radius: float
    power: tuple          # RGB: integral of its radiance over the sphere's measure (the sphere: 1)
    extent: float = 0.0   # radians from its direction to its farthest texel's centre
    points: tuple = ()    # a highlight's light as weighted directions (with_highlight_points)

    @classmethod
    def from_split(cls, source):
        """From one of Environment.light_sources' "sources" dicts."""
        return cls(tuple(source["direction"]), tuple(source["major_axis"]), float(source["major_radius"]),
                   float(source["minor_radius"]), tuple(source["power"]), float(source["extent"]))

    @property
    def highlight(self):
        """Whether the glossy lobe takes it on its own (HIGHLIGHT_RADIUS), not from the atlas."""
        return self.major_radius <= HIGHLIGHT_RADIUS

    def irradiance(self, strength):
        """RGB: the Lambert lobe's B (w(t) = 4 max(0, t) over the sphere's measure) that the
        source gives a surface facing it, times the environment's strength."""
        return 4.0 * strength * np.asarray(self.power, dtype=np.float64)


def _perpendicular_frame(direction):
    """Two unit vectors (u, w) with (u, w, direction) right-handed and orthonormal."""
    d = np.asarray(direction, dtype=np.float64)
    helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, d)
    u /= np.linalg.norm(u)
    return u, np.cross(d, u)


def shadow_rows(sources, to_environment, center, radius, size=SHADOW_MAP_SIZE):
    """The shader's rows of each source's shadow map, float64 [SOURCE_ROWS N, 4], and the caster
    pass's projection of each, [N] 4x4 (world to the map's clip space).

    Map i covers the sphere of `center` and `radius` (world; what casts shadows) seen from the
    source's world direction d = g^T (its direction), g = `to_environment`. Rows per source:
    0, 1: a world point's (u, v) in the map, [0, 1] across it; 2: its distance t towards the
    source from the sphere's centre (t = d . (p - c), what the map stores; larger is nearer the
    source); 3: its major axis in (u, v) (unit; the minor axis is it turned a quarter towards v), and
    its semi-axes as (u, v) per unit of blocker distance (their tangents over the map's span): how
    far a penumbra reaches; 4: (world size of a texel, the largest t anything casting can have: the
    radius, the span 2 radius, 0)."""
    g = np.asarray(to_environment, dtype=np.float64)
    center = np.asarray(center, dtype=np.float64)
    radius = max(float(radius), 1e-6)
    span = 2.0 * radius
    rows = np.zeros((SOURCE_ROWS * len(sources), 4))
    projections = []
    for i, source in enumerate(sources):
        d = g.T @ np.asarray(source.direction, dtype=np.float64)
        d /= np.linalg.norm(d)
        u, w = _perpendicular_frame(d)
        major = g.T @ np.asarray(source.major_axis, dtype=np.float64)
        major -= d * (major @ d)
        major = major / np.linalg.norm(major) if np.linalg.norm(major) > 1e-9 else u
        r = rows[SOURCE_ROWS * i:SOURCE_ROWS * (i + 1)]
        r[0] = np.append(u / span, 0.5 - (u @ center) / span)
        r[1] = np.append(w / span, 0.5 - (w @ center) / span)
        r[2] = np.append(d, -(d @ center))
        r[3] = (major @ u, major @ w, math.tan(source.major_radius) / span, math.tan(source.minor_radius) / span)
        r[4] = (span / size, radius, span, 0.0)
        # clip x, y = 2 (u, v) - 1; z = -t / radius, so that the depth test keeps what is nearest the source
        projection = np.zeros((4, 4))
        projection[0] = 2.0 * r[0] - np.array([0.0, 0.0, 0.0, 1.0])
        projection[1] = 2.0 * r[1] - np.array([0.0, 0.0, 0.0, 1.0])
        projection[2] = -r[2] / (radius * 1.001)
        projection[3, 3] = 1.0
        projections.append(projection)
    return rows, projections


def rows_from(rows, origin):
    """shadow_rows' rows for points relative to `origin` (world) instead of the world's: rows 0 - 2
    of each source take origin's dot product into their constant, in float64."""
    out = np.array(rows, dtype=np.float64)
    for i in range(len(out) // SOURCE_ROWS):
        part = out[SOURCE_ROWS * i:SOURCE_ROWS * i + 3]
        part[:, 3] += part[:, :3] @ np.asarray(origin, dtype=np.float64)
    return out


def shading_rows(sources, local_to_environment, strength):
    """The shader's per-source rows for one object: the direction towards each source in the
    object's bake space, (g R)^T times its direction, with sin^2 of the radius of the disc of its
    ellipse's area (sqrt(major minor): what the horizon clips, shaders/sd_source_shadows.glsl's
    sd_source_cosine); and its irradiance (Source.irradiance), with 1 where its highlight is shaded
    on its own (Source.highlight), else 0. float64 [N, 4] each."""
    gr = np.asarray(local_to_environment, dtype=np.float64)
    directions = np.zeros((len(sources), 4))
    irradiance = np.zeros((len(sources), 4))
    for i, source in enumerate(sources):
        directions[i, :3] = gr.T @ np.asarray(source.direction, dtype=np.float64)
        directions[i, 3] = math.sin(math.sqrt(source.major_radius * source.minor_radius)) ** 2
        irradiance[i] = (*source.irradiance(strength), float(source.highlight))
    return directions, irradiance


def _texel_angles(rows, columns, height, width):
    """(polar angle, azimuth) of the centres of the texels at `rows` (top-first) and `columns` of a
    height x width equirect map in Blender's orientation (u = 0.5 - atan2(y, x) / 2 pi)."""
    return (rows + 0.5) * (math.pi / height), (0.5 - (columns + 0.5) / width) * 2.0 * math.pi


def _highlight_texels(sources, height, width):
    """For each highlight source (Source.highlight) of `sources`: (source, rows, taken), the rows
    (top-first) its extent and a texel more crosses in a map of height x width, and which texels of
    them it takes - its extent and a texel more, less any wider source's and any earlier highlight's
    (two close lamps share no texel) - bool [len(rows), width]."""
    texel = math.pi / height
    _, phi = _texel_angles(0, np.arange(width), height, width)
    phi = phi.astype(np.float32)

    def cap(source, rows):
        theta = _texel_angles(rows, 0, height, width)[0].astype(np.float32)[:, None]
        d = np.asarray(source.direction, dtype=np.float32)
        cosine = np.sin(theta) * (np.cos(phi) * d[0] + np.sin(phi) * d[1]) + np.cos(theta) * d[2]
        return cosine >= math.cos(min(source.extent + texel, math.pi))

    for i, source in enumerate(sources):
        if not source.highlight:
            continue
        polar = math.acos(max(-1.0, min(1.0, source.direction[2])))
        reach = source.extent + 2.0 * texel
        rows = np.arange(max(0, int((polar - reach) / texel)), min(height, int((polar + reach) / texel) + 1))
        taken = cap(source, rows)
        for j, other in enumerate(sources):
            if not other.highlight or j < i:
                taken &= ~cap(other, rows)
        yield source, rows, taken


def highlight_rows(sources, local_to_environment):
    """The shader's rows of each highlight's points (Source.points) for one object, two per point,
    float64 [2 N HIGHLIGHT_POINTS, 4]: its direction in the object's bake space, (g R)^T times its
    own, with its alpha^2 widening; its share of the source's power per channel, with 0. A source
    given without points (not a highlight; made without a map, as in a test) is its ellipse's
    centre with all of its power, widened as the ellipse's peak is, major minor / 4. (A highlight
    whose texels all lie in a wider source's extent has points without shares: its light stays in
    the atlas.)"""
    gr = np.asarray(local_to_environment, dtype=np.float64)
    rows = np.zeros((len(sources), HIGHLIGHT_POINTS, 2, 4))
    for i, source in enumerate(sources):
        own = np.array(source.points or ((*source.direction, 0.25 * source.major_radius * source.minor_radius,
                                          1.0, 1.0, 1.0),), dtype=np.float64)
        rows[i, :len(own), 0, :3] = own[:, :3] @ gr     # (g R)^T d, row by row
        rows[i, :len(own), 0, 3] = own[:, 3]
        rows[i, :len(own), 1, :3] = own[:, 4:]
    return rows.reshape(-1, 4)


def without_highlights(whole, remainder, sources):
    """The map for the prefiltered atlas where the glossy lobe takes the highlight sources on their
    own (Source.highlight): the remainder's texels within each one's extent (and a texel more),
    the whole map's elsewhere and within a wider source's extent - so a wider source stays in the
    atlas whole. whole, remainder: the maps' RGB, [H, W, 3], rows top-first (sdnative's
    environment_from_pixels); float32 [H, W, 3]. Only the rows a cap crosses are looked at."""
    out = np.array(whole, dtype=np.float32)
    for _, rows, taken in _highlight_texels(sources, *out.shape[:2]):
        band = out[rows]
        band[taken] = np.asarray(remainder[rows[0]:rows[-1] + 1], dtype=np.float32)[taken]
        out[rows] = band
    return out


def with_highlight_points(sources, whole, remainder):
    """`sources` with each highlight's `points`: the light without_highlights takes from the atlas
    (whole - remainder over the texels it takes, luminance times each texel's solid angle) as
    HIGHLIGHT_POINTS weighted directions, so that its highlight has the source's own shape and colours - a
    sun's peaked, whiter core, a lamp's ellipse - not a uniform disc's flat top. Texels are gathered
    by k-means weighted by luminance in the plane tangent at the source's direction, from the
    brightest; each point is its texels' mean direction, how much its lobe's alpha^2 is widened
    to spread the light as they do, and their share of the power per channel. The widening matches
    the peak of D in l (1 / (4 pi alpha^2) for a mirror seen head-on) to the light's: a texel is read
    bilinearly by Cycles, a tent of peak 1 / (h_theta h_phi) (h: its angular sides), so
    h_theta h_phi / (4 pi); the texels' spread about the point adds half their second moment (a
    uniform disc's radius^2 / 4). Points without texels have no share."""
    height, width, _ = np.shape(whole)
    texel = math.pi / height
    out = []
    for source, rows, taken in _highlight_texels(sources, height, width):
        y, x = np.nonzero(taken)
        theta, phi = _texel_angles(rows[y], x, height, width)
        excess = np.maximum(np.asarray(whole[rows[y], x], dtype=np.float64) - remainder[rows[y], x], 0.0)
        power = excess * np.sin(theta)[:, None]
        directions = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)
        tent = texel * (2.0 * np.pi / width * np.sin(theta)) / (4.0 * np.pi)
        centre = np.asarray(source.direction, dtype=np.float64)
        # the gnomonic plane holds the texels well within a hemisphere (an extent is at most 10 degrees)
        keep = (power @ np.asarray(LUMINANCE) > 0.0) & (directions @ centre > 0.5)
        points = _clustered(directions[keep], power[keep], tent[keep], centre, HIGHLIGHT_POINTS)
        out.append((source, points))
    found = {id(source): points for source, points in out}
    return [dataclasses.replace(s, points=found[id(s)]) if id(s) in found else s for s in sources]


def _clustered(directions, power, tents, centre, count):
    """((x, y, z, widening, share R, G, B) * count): k-means of unit `directions` weighted by the
    luminance of their RGB `power` into `count` points in the gnomonic plane about `centre`, each
    point's alpha^2 widening its texels' own `tents` and half their second moment
    (with_highlight_points); zero rows past the texels."""
    if not len(power):
        return ((0.0,) * 7,) * count
    weights = power @ np.asarray(LUMINANCE)
    u, w = _perpendicular_frame(centre)
    depth = directions @ centre
    plane = np.stack([directions @ u, directions @ w], axis=1) / depth[:, None]
    order = np.argsort(-weights, kind="stable")
    means = plane[order[:count]].copy()
    for _ in range(8):
        label = np.argmin(((plane[:, None, :] - means[None]) ** 2).sum(axis=2), axis=1)
        for k in range(len(means)):
            mine = label == k
            if mine.any():
                means[k] = np.average(plane[mine], axis=0, weights=weights[mine])
    total = np.maximum(power.sum(axis=0), 1e-30)
    points = []
    for k in range(len(means)):
        mine = label == k
        if not mine.any():
            continue
        spread = np.average(0.5 * ((plane[mine] - means[k]) ** 2).sum(axis=1) + tents[mine], weights=weights[mine])
        direction = centre + means[k][0] * u + means[k][1] * w
        points.append((*(direction / np.linalg.norm(direction)), float(spread), *(power[mine].sum(axis=0) / total)))
    return tuple(points) + ((0.0,) * 7,) * (count - len(points))
