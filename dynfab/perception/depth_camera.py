"""A depth camera as the planner receives it: frames at ``rate``, noisy, the robot removed,
``delay`` late.

Each control tick the loop calls :meth:`DepthCamera.tick` with the simulated time ``t``, a
function that renders the current depth image and the robot's configuration ``q``. A frame is
taken at ``t = 0`` and then whenever ``t`` reaches the next multiple of the period ``1/rate``
(sim time; a tick later than that takes it, and the schedule keeps its multiples, so the mean
rate is ``rate`` whenever the ticks are faster). A frame is

0. with a ``workspace`` ball (:class:`~dynfab.perception.workspace.Workspace`, e.g.
   :func:`~dynfab.perception.workspace.robot_workspace`: the robot's reach plus the fabric's
   range), only the pixels whose points lie in it are kept (a per-pixel depth range computed
   once, :meth:`~dynfab.perception.depth_image.DepthProjector.ball_depths`): what no robot
   sphere can come near costs nothing further; none by default;
1. the rendered depth ``d`` [m] per pixel, plus Gaussian noise ``d + σ ε``, ``ε ~ N(0, 1)``
   (seeded) on the pixels with a return (and in the workspace): the simulated sensor's noise
   (:meth:`DepthCamera.sensed`, applied by :meth:`DepthCamera.tick`; :meth:`DepthCamera.frame`
   takes an image as a sensor gives it, noise included, and does steps 0 and 2-4);
2. back-projected (:class:`~dynfab.perception.depth_image.DepthProjector`);
3. without the robot's pixels: those within ``r_i + margin`` of a collision sphere at the
   configuration ``q`` of the frame's time (:func:`~dynfab.perception.self_filter.robot_pixels`);
4. each point marked if its pixel *arrived* since the previous frame (something came nearer:
   :class:`~dynfab.perception.depth_changes.DepthChanges`, the velocity tracker's seeds);
5. buffered as ``(time, points)`` and released by :meth:`DepthCamera.release` once
   ``t >= time + delay``.

The renderer is any ``() -> depth image`` (H, W) [m] with ``inf`` where nothing was hit:
MuJoCo's in :class:`dynfab.sim.depth_render.MujocoDepthRenderer`, or a real sensor's.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.perception.camera_spec import CameraSpec
from dynfab.perception.depth_changes import DepthChanges
from dynfab.perception.depth_image import DepthProjector
from dynfab.perception.self_filter import robot_pixels
from dynfab.perception.workspace import Workspace
from dynfab.robots.robot import Robot

__all__ = ["ROBOT_MARGIN", "CameraFrame", "DepthCamera"]

#: Default margin around the robot's collision spheres within which points are its own [m].
ROBOT_MARGIN = 0.02
#: Times closer than this count as equal [s] (sim times are sums of periods).
_EPSILON = 1e-9

DepthRender = Callable[[], NDArray[np.floating]]
"""``() -> depth (height, width) [m]``, ``inf`` where nothing was hit."""


@dataclass(frozen=True)
class CameraFrame:
    """One frame's points.

    Attributes:
        time: When it was taken [s] (sim time).
        points: (N, 3) world points [m] without the robot's, read-only.
        robot_points: Pixels removed as the robot's.
        configuration: The robot's configuration at ``time`` (read-only).
        arrived: Per point, whether its pixel arrived since the previous frame (N,) (read-only).
    """

    time: float
    points: NDArray[np.float64]
    robot_points: int
    configuration: NDArray[np.float64]
    arrived: NDArray[np.bool_]


class DepthCamera:
    """Frames of one depth camera (module docstring).

    Attributes:
        spec: The camera.
        projector: Its back-projection.
        margin: Added to every sphere's radius when filtering the robot [m].

    ``workspace``: keep only the points in this ball (step 0); None keeps every point.
    """

    def __init__(self, spec: CameraSpec, robot: Robot, margin: float = ROBOT_MARGIN, seed: int = 0,
                 workspace: Workspace | None = None) -> None:
        if not margin >= 0.0:
            raise ValueError(f"margin must be >= 0, got {margin}")
        self.spec = spec
        self.projector = DepthProjector(spec)
        self.margin = margin
        self._rng = np.random.default_rng(seed)
        q = ca.SX.sym("q", robot.kinematics.dof)
        self._centres = ca.Function("sphere_centres", [q], [robot.sphere_centers(q)])
        self._radii = np.asarray(robot.sphere_radii, dtype=float) + margin
        links = [sphere.link for sphere in robot.collision_spheres]
        self._groups = [np.flatnonzero([link == name for link in links]) for name in dict.fromkeys(links)]
        self._depth_range = None if workspace is None else self.projector.ball_depths(
            np.array(workspace.centre), workspace.radius)
        self._changes = DepthChanges(spec.noise)
        self._next = 0.0
        self._buffer: deque[CameraFrame] = deque()

    def due(self, t: float) -> bool:
        """Whether a frame is to be taken at time ``t`` [s]."""
        return t >= self._next - _EPSILON

    def tick(self, t: float, render: DepthRender, q: ArrayLike) -> CameraFrame | None:
        """Take a frame at ``t`` [s] if one is due (rendering it then only) and buffer it;
        the frame taken, or None."""
        if not self.due(t):
            return None
        while self._next <= t + _EPSILON:
            self._next += self.spec.period
        frame = self.frame(t, self.sensed(render()), q)
        self._buffer.append(frame)
        return frame

    def release(self, t: float) -> list[CameraFrame]:
        """The buffered frames that are ``delay`` old at ``t`` [s], oldest first (each once)."""
        released = []
        while self._buffer and self._buffer[0].time + self.spec.delay <= t + _EPSILON:
            released.append(self._buffer.popleft())
        return released

    def sensed(self, depth: NDArray[np.floating]) -> NDArray[np.floating]:
        """The image a sensor of noise ``σ = spec.noise`` reports for the true depth image
        (H, W) [m]: ``d + σ ε`` (``ε ~ N(0, 1)``, float32, from this camera's seeded stream) on
        the pixels with a return in the workspace, the others as they were; ``depth`` itself
        when ``σ = 0``. The simulation's sensor model (step 1): a real sensor's image already
        has its noise and goes to :meth:`frame` as it is.

        Raises:
            ValueError: ``depth`` is not (height, width).
        """
        depth = np.asarray(depth)
        if self.spec.noise == 0.0:
            return depth
        returns = self._returns(depth)
        noisy = depth.astype(np.float32, copy=True)
        noisy[returns] += self._rng.standard_normal(int(returns.sum()), dtype=np.float32) * self.spec.noise
        return noisy

    def _returns(self, depth: NDArray[np.floating]) -> NDArray[np.bool_]:
        """Pixels of ``depth`` (checked to be (H, W)) with a return, in the workspace if there is one."""
        self.projector.check(depth)
        returns = DepthProjector.returns(depth)
        if self._depth_range is not None:
            near, far = self._depth_range
            returns &= (depth >= near) & (depth <= far)
        return returns

    def frame(self, t: float, depth: NDArray[np.floating], q: ArrayLike) -> CameraFrame:
        """Steps 0 and 2-4 of the module docstring on one depth image (H, W) [m] as the sensor
        gives it (its noise included: :meth:`sensed` simulates it), taken at ``t`` with the
        robot at ``q``.

        Raises:
            ValueError: ``depth`` is not (height, width).
        """
        depth = np.asarray(depth)
        returns = self._returns(depth)
        configuration = np.array(q, dtype=float).reshape(-1)
        centres = np.asarray(self._centres(configuration), dtype=float).reshape(-1, 3)
        robot = robot_pixels(depth, returns, self.projector, centres, self._radii, self._groups)
        kept = returns & ~robot
        points = self.projector.points(depth, kept)
        arrived = np.compress(kept.reshape(-1), self._changes.arrived(depth, returns, kept).reshape(-1))
        for array in (points, configuration, arrived):
            array.setflags(write=False)
        return CameraFrame(float(t), points, int(robot.sum()), configuration, arrived)
