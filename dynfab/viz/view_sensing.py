"""Mesh obstacles, point clouds and the depth camera as viser scene nodes, in bounded size.

- A mesh: its vertices and triangles, at most :data:`VIEW_MAX_FACES` of them (an evenly
  spaced subset of a larger mesh's, :func:`~dynfab.viz.scene_samples.even_subset`), drawn
  from both sides (an open surface has no outside).
- A point cloud: at most :data:`VIEW_MAX_POINTS` of its points, each a square of the cloud's
  voxel edge (at least :data:`MIN_POINT_SIZE`).
- A camera: viser's frustum primitive at the camera's optical centre, turned into the OpenCV
  frame viser's cameras use (x right, y down, looking along +z): ``R_cv = R diag(1, −1, −1)``
  with ``R`` the camera's OpenGL-convention frame (:class:`~dynfab.perception.camera_spec.CameraSpec`).
  Viser's browser client draws a frustum of depth ``scale / ∛(tan²(fov/2) · aspect / 3)``
  (it normalises the pyramid's volume), so a frustum of depth ``d`` takes
  ``scale = d ∛(tan²(fov/2) · aspect / 3)``: the same pyramid as the plots draw
  (:func:`~dynfab.viz.scene_samples.frustum_segments`), with its optical axis to ``look_at``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.point_cloud import PointCloud
from dynfab.perception.camera_spec import CameraSpec
from dynfab.viz.scene_samples import drawn_points, even_subset, frustum_depth

if TYPE_CHECKING:
    import viser

__all__ = ["CAMERA_POINTS_COLOR", "MIN_POINT_SIZE", "VIEW_MAX_FACES", "VIEW_MAX_POINTS", "add_camera", "add_cloud", "add_mesh",
           "frustum_scale", "opencv_wxyz"]

#: Most triangles of one mesh sent to the browser.
VIEW_MAX_FACES = 200_000
#: Most points of one cloud sent to the browser.
VIEW_MAX_POINTS = 200_000
#: Smallest drawn point [m].
MIN_POINT_SIZE = 0.005
CLOUD_COLOR = (150, 90, 200)
CAMERA_POINTS_COLOR = (220, 40, 180)
CAMERA_COLOR = (70, 70, 70)


def add_mesh(scene: viser.SceneApi, name: str, mesh: Mesh, wxyz: np.ndarray, color: tuple[int, int, int],
             opacity: float) -> viser.MeshHandle:
    """The mesh's triangles in its frame, turned by the unit quaternion ``wxyz`` under the
    node ``name``'s parent."""
    faces = mesh.faces[even_subset(len(mesh.faces), VIEW_MAX_FACES)]
    return scene.add_mesh_simple(name, np.asarray(mesh.vertices, dtype=np.float32), faces.astype(np.uint32),
                                 color=color, opacity=opacity, wxyz=wxyz, side="double")


def add_cloud(scene: viser.SceneApi, name: str, cloud: PointCloud, wxyz: np.ndarray) -> viser.PointCloudHandle:
    """At most :data:`VIEW_MAX_POINTS` of the cloud's points, in its frame."""
    points = drawn_points(cloud.points, VIEW_MAX_POINTS).astype(np.float32)
    return scene.add_point_cloud(name, points, CLOUD_COLOR, point_size=max(cloud.voxel, MIN_POINT_SIZE),
                                 precision="float32", wxyz=wxyz)


def add_camera(scene: viser.SceneApi, name: str, camera: CameraSpec) -> viser.CameraFrustumHandle:
    """The camera's frustum (module docstring) at ``name`` and its optical axis at
    ``name + "_axis"``."""
    fov = math.radians(camera.fov)
    aspect = camera.width / camera.height
    axis = np.array([[camera.position, camera.look_at]], dtype=np.float32)
    scene.add_line_segments(f"{name}_axis", axis, CAMERA_COLOR, thickness=0.003)
    return scene.add_camera_frustum(name, fov, aspect, scale=frustum_scale(fov, aspect, frustum_depth(camera)),
                                    thickness=0.004, color=CAMERA_COLOR, wxyz=opencv_wxyz(camera),
                                    position=np.asarray(camera.position))


def frustum_scale(fov: float, aspect: float, depth: float) -> float:
    """The ``scale`` of viser's frustum of vertical field of view ``fov`` [rad] and
    ``aspect`` (width / height) whose depth is ``depth`` [m] (module docstring)."""
    return depth * (math.tan(fov / 2.0) ** 2 * aspect / 3.0) ** (1.0 / 3.0)


def opencv_wxyz(camera: CameraSpec) -> np.ndarray:
    """(4,): the quaternion (w, x, y, z) of the camera's OpenCV frame (module docstring)."""
    from viser import transforms

    return transforms.SO3.from_matrix(camera.rotation @ np.diag([1.0, -1.0, -1.0])).wxyz
