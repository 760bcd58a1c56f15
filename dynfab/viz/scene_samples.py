"""What a drawing shows of mesh obstacles, point clouds and a depth camera, in bounded size.

- A mesh's triangles placed in the world, ``x = R x_s + p`` [m]; a mesh of more than
  ``max_faces`` triangles is drawn as an evenly spaced subset of them (every ``F / max_faces``
  -th triangle in file order), so a drawing costs the same whatever the file.
- A cloud's points, an evenly spaced subset of at most ``max_points`` of them (the kept voxel
  centres are ordered by cell, so the subset spreads over the whole cloud).
- A camera's frustum: the pyramid from its optical centre ``c`` to the rectangle it sees at
  depth ``d`` along its axis, in the camera frame (x right, y up, looking along −z,
  :class:`~dynfab.perception.camera_spec.CameraSpec`) the corners

      (±a, ±b, −d),   b = d tan(fov / 2),   a = b · width / height     [m],

  rotated by the camera's ``R`` and moved to ``c``. The depth defaults to
  :data:`FRUSTUM_DEPTH`, or the distance from ``c`` to ``look_at`` if that is shorter: a
  frustum as deep as the scene would cover it; the optical axis from ``c`` to ``look_at``
  says where the camera looks.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.shapes import quaternion_matrix
from dynfab.perception.camera_spec import CameraSpec

__all__ = ["FRUSTUM_DEPTH", "MAX_DRAWN_FACES", "MAX_DRAWN_POINTS", "drawn_points", "even_subset", "frustum_corners", "frustum_depth",
           "frustum_segments", "placed_triangles"]

#: Most triangles of one mesh a plot draws.
MAX_DRAWN_FACES = 4000
#: Most points of one cloud a plot draws.
MAX_DRAWN_POINTS = 4000
#: Depth of the frustum drawn [m] (at most the distance to ``look_at``).
FRUSTUM_DEPTH = 0.3


def even_subset(count: int, most: int) -> NDArray[np.int64]:
    """Indices of an evenly spaced subset of ``range(count)``: all of them if ``count <= most``,
    else ``most`` of them, first and last included.

    Raises:
        ValueError: ``most`` is below 1.
    """
    if most < 1:
        raise ValueError(f"most must be at least 1, got {most}")
    if count <= most:
        return np.arange(count)
    return np.unique(np.linspace(0, count - 1, most).round().astype(np.int64))


def placed_triangles(mesh: Mesh, orientation: Sequence[float], position: ArrayLike,
                     max_faces: int = MAX_DRAWN_FACES) -> NDArray[np.float64]:
    """(F', 3, 3): the corners [m] of the mesh's triangles placed at ``position`` with the
    unit quaternion ``orientation`` (w, x, y, z), at most ``max_faces`` of them (module doc)."""
    faces = mesh.faces[even_subset(len(mesh.faces), max_faces)]
    corners = mesh.vertices[faces] @ quaternion_matrix(orientation).T
    return corners + np.asarray(position, dtype=float)[:3]


def drawn_points(points: ArrayLike, max_points: int = MAX_DRAWN_POINTS) -> NDArray[np.float64]:
    """(n, 3): at most ``max_points`` of the points (N, 3) [m], evenly spaced (module doc)."""
    array = np.asarray(points, dtype=float).reshape(-1, 3)
    return array[even_subset(len(array), max_points)]


def frustum_depth(camera: CameraSpec) -> float:
    """``min(FRUSTUM_DEPTH, ‖look_at − position‖)`` [m]: the depth of the frustum drawn."""
    return min(FRUSTUM_DEPTH, float(np.linalg.norm(np.subtract(camera.look_at, camera.position))))


def frustum_corners(camera: CameraSpec, depth: float | None = None) -> NDArray[np.float64]:
    """(4, 3): the far rectangle's corners in the world [m], in order top-right, top-left,
    bottom-left, bottom-right as the image shows them (module docstring)."""
    d = frustum_depth(camera) if depth is None else float(depth)
    if not (math.isfinite(d) and d > 0.0):
        raise ValueError(f"depth must be a positive finite number, got {depth}")
    b = d * math.tan(math.radians(camera.fov) / 2.0)
    a = b * camera.width / camera.height
    local = np.array([[a, b, -d], [-a, b, -d], [-a, -b, -d], [a, -b, -d]])
    return local @ camera.rotation.T + np.asarray(camera.position)


def frustum_segments(camera: CameraSpec, depth: float | None = None) -> NDArray[np.float64]:
    """(8, 2, 3): the frustum's edges [m]: four from the optical centre to the far corners,
    then the far rectangle's four sides (:func:`frustum_corners`)."""
    corners = frustum_corners(camera, depth)
    apex = np.broadcast_to(np.asarray(camera.position, dtype=float), (4, 3))
    rays = np.stack([apex, corners], axis=1)
    sides = np.stack([corners, np.roll(corners, -1, axis=0)], axis=1)
    return np.concatenate([rays, sides])
