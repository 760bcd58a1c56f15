"""Collision metrics of URDF robots measured on their collision meshes (docs/design.md section 6).

Which robots: a robot that is not planar and has at least one link with ``<collision>``
geometry (a URDF robot as it ships), and the built-in ``panda`` and ``boxer-panda``
(:mod:`dynfab.robots.builtin_meshes`): Franka's collision meshes from example-robot-data
(links 0-7, the hand, the fingers at the scenario's opening; same frames) and, for
``boxer-panda``, Clearpath's collision box of the Boxer's body. example-robot-data is in
the ``robots`` / ``test`` extras, not the core: without it these two keep the sphere
figures, as do the planar built-in robots (``point``, ``boxer``) and URDFs without collision
geometry: ``clearance`` is the sphere clearance and ``self_collision`` /
``min_self_distance`` are None.

For a mesh robot the run's metrics become

- ``clearance``: min over every sample, link and obstacle of the mesh-to-shape distance
  [m] (negative: the penetration depth of the link's convex hull); to a point cloud, the
  signed distance to its kept points (a point inside a link: minus its distance to the
  link's surface, :mod:`dynfab.geometry.cloud_collision`) less the voxel half-diagonal
  ``δ``, a lower bound of the distance to the measured points;
- ``collision``: some link touched an obstacle (distance <= 0);
- ``self_collision``: some checked link pair touched
  (:mod:`dynfab.robots.mesh_collision` says which pairs are checked);
- ``min_self_distance``: min over samples and checked pairs [m];
- ``success``: goal reached, no collision and no self-collision;
- ``sphere_clearance``: the collision spheres' figure, as before.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.shapes import Placement, PointCloud
from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.link_meshes import LinkMeshError
from dynfab.robots.mesh_collision import MeshCollisionModel, mesh_collision_model
from dynfab.robots.mesh_sweep import MeshSweep, PlacedShape
from dynfab.robots.robot import Robot
from dynfab.scenario.metrics import Metrics
from dynfab.scenario.schema import ObstacleSpec, ScenarioError

__all__ = ["mesh_model_for", "obstacle_shapes", "with_mesh_metrics"]


def mesh_model_for(robot: Robot) -> MeshCollisionModel | None:
    """The robot's mesh model, or None if its metrics stay sphere-based (module doc).

    Raises:
        ScenarioError: ``robot.urdf`` names a collision mesh that is missing or unreadable.
    """
    if robot.planar:
        return None
    try:
        return mesh_collision_model(robot.kinematics, robot.default_q, builtin_collision_meshes(robot))
    except LinkMeshError as error:
        raise ScenarioError("robot.urdf", str(error)) from error


def obstacle_shapes(obstacles: Sequence[ObstacleSpec], centers: NDArray[np.float64],
                    lowered: bool = False) -> list[PlacedShape]:
    """The scenario's obstacles as shapes placed at each sample.

    Args:
        obstacles: The scenario's obstacles.
        centers: Their centres (a plane: its point) at each sample, shape (T, m, 3) [m].
        lowered: a point cloud's distances less its ``δ`` (a run's metrics: a lower bound of
            the distance to the measured points); else to its kept points (the start
            check, which refuses only a start that touches one).
    """
    shapes = []
    for k, obstacle in enumerate(obstacles):
        track = centers[:1, k] if obstacle.trajectory is None else centers[:, k]
        lowering = obstacle.shape.lowering if lowered and isinstance(obstacle.shape, PointCloud) else 0.0
        shapes.append(PlacedShape(obstacle.name(k), obstacle.shape,
                                  tuple(Placement(tuple(c), obstacle.orientation) for c in track), lowering))
    return shapes


def with_mesh_metrics(metrics: Metrics, sweep: MeshSweep) -> Metrics:
    """``metrics`` with the collision figures of the mesh sweep (module doc)."""
    collision = bool(sweep.obstacle_contacts)
    self_collision = bool(sweep.self_contacts)
    return dataclasses.replace(
        metrics, collision=collision, clearance=sweep.clearance, self_collision=self_collision,
        min_self_distance=sweep.min_self_distance,
        success=metrics.goal_reached and not collision and not self_collision)
