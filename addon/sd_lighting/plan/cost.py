"""What a setting costs per vertex: the floats its bake stores and the seconds of its bake (the
multiply-adds of one frame are each method's `frame_terms`, methods.py) - the cost side of
the automatic mode (plan/automatic.py) and of the panel's prediction; the accuracy side is
plan/accuracy.py.

Design node counts are the generic count of a design of degree t, ((t+1)^2 + 2) / 3 rounded up
(a node is 3 unknowns for (t+1)^2 moments), which both builders' designs meet on average
(docs/msd-notes.md: 17.2 nodes at degree 6; 41 for a zonal lobe at degree 10).
"""

import math
import os

# Design build time per vertex per core by degree s+s' (ms; build/native/design_benchmarks 1024
# 9 3 8, refitted designs): MSD (13)'s bake is dominated by it. Beyond the table: x4 per degree.
DESIGN_MS = {0: 0.01, 1: 0.02, 2: 0.05, 3: 0.1, 4: 0.31, 5: 2.5, 6: 4.0, 7: 16.8, 8: 65.5,
             9: 154.0}
RAY_SECONDS = 1.5e-7         # per ray per core: Embree's occlusion rays with the projections
# The CPU evaluator's (sdnative.shade) time per frame term per vertex: the accuracy report's fits
# of ns per vertex against frame_terms run from 1.3 to 4.5 ns per term over the methods and lobes
# (docs/report/cost_model.json, "frame_ns_per_vertex"); this is their middle.
CPU_NS_PER_TERM = 2.0


def design_nodes(degree):
    """The generic node count of a weighted design of degree `degree`."""
    return math.ceil(((degree + 1) ** 2 + 2) / 3)


def gaunt_terms(sdnative, s, sv):
    """The non-zero real Gaunt coefficients eq. (10) sums over at orders s, s'."""
    return len(sdnative.gaunt_coefficients(s, sv, s + sv)[1])


def stored_floats(method, s, sv):
    """Floats per vertex the method's bake stores (methods.Method) as the bake counts them
    (`floats_per_vertex`, its normal excluded; a design's node count, an int, as one float): the
    ambient occlusion, which every bake keeps, and the method's array in vec4 groups, or a design at
    its own length, three floats a node (store/bake_data.py), the generic node count, which the
    designs meet on average."""
    data = method.data
    if data is None or data.packing == "scalar":
        return 1
    if data.packing == "design":
        return 2 + 3 * design_nodes(s + sv)
    return 1 + 4 * data.stride(s, sv)


# The peak memory of a bake (native arrays are float64; blender_tests/benchmark_bake.py --memory
# measures it against this model): per traced point its results and origin; per traced triangle
# (the object's, after a least-squares split, and the occluders') Embree's scene and the bake's
# record of which faces are sheets; per mesh vertex the add-on's arrays of the mesh.
POINT_BYTES = 130              # besides 8 bytes per float of its results
TRIANGLE_BYTES = 520
MESH_VERTEX_BYTES = 500


def bake_bytes(mesh_vertices, points, triangles, floats):
    """The predicted peak bytes of a bake tracing `points` points (vertices, with least squares
    also the face centres; texels) against `triangles` triangles (its own, split at the centres
    with least squares, and the occluders'), each point getting `floats` floats (stored_floats)."""
    return mesh_vertices * MESH_VERTEX_BYTES + points * (POINT_BYTES + 8 * floats) + triangles * TRIANGLE_BYTES


def available_bytes():
    """The memory a bake may take without pushing others out: Linux's MemAvailable, else the free
    physical pages; None where neither is known."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def memory_text(count):
    """Bytes for the user: "1.4 GB", "120 MB"."""
    return "%.1f GB" % (count / 1e9) if count >= 1e9 else "%.0f MB" % (count / 1e6)


def frame_milliseconds(frame_terms, vertices):
    """The predicted CPU evaluator time of one frame of `vertices` vertices (the GPU's is measured
    in the report, not modelled)."""
    return 1e-6 * CPU_NS_PER_TERM * frame_terms * vertices


def bake_seconds(method, s, sv, rays, vertices, threads):
    """The predicted seconds of the method's bake of `vertices` vertices on `threads` cores."""
    per_vertex = rays * RAY_SECONDS
    if method.data is not None and method.data.packing == "design":
        degree = s + sv
        top = max(DESIGN_MS)
        per_vertex += 1e-3 * (DESIGN_MS[degree] if degree <= top else DESIGN_MS[top] * 4.0 ** (degree - top))
    return per_vertex * vertices / max(threads, 1)
