"""The shading methods: the one table of what each computes and what it needs from the bake, the
CPU evaluator and the shader. Adding a method is an entry here, its native evaluator
(sdnative.shade), its GLSL branch (SD_METHOD_<ID>) and their tests.

Identifiers are those of `sdnative.shade(method, ...)`; equation numbers are the seed's
(msd-notes.md); s is the environment's SH order, s' the visibility's.
"""

from dataclasses import dataclass
from typing import Callable, Optional

from .store import bake_data
from .plan.cost import design_nodes
from .store.bake_data import AMBIENT_OCCLUSION, DESIGN, PRODUCT_MATRIX, TRANSFER, VISIBILITY


@dataclass(frozen=True)
class Method:
    id: str                    # sdnative.shade's name; the shader's SD_METHOD_<ID>
    label: str                 # shown in the panel
    short_label: str           # in tables and plots: its equation
    description: str           # tooltip
    data: Optional[bake_data.VertexArray]  # what it reads per vertex (baked, and the data texture)
    basis_order: Callable      # (s, s', band-limited texture) -> order of the SH basis the shader
                               # evaluates at a direction (-1: none)
    lobe_order: Callable       # (s, s') -> highest l of the lobe's Funk-Hecke factors it reads
    frame_terms: Callable      # (s, s', gaunt) -> multiply-adds per vertex and colour of a frame;
                               # gaunt: (s, s') -> eq. (10)'s Gaunt term count (cost.gaunt_terms)
    uses_visibility_order: bool = False   # has an s' (bakes and reads V at order s')
    lambert_only: bool = False
    band_limited_texture: bool = False    # can look L~ up in the band-limited texture
    lobe_design: bool = False  # reads the lobe's design of degree s + s' (eq. 12)
    gaunt_table: bool = False  # reads the real Gaunt coefficients (eq. 10)
    equal_to: Optional[str] = None   # the method whose result it equals for the same bake (its
                                     # error is measured once, as that method's)
    open_order: Callable = lambda s, sv: s   # (s, s') -> the order of the lobe's Funk-Hecke sum
                                     # its B is where V = 1 (the prefiltered glossy light's
                                     # visibility ratio divides by that)

    def bake_arguments(self, light_order, visibility_order):
        """sdnative.bake_transfer's keywords for what this method reads (the ambient occlusion
        and the normals come with every bake)."""
        return self.data.bake_arguments(light_order, visibility_order) if self.data else {}

    @property
    def baked_kind(self):
        """The kind of data its bake traces rays for (bake_data.VertexArray.name): the ambient
        occlusion, which every bake returns, for a method that reads nothing else."""
        return (self.data or bake_data.AMBIENT_OCCLUSION).name

    @property
    def measured_as(self):
        """The method whose error stands for its own: equal_to, or itself."""
        return self.equal_to or self.id

    @property
    def designs_per_vertex(self):
        """Whether its bake builds a design per vertex (eq. 13): far slower than the rays alone."""
        return self.data is DESIGN

    @property
    def shade_inputs(self):
        """The per-vertex keywords of sdnative.shade it takes, besides light and normals."""
        keys = self.data.keys if self.data else ()
        return keys + (("visibility_order",) if self.uses_visibility_order else ())


METHODS = (
    Method("msd_visibility", "MSD Theorem 2.2 (13)", "MSD (13)",
           "Method of spherical designs with a per-vertex design of the visibility: eq. (13). "
           "Equal to PRT (8) for the same rays, at a fraction of its cost", DESIGN,
           basis_order=lambda s, sv, texture: -1 if texture else s,
           lobe_order=lambda s, sv: sv,
           # each node: L~ there and the lobe truncated at s'
           frame_terms=lambda s, sv, gaunt: design_nodes(s + sv) * ((s + 1) ** 2 + sv + 1),
           uses_visibility_order=True, band_limited_texture=True, equal_to="prt_matrix",
           open_order=lambda s, sv: min(s, sv)),
    Method("msd_lobe", "MSD Theorem 2.1 (12)", "MSD (12)",
           "Method of spherical designs with a design of the BRDF lobe turned onto the lobe axis: "
           "eq. (12). Equal to PRT (10)", VISIBILITY,
           basis_order=lambda s, sv, texture: sv if texture else max(s, sv),
           lobe_order=lambda s, sv: 0,
           # each lobe-design node: L~ and V~ there
           frame_terms=lambda s, sv, gaunt: design_nodes(s + sv) * ((s + 1) ** 2 + (sv + 1) ** 2),
           uses_visibility_order=True, band_limited_texture=True, lobe_design=True, equal_to="prt_gaunt"),
    Method("prt_gaunt", "PRT (10)", "PRT (10)",
           "Precomputed radiance transfer with the visibility's SH coefficients and real Gaunt "
           "coefficients: eq. (10)", VISIBILITY,
           basis_order=lambda s, sv, texture: s + sv,
           lobe_order=lambda s, sv: s + sv,
           frame_terms=lambda s, sv, gaunt: gaunt(s, sv),   # one per non-zero Gaunt coefficient
           uses_visibility_order=True, gaunt_table=True),
    Method("prt_matrix", "PRT (8)", "PRT (8)",
           "Precomputed radiance transfer with the full visibility product matrix: eqs. (8)-(9)",
           PRODUCT_MATRIX,
           basis_order=lambda s, sv, texture: sv,
           lobe_order=lambda s, sv: sv,
           # M^T L, then against the lobe of order s'
           frame_terms=lambda s, sv, gaunt: (s + 1) ** 2 * (sv + 1) ** 2 + (sv + 1) ** 2,
           uses_visibility_order=True, open_order=lambda s, sv: min(s, sv)),
    Method("prt_diffuse", "PRT (2), diffuse", "PRT (2)",
           "Precomputed radiance transfer for Lambert materials: one dot product, eq. (2)",
           TRANSFER,
           basis_order=lambda s, sv, texture: -1,
           lobe_order=lambda s, sv: 0,
           frame_terms=lambda s, sv, gaunt: (s + 1) ** 2,
           lambert_only=True),
    Method("ambient_occlusion", "Ambient occlusion only", "AO",
           "Unshadowed lighting scaled by the vertex's ambient occlusion", AMBIENT_OCCLUSION,
           basis_order=lambda s, sv, texture: s,
           lobe_order=lambda s, sv: s,
           frame_terms=lambda s, sv, gaunt: (s + 1) ** 2 + 1),
    Method("unshadowed", "Unshadowed", "unshadowed",
           "Environment lighting without any shadowing (V = 1)", None,
           basis_order=lambda s, sv, texture: s,
           lobe_order=lambda s, sv: s,
           frame_terms=lambda s, sv, gaunt: (s + 1) ** 2),
)

BY_ID = {method.id: method for method in METHODS}


def get(method_id):
    """The Method with this identifier; KeyError for an unknown one."""
    return BY_ID[method_id]


def enum_items():
    """Items for a bpy EnumProperty."""
    return [(m.id, m.label, m.description) for m in METHODS]
