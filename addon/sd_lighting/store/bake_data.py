"""What a bake stores: the per-vertex arrays sdnative.bake_transfer returns, as attributes of the
baked mesh and as the shader's texels, and the custom properties that link and describe a bake.
The names are a file format; README.md ("Where the results live") is the user's reference, this
module is what writes and reads them.

An array is stored either as one FLOAT attribute `sd_<name>` (a scalar per vertex), or as vec4
groups: FLOAT_COLOR attributes `sd_<name>_000`, `_001`, ... which are, in this order, the vertex's
texels in the shader's data texture; coefficient arrays are flattened row-major and their last
group zero padded. Designs (eq. 13) are stored at their own length: each vertex's node count in
the INT attribute `sd_design_count`, and the nodes of all vertices, in vertex order, as the points
of a nodes' mesh the baked mesh links in `sd_design_nodes`: each point is its node's weight times
its direction, lambda x (weights are positive: |lambda x| gives both back), so a node is 12 bytes.
In the data texture a design is one header texel per vertex (where its nodes start, as column and
row of the texture, and how many there are) followed by every vertex's nodes (x, y, z, lambda).
"""

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

PREFIX = "sd_"
NORMAL = PREFIX + "normal"          # FLOAT_VECTOR: the normal a vertex was baked and is shaded with
MATERIAL_SLOT = PREFIX + "material_slot"  # FLOAT: the vertex's material slot (objects with several)
UV = PREFIX + "uv"                  # FLOAT2: the vertex's UV for the albedo texture (when one is read)
SIDE = PREFIX + "side"              # FLOAT: bake/sides.py's FRONT_SIDE or BACK_SIDE for a vertex drawn from its own side only
BAKE = PREFIX + "bake"              # custom property: the bake's settings and summary
BAKED_MESH = PREFIX + "baked_mesh"  # custom property of an object: its baked mesh
LIGHTMAP = PREFIX + "lightmap"      # custom property of a baked mesh: its texels' mesh (texture space)
LIGHTMAP_UV = "SD Lightmap"         # the baked mesh's UV map of those texels
TEXEL = PREFIX + "texel"            # FLOAT: a texels' mesh point's texel, y W + x (exact below 2^24)
DESIGN_COUNT = PREFIX + "design_count"    # INT: the nodes of a vertex's design
DESIGN_NODES = PREFIX + "design_nodes"    # custom property of a mesh with designs: its nodes' mesh
DESIGN_TOTAL = PREFIX + "design_total"    # custom property of a nodes' mesh: its node count
TEXTURE_WIDTH_LOG2 = 12
TEXTURE_WIDTH = 1 << TEXTURE_WIDTH_LOG2   # every data texture has this width (rows: as needed)


def vec4_groups(values):
    """[N, K] -> float32 [N, G, 4] with G = ceil(K / 4), the last group zero padded."""
    values = np.asarray(values, dtype=np.float32)
    n, k = values.shape
    groups = (k + 3) // 4
    padded = np.zeros((n, 4 * groups), dtype=np.float32)
    padded[:, :k] = values
    return padded.reshape(n, groups, 4)


def weighted_nodes(nodes, weights):
    """A nodes' mesh's points: float32 [total, 3], each node's weight times its unit direction."""
    return (np.asarray(nodes, dtype=np.float64).reshape(-1, 3) *
            np.asarray(weights, dtype=np.float64).reshape(-1, 1)).astype(np.float32)


