"""The baked copy's geometry: the evaluated mesh as arrays in the object's bake space, its faces
turned or doubled where a viewer sees them from behind (sides.py), split where its corners shade
differently (corners.py) and optionally refined (refine.py), and the other objects' triangles
that occlude it, joined into one mesh.

The bake space is the object's local space with its scale K applied (scene/transforms.bake_space):
the rays of a non-uniformly scaled object are traced in the shape it is shown with.
"""

import dataclasses
import functools

import numpy as np

from .. import compat, native
from ..scene import materials, transforms
from ..store import attributes, source as source_module
from . import corners, refine, sides as sides_module

GEOMETRY_TYPES = {'MESH', 'CURVE', 'SURFACE', 'META', 'FONT'}


def casts(obj):
    """Whether moving or hiding the object can change the occluders (scene_parts): geometry, or an
    instancer of some."""
    return obj.type in GEOMETRY_TYPES or obj.is_instancer


def _unit_or_zero(vectors):
    """Unit rows; zero (and non-finite) rows become zero, for the native bake's fallback."""
    length = np.linalg.norm(vectors, axis=1)
    good = np.isfinite(length) & (length > 0.0)
    out = np.zeros_like(vectors)
    out[good] = vectors[good] / length[good, None]
    return out


class Geometry:
    """A mesh as arrays: its positions and polygons in the object's local space (to rebuild it as
    the baked mesh), and the vertices, normals and triangles that are baked, in the bake space
    (transforms.bake_space: the local space with the object's scale K applied).

    The vertices are the mesh's split where its corners shade differently (bake/corners.py): each
    carries the corner normal Blender and Cycles shade with, its material slot and, when a material
    reads an image texture, its UV (`material_slots`, `uvs`: per vertex, or None). A vertex whose
    corners have no normal (Blender finds none for degenerate faces: docs/blender-notes.md, "Zero
    vertex normals") keeps a zero one: the native bake gives it its faces' normal and lists it.
    Loose vertices (no face) are left out: nothing draws them.

    Faces are turned or doubled as sides.py says, against `occluders` ((vertices, triangles) in
    the bake space, or (None, None)); with `backs` False (every material culls back faces) no
    face gets a reverse copy."""

    def __init__(self, mesh, shape, uv_map=None):
        """mesh: a temporary mesh (Object.to_mesh()), which this scales by K; uv_map: the name of
        the UV layer an albedo texture is read through ("" for the active render layer), or None."""
        self._local_positions = attributes.read_positions(mesh)
        self._loop_vertices = np.empty(len(mesh.loops), dtype=np.int32)
        mesh.loops.foreach_get('vertex_index', self._loop_vertices)
        self._loop_starts = np.empty(len(mesh.polygons), dtype=np.int32)
        mesh.polygons.foreach_get('loop_start', self._loop_starts)
        self._loop_totals = np.empty(len(mesh.polygons), dtype=np.int32)
        mesh.polygons.foreach_get('loop_total', self._loop_totals)
        self._loop_slots = attributes.read_loop_material_slots(mesh) if len(mesh.materials) > 1 else None
        self._loop_uvs = attributes.read_loop_uvs(mesh, uv_map) if uv_map is not None else None
        # The scale applied as Object > Apply > Scale does (normals recomputed from the scaled
        # faces); a mirror's normals and triangles turned outside out (the bake reads their winding).
        matrix = np.eye(4)
        matrix[:3, :3] = shape
        mesh.transform([list(row) for row in matrix])
        self._mirrored = bool(np.linalg.det(shape) < 0)
        normals = compat.corner_normals(mesh).astype(np.float64)
        self._corner_normals = -normals if self._mirrored else normals
        self._scaled_positions = attributes.read_positions(mesh).astype(np.float64)
        self._triangle_loops = attributes.read_triangle_loops(mesh)
        self.triangle_count = len(self._triangle_loops)
        self.occluders = (None, None)
        self.backs = True
        self.lightmap_uvs = None   # each loop's lightmap UV [L, 2], for texture-space data (lightmap_uvs)
        self.unwrap_seconds = 0.0  # what finding them took

    def inputs(self):
        """What was read from the mesh: everything the other arrays are computed from."""
        return (self._local_positions, self._loop_vertices, self._loop_starts, self._loop_totals,
                self._loop_slots, self._loop_uvs, np.array(self._mirrored), self._corner_normals,
                self._scaled_positions, self._triangle_loops, np.array(self.backs))

    @functools.cached_property
    def source(self):
        """The digest of the mesh as read (store/source.py): what a bake of it was baked from."""
        return source_module.digest(self._local_positions, self._loop_vertices, self._loop_totals)

    @property
    def mesh_positions(self):
        """The mesh's own vertex positions in the local space (before the split)."""
        return self._local_positions

    @property
    def _wound_triangle_loops(self):
        loops = self._triangle_loops
        return loops[:, ::-1] if self._mirrored else loops

    @property
    def lightmap_corner_uvs(self):
        """Each triangle corner's lightmap UV [T, 3, 2], as `triangles`."""
        return self.lightmap_uvs[self.triangle_loops]

    @property
    def mesh_triangles(self):
        """`triangles` over the mesh's own vertices: the same faces, without computing the split."""
        return self._loop_vertices[self._wound_triangle_loops]

    # The sides, the split and what follows from them are computed when first read - for a bake
    # from the UI in its worker thread (BakeJob.run), not on the main thread, except for a
    # texture-space bake's unwrap (lightmap_uvs) - and kept.
    @functools.cached_property
    def _sided(self):
        wound = self._wound_triangle_loops
        vertices, triangles = self.occluders
        extra = {} if vertices is None else {"occluder_vertices": vertices, "occluder_triangles": triangles}
        codes = sides_module.polygon_codes(
            native.get().face_sides(self._scaled_positions, self._loop_vertices[wound], **extra),
            wound, self._loop_starts, self._loop_totals)
        if not self.backs:
            codes[codes == sides_module.BOTH] = sides_module.FRONT
        return sides_module.apply(codes, self._loop_starts, self._loop_totals, wound)

    @property
    def loop_starts(self):
        return self._sided.loop_starts

    @property
    def loop_totals(self):
        return self._sided.loop_totals

    @property
    def triangle_loops(self):
        """Each triangle's loops [T, 3] (of the turned and doubled faces), as the bake winds them."""
        return self._sided.triangle_loops

    @property
    def faces_flipped(self):
        """The polygons turned round (their front inside the solid they bound)."""
        return self._sided.flipped

    @property
    def faces_doubled(self):
        """The polygons given a reverse copy (seen from behind too)."""
        return self._sided.doubled

    @functools.cached_property
    def _split(self):
        sided = self._sided
        return corners.split(sided.gather(self._loop_vertices), sided.normals(self._corner_normals),
                             sided.gather(self._loop_slots), sided.gather(self._loop_uvs), sided.loop_sides)

    @functools.cached_property
    def positions(self):
        return self._local_positions[self._split.origin]

    @property
    def loop_vertices(self):
        return self._split.loop_vertex

    @functools.cached_property
    def vertices(self):
        return self._scaled_positions[self._split.origin]

    @functools.cached_property
    def normals(self):
        return _unit_or_zero(self._split.normal_sums)

    @functools.cached_property
    def triangles(self):
        return self._split.loop_vertex[self.triangle_loops]

    @functools.cached_property
    def material_slots(self):
        return None if self._loop_slots is None else corners.vertex_values(self._split, self._sided.gather(self._loop_slots))

    @functools.cached_property
    def uvs(self):
        return None if self._loop_uvs is None else corners.vertex_values(self._split, self._sided.gather(self._loop_uvs))

    @functools.cached_property
    def sides(self):
        """Each vertex's side (sides.SINGLE, FRONT_SIDE or BACK_SIDE), or None when every vertex is single."""
        loop_sides = self._sided.loop_sides
        return corners.vertex_values(self._split, loop_sides) if loop_sides.any() else None

    def build_mesh(self, name):
        """A new mesh datablock with this geometry in the local space, vertices in the same order."""
        return attributes.new_mesh(name, self.positions, self.loop_vertices, self.loop_starts,
                                   self.loop_totals)

    def surface(self):
        """The baked vertices and triangles as a refine.Surface. Vertices at one point weld: the
        corner copies of a mesh vertex, and the corners of a mesh whose faces share none (a
        triangle soup, as some exporters write), so that the split stays conforming there too."""
        weld = np.unique(self.vertices, axis=0, return_inverse=True)[1].reshape(-1)
        return refine.Surface(self.vertices, self.normals, self.positions, weld, self.triangles,
                              self.material_slots, self.uvs, self.sides)

    def refined(self, surface):
        """The geometry of a refined copy (refine.refine's surface from this one's)."""
        return RefinedGeometry(surface, self._mirrored, self.faces_flipped, self.faces_doubled)


