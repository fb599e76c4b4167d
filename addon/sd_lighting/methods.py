"""The shading methods the add-on offers: what each computes, and what it needs from the bake.

Identifiers are those of `sdnative.shade(method, ...)`; equation numbers are the seed's
(msd-notes.md). `needs` says which per-vertex data the bake must store for a method:
  "visibility"  V~, the order-s' SH coefficients of the vertex's visibility
  "transfer"    T, the order-s diffuse transfer vector (Lambert only)
  "matrix"      M, the (s+1)^2 x (s'+1)^2 visibility product matrix
  "design"      the vertex's design of V of degree s+s' (nodes and weights)
The ambient occlusion is always stored (it comes with every bake).
"""

from dataclasses import dataclass


@dataclass(frozen=True)
class Method:
    id: str            # sdnative.shade's name
    label: str         # shown in the panel
    description: str   # tooltip
    needs: str         # "", "visibility", "transfer", "matrix" or "design"
    lambert_only: bool = False


METHODS = (
    Method("msd_visibility", "MSD Theorem 2.2 (13)",
           "Method of spherical designs with a per-vertex design of the visibility: eq. (13). "
           "Equal to PRT (8) for the same rays, at a fraction of its cost", "design"),
    Method("msd_lobe", "MSD Theorem 2.1 (12)",
           "Method of spherical designs with a design of the BRDF lobe turned onto the lobe axis: "
           "eq. (12). Equal to PRT (10)", "visibility"),
    Method("prt_gaunt", "PRT (10)",
           "Precomputed radiance transfer with the visibility's SH coefficients and real Gaunt "
           "coefficients: eq. (10)", "visibility"),
    Method("prt_matrix", "PRT (8)",
           "Precomputed radiance transfer with the full visibility product matrix: eqs. (8)-(9)",
           "matrix"),
    Method("prt_diffuse", "PRT (2), diffuse",
           "Precomputed radiance transfer for Lambert materials: one dot product, eq. (2)",
           "transfer", lambert_only=True),
    Method("ambient_occlusion", "Ambient occlusion only",
           "Unshadowed lighting scaled by the vertex's ambient occlusion", ""),
    Method("unshadowed", "Unshadowed",
           "Environment lighting without any shadowing (V = 1)", ""),
)

BY_ID = {method.id: method for method in METHODS}


def get(method_id):
    """The Method with this identifier; KeyError for an unknown one."""
    return BY_ID[method_id]


def enum_items():
    """Items for a bpy EnumProperty."""
    return [(m.id, m.label, m.description) for m in METHODS]