def split_weighted_nodes(points):
    """Inverse of weighted_nodes: (unit nodes float64 [total, 3], weights float64 [total])."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    weights = np.linalg.norm(points, axis=1)
    return points / np.where(weights > 0.0, weights, 1.0)[:, None], weights


def design_headers(offsets):
    """Each vertex's header texel for sdnative's design offsets [N+1], its nodes following the N
    headers: float32 [N, 4] (column and row of its first node's texel, its node count, 0). Column
    and row are exact floats at any size the texture can have (one float is not, past 2^24)."""
    offsets = np.asarray(offsets, dtype=np.int64)
    n = len(offsets) - 1
    first = n + offsets[:-1]
    headers = np.zeros((n, 4), dtype=np.float32)
    headers[:, 0] = first & (TEXTURE_WIDTH - 1)
    headers[:, 1] = first >> TEXTURE_WIDTH_LOG2
    headers[:, 2] = np.diff(offsets)
    return headers


def design_texels(offsets, nodes, weights):
    """Per-vertex designs (sdnative's offsets [N+1], nodes [total, 3], weights [total]) as the data
    texture's float32 [N + total, 4] texels: the headers (design_headers), then the nodes
    (x, y, z, lambda)."""
    headers = design_headers(offsets)
    nodes = np.concatenate([np.asarray(nodes, dtype=np.float32).reshape(-1, 3),
                            np.asarray(weights, dtype=np.float32).reshape(-1, 1)], axis=1)
    return np.concatenate([headers, nodes])


@dataclass(frozen=True)
class VertexArray:
    """One kind of per-vertex bake data."""
    name: str                  # stored as sd_<name> (scalar), sd_<name>_NNN (vec4 groups) or as designs
    keys: tuple                # its entries in bake_transfer's result and sdnative.shade's arguments
    packing: str               # "scalar", "coefficients" (a per-vertex array of `shape`) or "design"
    shape: Optional[Callable] = None          # (s, s') -> per-vertex shape of "coefficients"
    bake_argument: Optional[Callable] = None  # (s, s') -> bake_transfer's keywords; None: every bake

    @property
    def grouped(self):
        """Stored as vec4 groups (FLOAT_COLOR attributes)."""
        return self.packing == "coefficients"

    @property
    def attribute(self):
        """The name of a scalar array's attribute."""
        return PREFIX + self.name

    def group_name(self, index):
        """The name of a grouped array's index-th vec4 attribute: sd_visibility_000, ..."""
        return "%s%s_%03d" % (PREFIX, self.name, index)

    def bake_arguments(self, light_order, visibility_order):
        """The keywords that make sdnative.bake_transfer return this array."""
        return self.bake_argument(light_order, visibility_order) if self.bake_argument else {}

    def in_result(self, result):
        return all(result.get(key) is not None for key in self.keys)

    def stride(self, light_order, visibility_order):
        """Texels per vertex in the data texture: its vec4 groups, or a design's header."""
        if self.packing == "coefficients":
            return (int(np.prod(self.shape(light_order, visibility_order))) + 3) // 4
        return 1

    def stored_floats(self, arrays):
        """Floats per vertex the array takes stored (store/attributes.write; a design's node count,
        an int, as one float): one for a scalar, its vec4 groups, or a design at its own length -
        three floats a node and the count."""
        if self.packing == "design":
            offsets = np.asarray(arrays[self.keys[0]])
            return 1 + 3 * int(offsets[-1]) / max(len(offsets) - 1, 1)
        return 4 * self.groups(arrays).shape[1] if self.grouped else 1

    def groups(self, arrays):
        """A scalar or coefficient array (its key in `arrays`, e.g. a bake result) as float32
        [N, G, 4] vec4 groups; a scalar is one group (value, 0, 0, 0)."""
        values = np.asarray(arrays[self.keys[0]])
        return vec4_groups(values.reshape(len(values), -1))

    def from_groups(self, groups, light_order, visibility_order):
        """Inverse of groups(): {key: float64 array in sdnative's shapes}."""
        n = groups.shape[0]
        shape = self.shape(light_order, visibility_order) if self.shape else ()
        flat = groups.reshape(n, -1)[:, :int(np.prod(shape))]
        return {self.keys[0]: flat.reshape((n,) + tuple(shape)).astype(np.float64)}

    def texels(self, arrays):
        """The array as the data texture's texels: (float32 [M, 4], texels per vertex)."""
        if self.packing == "design":
            return design_texels(*(arrays[key] for key in self.keys)), 1
        groups = self.groups(arrays)
        return groups.reshape(-1, 4), groups.shape[1]


AMBIENT_OCCLUSION = VertexArray("ambient_occlusion", ("ambient_occlusion",), "scalar")
VISIBILITY = VertexArray("visibility", ("visibility",), "coefficients",
                         shape=lambda s, sv: ((sv + 1) ** 2,),
                         bake_argument=lambda s, sv: {"visibility_order": sv})
TRANSFER = VertexArray("transfer", ("transfer",), "coefficients",
                       shape=lambda s, sv: ((s + 1) ** 2,),
                       bake_argument=lambda s, sv: {"transfer_order": s})
PRODUCT_MATRIX = VertexArray("product_matrix", ("product_matrices",), "coefficients",
                             shape=lambda s, sv: ((s + 1) ** 2, (sv + 1) ** 2),
                             bake_argument=lambda s, sv: {"product_orders": (s, sv)})
DESIGN = VertexArray("design", ("design_offsets", "design_nodes", "design_weights"), "design",
                     bake_argument=lambda s, sv: {"design_orders": (s, sv)})

ARRAYS = (AMBIENT_OCCLUSION, VISIBILITY, TRANSFER, PRODUCT_MATRIX, DESIGN)