class RefinedGeometry:
    """A baked copy refined (bake/refine.py): the Geometry arrays of its surface, all triangles."""

    def __init__(self, surface, mirrored, faces_flipped, faces_doubled):
        self.vertices, self.normals, self.positions = surface.vertices, surface.normals, surface.positions
        self.triangles, self.material_slots, self.uvs = surface.triangles, surface.slots, surface.uvs
        self.sides = surface.sides
        self.faces_flipped, self.faces_doubled = faces_flipped, faces_doubled
        self._mirrored = mirrored

    def build_mesh(self, name):
        """A new mesh datablock of these triangles in the local space (the object's winding)."""
        faces = self.triangles[:, ::-1] if self._mirrored else self.triangles
        count = len(faces)
        return attributes.new_mesh(name, self.positions, faces.ravel(), 3 * np.arange(count),
                                   np.full(count, 3))



def evaluated_geometry(obj, depsgraph, shape):
    """The Geometry of the object's evaluated mesh (modifiers applied), or None."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if mesh is None:
            return None
        return Geometry(mesh, shape, materials.albedo_uv_map(obj))
    finally:
        evaluated.to_mesh_clear()


def render_differences(obj):
    """Where Cycles' renders evaluate the object's modifiers differently from the viewport's mesh
    that the bake reads and the preview draws: one phrase per modifier (none: the same geometry).
    A Subdivision's render levels are 2 by default where its viewport levels are 1, which moves a
    glossy highlight's every glint."""
    notes = []
    for modifier in getattr(obj, "modifiers", ()):
        if modifier.show_viewport != modifier.show_render:
            notes.append("%s only in %s" % (modifier.name, "renders" if modifier.show_render else "the viewport"))
        elif (modifier.show_render and modifier.type in {'SUBSURF', 'MULTIRES'}
              and modifier.render_levels != modifier.levels):
            notes.append("%s at %d levels in renders, %d in the viewport"
                         % (modifier.name, modifier.render_levels, modifier.levels))
    return notes


