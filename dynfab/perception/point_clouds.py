"""Point clouds given to a planner at run time: downsampled, the robot filtered out, fed to
the nearest-point leaf each tick.

Each time a cloud arrives (a depth camera's, 10-30 Hz), :meth:`PointCloudFeed.update_points`
takes the raw points (N, 3) [m, world frame] and the configuration ``q`` at which they were
taken, and

1. drops NaN or infinite rows (counted), keeps one point per occupied voxel of edge ``h``
   (the voxel's centre), doubling ``h`` until at most ``max_points`` remain
   (:class:`~dynfab.geometry.point_cloud.PointCloud`, bounded memory);
2. removes the robot's own body: every kept point within ``r_i + margin`` of a robot
   collision sphere ``(p_i(q), r_i)`` (the points in the box around all the spheres, then
   one query each in a 4-D KD-tree of the spheres: :func:`~dynfab.perception.self_filter.robot_points`);
3. builds a KD-tree of what is left.

Each control tick :meth:`PointCloudFeed.write` finds, per sphere of the leaf, the nearest
kept point ``c`` within the leaf's reach and writes the point ``c + δ n``, the normal
``n = (p − c)/‖p − c‖`` and ``active`` into the leaf
(:class:`~dynfab.fabric.leaves.surface_points.NearestSurfaceAvoidance`), ``δ = h√3/2``: the
leaf's clearance ``‖p − c‖ − δ − r`` never exceeds the distance to a measured point; one
KD-tree query and two buffer evaluations (:mod:`dynfab.perception.nearest_cloud_points`).
The representation is the scenario's (:class:`~dynfab.perception.surfaces.SurfaceFeed`):
given ``q̇``, a braking leaf's reach grows by each sphere's stopping distance, and a leaf
with ``far_side`` gets a second point per sphere on another side
(:mod:`dynfab.geometry.cloud_far_side`; two more queries). Both are the caller's choice
(the leaf it builds, the ``qdot`` it passes); their cost is measured by
``bench/bench_point_clouds.py``.
An empty cloud (or one the filter empties) leaves every sphere inactive: no cloud obstacle.

The global planner reads the same kept points: pass ``feed.cloud`` to the guided fabric as
an obstacle (its checker builds a distance grid of it, :mod:`dynfab.geometry.cloud_grid`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance
from dynfab.fabric.parameters import LeafViews
from dynfab.geometry.point_cloud import DEFAULT_VOXEL, MAX_CLOUD_POINTS, PointCloud
from dynfab.perception.nearest_cloud_points import NearestCloudPoints
from dynfab.perception.self_filter import robot_points
from dynfab.robots.robot import Robot

__all__ = ["CloudUpdate", "PointCloudFeed", "RobotFilter"]

#: Default margin around the robot's spheres within which points are its own [m].
ROBOT_MARGIN = 0.02


@dataclass(frozen=True)
class CloudUpdate:
    """What became of one cloud.

    Attributes:
        received: Rows given.
        dropped: Rows dropped for NaN or infinite coordinates.
        on_robot: Kept points removed as the robot's own body.
        kept: Points the planner sees.
        voxel: The voxel edge used [m] (larger than asked if the cap was reached).
    """

    received: int
    dropped: int
    on_robot: int
    kept: int
    voxel: float


class RobotFilter:
    """Removes the points within ``r_i + margin`` of the robot's collision spheres at ``q``.

    Attributes:
        margin: Added to every sphere's radius [m].
    """

    def __init__(self, robot: Robot, margin: float = ROBOT_MARGIN) -> None:
        if not margin >= 0.0:
            raise ValueError(f"margin must be >= 0, got {margin}")
        self.margin = margin
        q = ca.SX.sym("q", robot.kinematics.dof)
        self._centres = ca.Function("sphere_centres", [q], [robot.sphere_centers(q)])
        self._radii = np.asarray(robot.sphere_radii, dtype=float) + margin

    def __call__(self, cloud: PointCloud, q: ArrayLike) -> tuple[PointCloud, int]:
        """``cloud`` without the robot's points at ``q``, and how many were removed."""
        if cloud.empty or len(self._radii) == 0:
            return cloud, 0
        centres = np.asarray(self._centres(np.asarray(q, dtype=float)), dtype=float).reshape(-1, 3)
        robot = robot_points(cloud.points, centres, self._radii)
        hits = int(np.count_nonzero(robot))
        if hits == 0:
            return cloud, 0
        return PointCloud(cloud.points[~robot], cloud.voxel, cloud.dropped, cloud.source), hits


class PointCloudFeed:
    """Gives a planner's nearest-point leaf the latest point cloud (module docstring);
    ``backend`` (``"c"`` or ``"vm"``, default :func:`~dynfab.fabric.backends.default_backend`)
    evaluates the per-tick functions.

    Attributes:
        voxel: The voxel edge asked for [m].
        max_points: Most points kept.
        cloud: The points the planner sees (empty until the first update).
        nearest: What writes the leaf each tick (its ``index``: each sphere's nearest point).
    """

    def __init__(self, robot: Robot, leaf: NearestSurfaceAvoidance, views: LeafViews, voxel: float = DEFAULT_VOXEL,
                 max_points: int = MAX_CLOUD_POINTS, margin: float = ROBOT_MARGIN, backend: str | None = None) -> None:
        self.voxel = voxel
        self.max_points = max_points
        self.cloud = PointCloud(np.zeros((0, 3)), voxel)
        self._filter = RobotFilter(robot, margin)
        self.nearest = NearestCloudPoints(robot, leaf, views, backend)

    def update_points(self, points: ArrayLike, q: ArrayLike | None) -> CloudUpdate:
        """Replace the cloud by ``points`` (N, 3) [m, world frame] taken at configuration
        ``q`` (None: nothing filtered, the cloud holds no part of the robot).

        Raises:
            ValueError: ``points`` is not an (N, 3) array of numbers.
        """
        raw = np.asarray(points)
        if raw.size == 0:
            raw = raw.reshape(0, 3)
        cloud = PointCloud.from_points(raw, self.voxel, self.max_points, source="update_points")
        on_robot = 0
        if q is not None:
            cloud, on_robot = self._filter(cloud, q)
        self.cloud = cloud
        return CloudUpdate(len(raw), cloud.dropped, on_robot, len(cloud.points), cloud.voxel)

    def write(self, q: NDArray[np.float64], qdot: NDArray[np.float64] | None = None) -> None:
        """Write the leaf's nearest points for configuration ``q`` (every tick); with a
        braking leaf and ``qdot`` [rad/s] given, each sphere's reach grown by its stopping
        distance (:mod:`dynfab.perception.nearest_cloud_points`)."""
        self.nearest.write(q, self.cloud, qdot)
