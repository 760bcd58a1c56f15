"""Obstacles and the depth camera drawn into a run plot's axes, in 3-D or projected on the
plane of two axes: primitives as wireframes (:mod:`dynfab.viz.shape_outlines`), meshes as
their triangles (a :class:`Poly3DCollection`, projected: a :class:`PolyCollection`), point
clouds as a scatter of their points, each at most the bounded sample of
:mod:`dynfab.viz.scene_samples`, and the camera as its frustum's eight edges and its optical
axis (dashed, to ``look_at``).

A shape is drawn where its track ends (a moving one also with the dotted path of its
origin); a cloud's points are in the world frame, placed by its track like any shape.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import PolyCollection
from mpl_toolkits.mplot3d import Axes3D
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from numpy.typing import NDArray

from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Shape, quaternion_matrix
from dynfab.perception.camera_spec import CameraSpec
from dynfab.viz.scene_samples import drawn_points, frustum_segments, placed_triangles
from dynfab.viz.shape_outlines import shape_outline

OBSTACLE_COLOR = "C3"
CLOUD_COLOR = "C4"
CAMERA_COLOR = "0.35"
#: Opacity of a mesh's triangles in 3-D, and in a projection (where they overlap).
MESH_ALPHA_3D = 0.25
MESH_ALPHA_PROJECTED = 0.08
#: Marker area of a cloud's points [pt²].
CLOUD_MARKER = 2.0

#: Labels of the legend entries, by what is drawn.
SHAPE_LABEL, MESH_LABEL, CLOUD_LABEL, CAMERA_LABEL = "shape", "mesh", "point cloud", "camera"


def draw_shape_3d(ax: Axes3D, shape: Shape, orientation: Sequence[float], centres: NDArray[np.float64]
                  ) -> NDArray[np.float64]:
    """Draw ``shape`` at the last of its ``centres`` (T, 3) [m] with the path of its origin
    if it moves; returns the points drawn (k, 3), for the axes' extent."""
    if np.ptp(centres, axis=0).max() > 0.0:
        ax.plot(*centres.T, ":", color=OBSTACLE_COLOR, linewidth=1)
    if isinstance(shape, Mesh):
        triangles = placed_triangles(shape, orientation, centres[-1])
        ax.add_collection3d(Poly3DCollection(triangles, facecolor=OBSTACLE_COLOR, edgecolor=OBSTACLE_COLOR,
                                             linewidths=0.2, alpha=MESH_ALPHA_3D, label=MESH_LABEL))
        return triangles.reshape(-1, 3)
    if isinstance(shape, PointCloud):
        points = _placed_cloud(shape, orientation, centres[-1])
        ax.scatter(points[:, 0], points[:, 1], points[:, 2], s=CLOUD_MARKER, color=CLOUD_COLOR, alpha=0.5,
                   depthshade=False, label=CLOUD_LABEL)
        return points
    lines = shape_outline(shape, orientation, centres[-1])
    for line in lines:
        ax.plot(line[:, 0], line[:, 1], line[:, 2], color=OBSTACLE_COLOR, linewidth=1, alpha=0.6)
    return np.vstack(lines)


def draw_shape_projection(ax: Axes, axes: tuple[int, int], shape: Shape, orientation: Sequence[float],
                          centres: NDArray[np.float64], labelled: bool) -> None:
    """Draw ``shape`` as :func:`draw_shape_3d` does, projected on the plane of ``axes``
    (e.g. ``(0, 1)``: the top view); ``labelled``: give it its legend entry."""
    i, j = axes
    if np.ptp(centres[:, [i, j]], axis=0).max() > 0.0:
        ax.plot(centres[:, i], centres[:, j], ":", color=OBSTACLE_COLOR, linewidth=1)
    if isinstance(shape, Mesh):
        triangles = placed_triangles(shape, orientation, centres[-1])[:, :, [i, j]]
        ax.add_collection(PolyCollection(triangles, facecolor=OBSTACLE_COLOR, edgecolor="none",
                                         alpha=MESH_ALPHA_PROJECTED, label=MESH_LABEL if labelled else None))
        ax.update_datalim(triangles.reshape(-1, 2))
        return
    if isinstance(shape, PointCloud):
        points = _placed_cloud(shape, orientation, centres[-1])
        ax.scatter(points[:, i], points[:, j], s=CLOUD_MARKER, color=CLOUD_COLOR, alpha=0.5, linewidths=0,
                   label=CLOUD_LABEL if labelled else None)
        return
    for n, line in enumerate(shape_outline(shape, orientation, centres[-1])):
        label = SHAPE_LABEL if labelled and n == 0 else None
        ax.plot(line[:, i], line[:, j], color=OBSTACLE_COLOR, linewidth=1, alpha=0.6, label=label)


def shape_label(shape: Shape) -> str:
    """The legend entry of ``shape``'s kind: a mesh, a point cloud, or a (primitive) shape."""
    return MESH_LABEL if isinstance(shape, Mesh) else CLOUD_LABEL if isinstance(shape, PointCloud) else SHAPE_LABEL


def draw_camera_3d(ax: Axes3D, camera: CameraSpec) -> NDArray[np.float64]:
    """The camera's frustum (:func:`~dynfab.viz.scene_samples.frustum_segments`), its
    optical axis and centre; returns the points drawn (6, 3)."""
    segments = frustum_segments(camera)
    for n, (start, end) in enumerate(segments):
        ax.plot(*np.stack([start, end]).T, color=CAMERA_COLOR, linewidth=1,
                label=CAMERA_LABEL if n == 0 else None)
    axis = np.array([camera.position, camera.look_at])
    ax.plot(*axis.T, "--", color=CAMERA_COLOR, linewidth=0.8)
    ax.plot(*axis[:1].T, "^", color=CAMERA_COLOR, markersize=6)
    return np.vstack([axis, segments[:4, 1]])


def draw_camera_projection(ax: Axes, axes: tuple[int, int], camera: CameraSpec, labelled: bool) -> None:
    """The camera's frustum projected on the plane of ``axes``."""
    i, j = axes
    for n, (start, end) in enumerate(frustum_segments(camera)):
        ax.plot([start[i], end[i]], [start[j], end[j]], color=CAMERA_COLOR, linewidth=1,
                label=CAMERA_LABEL if labelled and n == 0 else None)
    ax.plot([camera.position[i], camera.look_at[i]], [camera.position[j], camera.look_at[j]], "--",
            color=CAMERA_COLOR, linewidth=0.8)
    ax.plot(camera.position[i], camera.position[j], "^", color=CAMERA_COLOR, markersize=6)


def _placed_cloud(cloud: PointCloud, orientation: Sequence[float], position: NDArray[np.float64]
                  ) -> NDArray[np.float64]:
    """The drawn sample of a cloud's points placed like a shape (a scenario's: as given)."""
    return drawn_points(cloud.points) @ quaternion_matrix(orientation).T + position[:3]