@dataclasses.dataclass
class Part:
    """A piece of visible geometry in world space: an object, or an instance of one (a collection
    instance, geometry nodes' instances, particles)."""
    name: str             # the object's name_full (for an instance, the instanced object's)
    instance: bool
    vertices: np.ndarray  # float64 [V, 3], world space
    triangles: np.ndarray  # [T, 3], wound outside-out also for a mirroring matrix


def _local_triangles(evaluated):
    """(positions float32 [V, 3], triangles [T, 3]) of an evaluated object's mesh, or None without
    faces."""
    mesh = evaluated.to_mesh()
    try:
        if mesh is None or len(mesh.vertices) == 0:
            return None
        triangles = attributes.read_triangles(mesh)
        return (attributes.read_positions(mesh), triangles) if len(triangles) else None
    finally:
        evaluated.to_mesh_clear()


def scene_parts(depsgraph, view_layer):
    """Every visible piece of geometry as the evaluated depsgraph instances it, as Parts: what
    occludes a bake and what a preview draws. Each instanced mesh is read once."""
    local = {}
    parts = []
    for instance in depsgraph.object_instances:
        evaluated = instance.object
        if evaluated.type not in GEOMETRY_TYPES:
            continue
        original = evaluated.original
        if not instance.is_instance and not original.visible_get(view_layer=view_layer):
            continue
        key = (evaluated.name_full, evaluated.data.as_pointer() if evaluated.data is not None else 0)
        if key not in local:
            local[key] = _local_triangles(evaluated)
        if local[key] is None:
            continue
        positions, triangles = local[key]
        matrix = np.array(instance.matrix_world, dtype=np.float64)
        if np.linalg.det(matrix[:3, :3]) < 0:
            triangles = triangles[:, ::-1].copy()
        parts.append(Part(original.name_full, bool(instance.is_instance),
                          transforms.transform_points(matrix, positions), triangles))
    return parts


def join(parts):
    """Meshes as one: (vertices float64 [V, 3], triangles int32 [T, 3]) of the (vertices,
    triangles) pairs in order, each triangle's indices moved past the vertices before it; parts
    without triangles are left out, and (None, None) is returned when none is left."""
    parts = [(vertices, triangles) for vertices, triangles in parts if len(triangles)]
    if not parts:
        return None, None
    bases = np.cumsum([0] + [len(vertices) for vertices, _ in parts[:-1]])
    return (np.concatenate([np.asarray(vertices, np.float64) for vertices, _ in parts]),
            np.concatenate([triangles + base for (_, triangles), base in zip(parts, bases)]).astype(np.int32))
