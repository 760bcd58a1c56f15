"""A depth camera's frames into a planner's nearest-point leaf, with velocities.

Each control tick, the frames that the camera (:class:`~dynfab.perception.depth_camera.DepthCamera`)
has released by then (``delay`` after they were taken) replace the cloud of a
:class:`~dynfab.perception.point_clouds.PointCloudFeed`: voxel-downsampled, the robot
already filtered out at the frame's configuration. The frame's points and which of them
arrived (came nearer since the previous frame) go through the
:class:`~dynfab.perception.motion_tracks.ClusterTracker`, which follows only the clusters
holding arrived points (nothing where nothing moves); a kept point inside a tracked cluster's
ball (:meth:`~dynfab.perception.motion_tracks.ClusterTracker.velocity_at`) has its velocity
estimate, any other 0. Then, as every tick, the feed writes the leaf's nearest points for the robot's
configuration ``q``, each moved to where its velocity estimate ``v`` puts it now: a frame
taken at ``t_f`` is at least ``delay`` old, so the point written is

    c(t) = c(t_f) + v (t − t_f)                                   [m]

(a ball at 0.5 m/s seen 33-66 ms late would otherwise be 1.7-3.3 cm behind). For a dynamic
fabric ``v`` is written as the point's velocity too, so the dynamic pullback acts on what
moves, as it does for tracked obstacles; a static fabric is given positions only.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance
from dynfab.fabric.parameters import LeafViews
from dynfab.geometry.point_cloud import PointCloud
from dynfab.perception.depth_camera import CameraFrame, DepthCamera, DepthRender
from dynfab.perception.motion_tracks import ClusterTracker
from dynfab.perception.point_clouds import PointCloudFeed
from dynfab.robots.robot import Robot

__all__ = ["CameraFeed"]


class CameraFeed:
    """Feeds one planner's nearest-point leaf from a depth camera (module docstring).

    Attributes:
        camera: The camera.
        tracker: The velocity estimator of the kept points.
        frames: Frames received so far.
        latest: The newest frame received, or None.

    ``backend``: how the per-tick nearest-point writer is evaluated (``"c"`` or ``"vm"``, as
    the planner it feeds; default :func:`~dynfab.fabric.backends.default_backend`).
    """

    def __init__(self, robot: Robot, camera: DepthCamera, tracker: ClusterTracker | None = None,
                 backend: str | None = None) -> None:
        self.camera = camera
        self._backend = backend
        self.tracker = tracker or ClusterTracker()
        self.frames = 0
        self.latest: CameraFrame | None = None
        self._robot = robot
        self._feed: PointCloudFeed | None = None
        self._leaf: NearestSurfaceAvoidance | None = None
        self._views: LeafViews | None = None

    @property
    def cloud(self) -> PointCloud | None:
        """The points the planner sees (None before a leaf is attached)."""
        return None if self._feed is None else self._feed.cloud

    def attach(self, leaf: NearestSurfaceAvoidance, views: LeafViews) -> None:
        """Write ``leaf`` (of a planner whose parameters hold ``views``) from now on; the
        latest cloud carries over.

        Raises:
            ValueError: ``leaf`` has far-side slots (the camera's velocities are estimated at
                each sphere's nearest point only).
        """
        if leaf is self._leaf and views is self._views:
            return
        if leaf.far_side:
            raise ValueError(f"leaf {leaf.name!r}: a camera's feed writes one slot a sphere (its velocity "
                             "estimate is per nearest point); build the leaf with far_side=False")
        self._leaf, self._views = leaf, views
        self._feed = PointCloudFeed(self._robot, leaf, views, backend=self._backend)
        if self.latest is not None:
            self._feed.update_points(self.latest.points, None)

    def capture(self, t: float, render: DepthRender, q: NDArray[np.float64]) -> None:
        """Let the camera take a frame at ``t`` [s] if one is due (robot at ``q``)."""
        self.camera.tick(t, render, q)

    def write(self, t: float, q: NDArray[np.float64], with_velocity: bool) -> bool:
        """Take the frames released by ``t`` [s], then write the leaf for ``q``; whether a new
        cloud arrived.

        Raises:
            RuntimeError: No leaf attached.
        """
        if self._feed is None or self._views is None:
            raise RuntimeError("CameraFeed.write before attach: no leaf to write")
        frames = self.camera.release(t)
        for frame in frames:
            self._feed.update_points(frame.points, None)  # the camera filtered the robot already
            self.tracker.update(frame.time, frame.points, frame.arrived)
            self.latest = frame
        self.frames += len(frames)
        self._feed.write(q)
        if self.latest is None or self._feed.cloud.empty:
            return bool(frames)
        active = np.asarray(self._views["active"], dtype=float) > 0.5
        velocities = np.zeros((len(active), 3))
        if active.any():
            velocities[active] = self.tracker.velocity_at(self._feed.cloud.points[self._feed.nearest.index[active]])
            points = np.asarray(self._views["points"]).reshape(-1, 3).copy()
            points[active] += velocities[active] * (t - self.latest.time)
            self._views["points"] = points
        if with_velocity:
            self._views["velocities"] = velocities
        return bool(frames)
