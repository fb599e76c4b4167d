"""The selection's budget (issue 30, item 4): one bake of many objects spends its vertices and its
seconds where they show, instead of the whole Max Verts and a minute of rays for every part (a
CAD model imported as dozens of parts baked for minutes where the same model joined into one
object took under one: README, Use, item 6).

The panel's Max Verts and the seconds of `selection_seconds` are the selection's. Each object gets
the share of both that its surface area is of the selection's: what it covers of the view,
whichever way the user turns it (a camera's view would favour one side, and the viewport is
turned). Within its share of the seconds the automatic mode chooses among the settings its copy as
it is affords, and its refinement stops where the vertices it adds, with its tests, would take the
bake past that share at the chosen rays.

Nothing here needs Blender.
"""

import numpy as np

from . import cost

# The rays of a selection's bake at the defaults, all objects together, the refinement's tests
# included: SECONDS_PER_POINT for each mesh vertex and each texel of texture-space data asked for,
# within MIN_SELECTION_SECONDS .. SELECTION_SECONDS. The automatic mode's measurement and the
# least-squares fit come on top. So a CAD model of tens of thousands of vertices bakes within a
# minute and a model of under a thousand in seconds (issue 30), while a plane of a few vertices
# that a shadow crosses still gets the seconds its refinement needs to draw it.
SELECTION_SECONDS = 25.0
SECONDS_PER_POINT = 3e-3
MIN_SELECTION_SECONDS = 2.0
# The points a refinement's tests trace for each vertex of the refined copy (each level's ends and
# midpoints, bake/refine.py), as measured on real models (README, Use, item 6): left out, a bake at
# few rays spent up to twice its seconds.
TESTED_POINTS_PER_VERTEX = 4.0


def selection_seconds(points):
    """The seconds the rays of a selection's bake may take at the defaults; points: its mesh vertices
    and the texels of the texture-space data asked for (BakeTask.budget_points)."""
    return float(np.clip(SECONDS_PER_POINT * points, MIN_SELECTION_SECONDS, SELECTION_SECONDS))


def surface_area(positions, triangles, block=1 << 20):
    """The area of a triangle mesh (positions [n, 3] in world space, triangles [t, 3]), summed over
    blocks of `block` triangles (a 10M-vertex mesh's corners at once would take gigabytes)."""
    positions, triangles = np.asarray(positions, dtype=np.float64), np.asarray(triangles).reshape(-1, 3)
    area = 0.0
    for first in range(0, len(triangles), block):
        a, b, c = (positions[triangles[first:first + block, k]] for k in range(3))
        area += float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())
    return area


def shares(areas):
    """Each object's share of the selection's budget: its area over the selection's (equal shares
    when every area is zero)."""
    areas = np.maximum(np.asarray(areas, dtype=np.float64), 0.0)
    total = areas.sum()
    return areas / total if total > 0.0 else np.full(len(areas), 1.0 / max(len(areas), 1))


def affordable_vertices(seconds, method, light_order, visibility_order, rays, threads, points_per_vertex,
                        test=None):
    """How many vertices a bake of the method at these orders and rays traces within `seconds` on
    `threads` cores, each vertex tracing `points_per_vertex` points (least squares adds the face
    centres: about 3 points a vertex on a refined mesh); test: None, or for a refined copy the
    (method, light order, rays) its refinement tests with, TESTED_POINTS_PER_VERTEX points a vertex."""
    per_vertex = cost.bake_seconds(method, light_order, visibility_order, rays, 1, threads) * points_per_vertex
    if test is not None:
        test_method, test_order, test_rays = test
        per_vertex += cost.bake_seconds(test_method, test_order, 0, test_rays, 1, threads) * TESTED_POINTS_PER_VERTEX
    return int(seconds / per_vertex) if per_vertex > 0.0 else np.iinfo(np.int64).max
