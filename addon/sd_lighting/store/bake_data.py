"""What a bake stores: the per-vertex arrays sdnative.bake_transfer returns, as attributes of the
baked mesh and as the shader's texels, and the custom properties that link and describe a bake.
The names are a file format; README.md ("Where the results live") is the user's reference, this
module is what writes and reads them.

An array is stored either as one FLOAT attribute `sd_<name>` (a scalar per vertex), or as vec4
groups: FLOAT_COLOR attributes `sd_<name>_000`, `_001`, ... which are, in this order, the vertex's
texels in the shader's data texture. Coefficient arrays are flattened row-major and their last
group zero padded; designs hold a node (x, y, z, lambda) per group, padded with lambda = 0.
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


def padded_designs(offsets, nodes, weights):
    """Per-vertex designs (sdnative's offsets [N+1], nodes [total, 3], weights [total]) as float32
    [N, max(nodes per vertex, 1), 4] rows (x, y, z, lambda), lambda = 0 padding."""
    offsets = np.asarray(offsets, dtype=np.int64)
    counts = np.diff(offsets)
    n = counts.size
    width = int(counts.max()) if n else 0
    padded = np.zeros((n, max(width, 1), 4), dtype=np.float32)
    if offsets[-1] > 0:
        vertex = np.repeat(np.arange(n), counts)
        slot = np.arange(offsets[-1]) - offsets[vertex]
        padded[vertex, slot, :3] = np.asarray(nodes, dtype=np.float32).reshape(-1, 3)
        padded[vertex, slot, 3] = np.asarray(weights, dtype=np.float32)
    return padded


def unpadded_designs(padded):
    """Inverse of padded_designs: (offsets int64 [N+1], nodes float64 [total, 3], weights [total])."""
    used = padded[:, :, 3] > 0.0
    offsets = np.zeros(padded.shape[0] + 1, dtype=np.int64)
    np.cumsum(used.sum(axis=1), out=offsets[1:])
    return offsets, padded[used][:, :3].astype(np.float64), padded[used][:, 3].astype(np.float64)


@dataclass(frozen=True)
class VertexArray:
    """One kind of per-vertex bake data."""
    name: str                  # stored as sd_<name> (scalar) or sd_<name>_NNN (vec4 groups)
    keys: tuple                # its entries in bake_transfer's result and sdnative.shade's arguments
    packing: str               # "scalar", "coefficients" (a per-vertex array of `shape`) or "design"
    shape: Optional[Callable] = None          # (s, s') -> per-vertex shape of "coefficients"
    bake_argument: Optional[Callable] = None  # (s, s') -> bake_transfer's keywords; None: every bake

    @property
    def grouped(self):
        """Stored as vec4 groups (FLOAT_COLOR) rather than one FLOAT."""
        return self.packing != "scalar"

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

    def texels(self, arrays):
        """The array (its keys in `arrays`, e.g. a bake result) as the shader's texels: float32
        [N, G, 4]; a scalar is one texel (value, 0, 0, 0)."""
        if self.packing == "design":
            return padded_designs(*(arrays[key] for key in self.keys))
        values = np.asarray(arrays[self.keys[0]])
        return vec4_groups(values.reshape(len(values), -1))

    def from_texels(self, texels, light_order, visibility_order):
        """Inverse of texels(): {key: float64 array in sdnative's shapes} (design offsets int64)."""
        if self.packing == "design":
            return dict(zip(self.keys, unpadded_designs(texels)))
        n = texels.shape[0]
        shape = self.shape(light_order, visibility_order) if self.shape else ()
        flat = texels.reshape(n, -1)[:, :int(np.prod(shape))]
        return {self.keys[0]: flat.reshape((n,) + tuple(shape)).astype(np.float64)}


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
