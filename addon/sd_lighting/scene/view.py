"""A camera to draw and shade for: the viewport's or a camera object's world-to-clip matrix and
eye (drawing.py draws with it; bake/prepare.py sizes an object's triangles on screen with it)."""

import numpy as np


class View:
    """A camera for drawing: world-to-clip matrix and the eye (position, or direction to an
    orthographic viewer with w = 0)."""

    def __init__(self, view_projection, camera):
        self.view_projection = np.asarray(view_projection, dtype=np.float64)
        self.camera = np.asarray(camera, dtype=np.float64)

    @classmethod
    def from_region(cls, region_3d):
        inverse = region_3d.view_matrix.inverted()
        if region_3d.is_perspective:
            camera = tuple(inverse.translation) + (1.0,)
        else:
            camera = tuple(inverse.col[2][:3]) + (0.0,)
        return cls(region_3d.perspective_matrix, camera)

    @classmethod
    def from_camera(cls, camera_object, depsgraph, width, height, scene=None):
        projection = camera_object.calc_matrix_camera(
            depsgraph, x=width, y=height,
            scale_x=scene.render.pixel_aspect_x if scene else 1.0,
            scale_y=scene.render.pixel_aspect_y if scene else 1.0)
        world = camera_object.matrix_world
        view = world.inverted()
        if camera_object.data.type == 'ORTHO':
            camera = tuple(world.col[2][:3]) + (0.0,)
        else:
            camera = tuple(world.translation) + (1.0,)
        return cls(projection @ view, camera)

    def view_directions(self, world_positions, world_to_local):
        """Unit directions to the eye, per point, in a local space (float64, as the CPU does)."""
        if self.camera[3] > 0.5:
            to_eye = self.camera[:3] - world_positions
        else:
            to_eye = np.broadcast_to(self.camera[:3], world_positions.shape)
        to_eye = to_eye / np.linalg.norm(to_eye, axis=1)[:, None]
        local = to_eye @ world_to_local.T
        return local / np.linalg.norm(local, axis=1)[:, None]
