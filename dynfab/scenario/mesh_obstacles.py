"""A scenario's mesh obstacles and point clouds for the fabric: the nearest-point leaf they
need and where they are at each tick (:mod:`dynfab.perception.surfaces` finds the points)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Placement
from dynfab.motion.references import References
from dynfab.perception.surfaces import PlacedMesh, SurfaceFeed
from dynfab.robots.robot import Robot
from dynfab.scenario.schema import ObstacleSpec

__all__ = ["MeshObstacles", "surface_leaf"]


@dataclass(frozen=True)
class MeshObstacles:
    """The mesh obstacles of a scenario and the feed that writes their nearest points.

    Attributes:
        indices: Their indices among the scenario's obstacles.
        obstacles: The obstacles.
        feed: Writes the planner's nearest-point leaf.
        with_velocity: Pass the meshes' velocities (dynamic fabrics); a static fabric sees
            positions only, as the paper's static-fabric baseline does.
        clouds: The scenario's point clouds (static).
        cloud_indices: Their indices among the scenario's obstacles (empty: not known, as
            for a camera's cloud).
        allowances: How far [m] the leaf lets spheres enter each mesh (in ``indices``
            order), then each cloud: guidance near a grasp goal writes them in place
            (:class:`SurfaceAllowance`); zeros at first.
    """

    indices: tuple[int, ...]
    obstacles: tuple[ObstacleSpec, ...]
    feed: SurfaceFeed
    with_velocity: bool
    clouds: tuple[PointCloud, ...] = ()
    cloud_indices: tuple[int, ...] = ()
    allowances: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0), compare=False)

    def __post_init__(self) -> None:
        if len(self.allowances) != len(self.indices) + len(self.clouds):
            object.__setattr__(self, "allowances", np.zeros(len(self.indices) + len(self.clouds)))

    def write(self, t: float, q: np.ndarray, references: References, qdot: np.ndarray | None = None) -> None:
        """Write the nearest surface point of each robot sphere at time ``t`` [s] (``qdot``
        [rad/s]: a braking leaf reaches farther into the meshes and clouds, :meth:`SurfaceFeed.braking_reach`)."""
        placed = []
        for k, obstacle in zip(self.indices, self.obstacles):
            point = references.obstacles[k].evaluate(t)
            velocity = tuple(float(v) for v in point.velocity) if self.with_velocity else (0.0, 0.0, 0.0)
            assert obstacle.mesh is not None
            placed.append(PlacedMesh(obstacle.mesh, Placement(tuple(point.position), obstacle.orientation),
                                     velocity, float(self.allowances[len(placed)])))  # type: ignore[arg-type]
        self.feed.write(q, placed, self.clouds, self.allowances[len(placed):], qdot)

    def surface_of(self, obstacle_index: int) -> int:
        """Where the scenario's obstacle ``obstacle_index`` (a mesh or a point cloud) is in
        :attr:`allowances`.

        Raises:
            ValueError: It is neither.
        """
        if obstacle_index in self.indices:
            return self.indices.index(obstacle_index)
        if obstacle_index in self.cloud_indices:
            return len(self.indices) + self.cloud_indices.index(obstacle_index)
        raise ValueError(f"obstacles[{obstacle_index}] is neither a mesh nor a point cloud of this feed")


def surface_leaf(robot: Robot, obstacles: Sequence[ObstacleSpec], barrier: Barrier,
                 perceived: bool = False) -> NearestSurfaceAvoidance | None:
    """The nearest-point leaf of a scenario with mesh obstacles or point clouds, or whose
    scene is ``perceived`` by a camera (on every sphere a joint moves; with a point cloud
    obstacle, a far-side slot each, :mod:`dynfab.geometry.cloud_far_side`); None otherwise."""
    if not perceived and not any(obstacle.type in ("mesh", "points") for obstacle in obstacles):
        return None
    clouds = any(obstacle.type == "points" for obstacle in obstacles)   # a camera's feed writes one slot a sphere
    return NearestSurfaceAvoidance(spheres=moving_spheres(robot), barrier=barrier, far_side=clouds and not perceived)
