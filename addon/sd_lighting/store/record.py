"""The bake record: what a bake was asked for, what the automatic mode chose and what the bake
found - the `sd_bake` custom property of the baked mesh and of its object (store/baked.py writes
and reads it; README.md, "Where the results live", describes it for users).

The schema is the dataclass below; the property holds its fields as a flat dict (an ID property
group), absent where a field is None. `VERSION` is written with it: a record of a later version,
or one that lacks a field every bake writes, cannot be read and asks to bake again
(RecordError). Records written before the version existed have the same fields: they read as
version 1.

Nothing here needs Blender.
"""

import dataclasses
import typing
from dataclasses import dataclass, field
from typing import Optional, Tuple

from ..scene.lobes import Lobes

VERSION = 1


class RecordError(Exception):
    """A record this add-on cannot read, with a message for the user."""


def _found(default=None):
    """A field the bake found (its summary), not one it was asked for or chose."""
    return field(default=default, metadata={"found": True})


@dataclass(frozen=True)
class BakeRecord:
    # What the bake was asked for: the panel's settings and the object's overrides.
    method: str                  # methods.Method id; "automatic" before the automatic mode chose
    light_order: int             # s
    visibility_order: int        # s' (0 for the methods without one)
    rays: int
    seed: int
    lobe: str                    # scene/lobes.py: the material's lobe, exponent and colour weights
    exponent: float
    environment: str             # the environment's description, for the panel
    refine: bool
    refine_target: float
    refine_max_vertices: int
    least_squares: bool
    lightmap: int                # the lightmap's side asked for texture-space data; 0: none
    shape: Tuple[float, ...] = ()   # the object's scale K (3 x 3, row-major) it was baked with
    placement: Tuple[float, ...] = ()   # its world matrix (4 x 4, row-major) at the bake
    diffuse_lobe: bool = False   # a Lambert lobe besides `lobe` (records before it: none)
    lobe_weights: bool = False
    diffuse_share: float = 0.0
    # The seconds of rays its share of the selection's budget allows (plan/budget.py; None: a bake
    # from before the budget, whose choice had CONFIRM_SECONDS and whose refinement had Max Verts)
    bake_seconds_budget: Optional[float] = None
    # What the automatic mode chose besides method, orders and rays (None: not automatic).
    automatic: Optional[str] = None       # its reasons, one per line
    per_pixel: Optional[bool] = None
    predicted_error: Optional[float] = None
    frame_terms: Optional[int] = None
    sources: Optional[bool] = None   # the map's bright sources shaded on their own (None: the
                                     # scene's Sharp Source Shadows decides)
    traced: Optional[bool] = None    # chosen with the glossy lobe's visibility traced when drawn
                                     # (the scene's Reflection Rays: its baked visibility unused)
    # What the bake found.
    bake_id: str = _found("")
    inputs: str = _found("")     # digest of everything the result depends on (BakeTask.inputs_hash)
    source: str = _found("")     # digest of the evaluated mesh baked (store/source.py; before it: "")
    occluder_triangles: int = _found(0)   # the other objects' triangles it was baked against
    faces_flipped: int = _found(0)   # faces turned round, faces given a reverse copy (bake/sides.py)
    faces_doubled: int = _found(0)
    seconds: float = _found(0.0)
    vertices: int = _found(0)
    floats_per_vertex: float = _found(0.0)   # the bake data's mean per vertex (designs vary)
    bytes_per_vertex: float = _found(0.0)
    design_nodes_max: Optional[int] = _found()     # methods with per-vertex designs
    design_nodes_mean: Optional[float] = _found()
    unrefined_vertices: Optional[int] = _found()   # with refinement
    refine_levels: Optional[int] = _found()
    refine_seconds: Optional[float] = _found()
    refine_worst_left: Optional[float] = _found()
    refine_estimated_left: Optional[float] = _found()
    refine_budget_reached: Optional[bool] = _found()
    lightmap_texels: Optional[int] = _found()      # with texture-space data
    lightmap_stored: Optional[int] = _found()
    lightmap_seconds: Optional[float] = _found()

    @classmethod
    def from_dict(cls, values):
        """The record of a property's dict (or any mapping of its fields, e.g. a bake's settings
        without what it found). RecordError for a later version or a missing field."""
        values = dict(values)
        version = int(values.pop("version", 1))
        if version > VERSION:
            raise RecordError("the bake was made by a later SD Lighting (record version %d, this one "
                              "reads %d): bake again" % (version, VERSION))
        kwargs = {}
        for f in dataclasses.fields(cls):
            if f.name not in values or values[f.name] is None:
                if f.default is dataclasses.MISSING:
                    raise RecordError("the bake record has no '%s': bake again" % f.name)
                continue
            kwargs[f.name] = _typed(f.type, values[f.name])
        return cls(**kwargs)

    def to_dict(self):
        """The property's dict: every field that is not None, and the version."""
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                  if getattr(self, f.name) is not None}
        values["shape"] = list(self.shape)
        values["placement"] = list(self.placement)
        values["version"] = VERSION
        return values

    def settings(self):
        """What the bake was asked for and what the automatic mode chose (a bake's settings dict:
        a re-bake with them bakes the same), without what it found."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if not f.metadata.get("found") and getattr(self, f.name) is not None}

    @property
    def lobes(self):
        """The material's lobes it was baked for."""
        return Lobes(self.lobe, self.exponent, self.diffuse_lobe, self.lobe_weights, self.diffuse_share)

    @property
    def chosen_automatically(self):
        return self.automatic is not None

    @property
    def refined(self):
        return self.unrefined_vertices is not None

    @property
    def has_texels(self):
        return self.lightmap_texels is not None


def _typed(annotation, value):
    """A stored value as its field's type (an ID property keeps a bool as an int, a tuple as an
    IDPropertyArray)."""
    if typing.get_origin(annotation) is typing.Union:        # Optional[kind]
        annotation = typing.get_args(annotation)[0]
    if typing.get_origin(annotation) is tuple:
        return tuple(float(x) for x in value)
    return annotation(value)
