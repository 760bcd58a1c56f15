"""Is a goal configuration free on the robot's collision meshes? Guidance's last resort for
goals millimetres from the scene, which the spheres refuse.

The configuration checker (:mod:`dynfab.motion.configuration_checker`) sees the robot's
collision spheres, which stick out of its meshes by up to 1-2 cm at the hand, against a
lower bound of a mesh's or a cloud's distance (its grid, up to ``h√3`` below): at a goal a
few millimetres from a mesh it reads −7 to −27 mm where the meshes are apart. This check
measures the robot's meshes (:class:`~dynfab.robots.mesh_collision.MeshCollisionModel`)
against the exact obstacles with coal (:func:`~dynfab.robots.mesh_sweep.sweep_meshes`):

    free(q) ⇔ min_{l, k} d(link_l(q), obstacle_k) − δ ≥ margin   and   no checked link pair touches

with ``δ`` the largest voxel half-diagonal of the point clouds among the obstacles (a cloud's
kept points stand for raw points within ``δ`` of them; 0 without clouds) [m]. A goal it
accepts and the spheres refuse is then planned as a blocked joint goal: escaped to a free
configuration nearby and approached slowly (:mod:`dynfab.motion.joint_planning`).

The segment of every escaped endpoint (a goal's approach, a start's way out) among meshes
and point clouds, and of one free on the meshes anywhere, is checked here
(:meth:`MeshGoalCheck.segment_free`): on the meshes it goes no deeper than the endpoint,
``c_obs ≥ min(floor, c_obs(endpoint))`` at every configuration. The spheres' own test ("no
deeper than the goal" on the grid) lets it go deeper than the goal truly is, the grid
reading up to ``h√3`` low at the goal and exactly elsewhere: a finger's mesh touched a shelf
on such an approach (training table_bars/0004, seed 0). Where the meshes find the endpoint
free this test replaces the spheres': among shapes at once, among meshes once both tests
together found no escape, never among point clouds
(:meth:`~dynfab.motion.guidance.JointGuidance._endpoint_tests`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.point_cloud import PointCloud
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.link_meshes import LinkMeshError
from dynfab.robots.mesh_collision import MeshCollisionModel, mesh_collision_model
from dynfab.robots.robot import Robot
from dynfab.robots.mesh_sweep import PlacedShape, meshes_clear, sweep_meshes

__all__ = ["MeshGoalCheck", "robot_mesh_model"]


class MeshGoalCheck:
    """``q ↦ free(q)`` of the module docstring.

    Attributes:
        model: the robot's mesh model.
        margin: clearance the meshes must keep from every obstacle [m].
    """

    def __init__(self, model: MeshCollisionModel, margin: float) -> None:
        if not np.isfinite(margin) or margin < 0.0:
            raise ValueError(f"margin: must be finite and >= 0, got {margin}")
        self.model = model
        self.margin = margin
        self._shapes: tuple[PlacedShape, ...] = ()
        self._lowering = 0.0

    def set_obstacles(self, obstacles: Sequence[PlacedObstacle]) -> None:
        """Check against ``obstacles`` from now on."""
        self._shapes = tuple(PlacedShape(f"obstacles[{k}]", o.shape, (o.placement,)) for k, o in enumerate(obstacles))
        self._lowering = max((o.shape.lowering for o in obstacles if isinstance(o.shape, PointCloud)), default=0.0)

    def clearance(self, q: NDArray[np.float64]) -> tuple[float, float]:
        """``(c_obs, c_self)`` on the meshes at ``q`` [m]: the least obstacle distance less
        ``δ``, and the least distance of the checked link pairs (``inf`` where nothing is
        checked); of a stack of configurations (k, n), the least over them."""
        sweep = sweep_meshes(self.model, np.atleast_2d(np.asarray(q, dtype=float)), self._shapes)
        obstacle = np.inf if sweep.clearance is None else sweep.clearance - self._lowering
        itself = np.inf if sweep.min_self_distance is None else sweep.min_self_distance
        return float(obstacle), float(itself)

    def free(self, q: NDArray[np.float64], floor: float | None = None) -> bool:
        """Whether ``q`` (or every row of a stack) is free on the meshes (module docstring),
        its obstacle clearance at least ``floor`` [m] (default :attr:`margin`)."""
        obstacle, itself = self.clearance(q)
        return obstacle >= (self.margin if floor is None else floor) and itself > 0.0

    def segment_free(self, a: NDArray[np.float64], b: NDArray[np.float64], step: float,
                     floor: float | None = None) -> bool:
        """Whether every configuration of the straight segment from ``a`` to ``b``, at most
        ``step`` apart [rad] (both ends included), keeps ``c_obs ≥ floor`` [m] (default
        :attr:`margin`) with no checked link pair touching."""
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        line = a + np.linspace(0.0, 1.0, count + 1)[:, None] * (b - a)
        least = (self.margin if floor is None else floor) + self._lowering
        return meshes_clear(self.model, line, self._shapes, least)


@lru_cache(maxsize=4)
def robot_mesh_model(robot: Robot) -> MeshCollisionModel | None:
    """``robot``'s collision meshes (:func:`~dynfab.robots.mesh_collision.mesh_collision_model`),
    read once per robot (60-110 ms for the Panda: every run's guidance asks for them at its
    first blocked goal); None without meshes (or if they cannot be read). Queries leave the
    model unchanged, so guidance instances and their worker threads share it."""
    try:
        return mesh_collision_model(robot.kinematics, robot.default_q, builtin_collision_meshes(robot))
    except LinkMeshError:
        return None
