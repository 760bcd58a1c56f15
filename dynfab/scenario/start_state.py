"""Checks of a scenario's start state before anything runs (ScenarioError, exit 2); the
joint limits are checked with the rest of the robot-dependent values, in
:func:`dynfab.scenario.schema.validate_for_robot`.

- No collision with an obstacle and no self-collision at ``t = 0``: on the collision
  meshes for a robot that has them (scenario/exact_metrics.py: URDF robots with collision
  geometry, and the built-in ``panda`` and ``boxer-panda`` on Franka's meshes when
  example-robot-data is installed), and then only on them: a start the meshes find free
  is never refused because a sphere, which reaches up to 1-2 cm out of them, overlaps an
  obstacle; else on the collision spheres (obstacle clearance
  ``d_o(R_oᵀ (p_i - c_o)) - r_i < 0`` with the exact signed distance ``d_o`` of the
  obstacle's shape, in the plane of the shape's origin for planar robots; self pairs
  ``||p_i - p_j|| - r_i - r_j < 0``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from dynfab.geometry.distance import shape_distance
from dynfab.robots.mesh_collision import MeshCollisionModel
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes
from dynfab.robots.robot import Robot
from dynfab.scenario.schema import ScenarioError

__all__ = ["check_start_collisions"]

_FIELD = "initial_state.q"


def check_start_collisions(q: ArrayLike, robot: Robot, mesh_model: MeshCollisionModel | None,
                           obstacles: Sequence[PlacedShape]) -> None:
    """Raise if the robot starts in collision with an obstacle or with itself.

    Args:
        q: Start configuration, shape (dof,).
        robot: The robot.
        mesh_model: Its mesh model, or None to check its collision spheres.
        obstacles: The obstacles, placed at ``t = 0`` by their first placement.

    Raises:
        ScenarioError: On ``initial_state.q``, naming the link and obstacle or the two links.
    """
    if mesh_model is not None:
        sweep = sweep_meshes(mesh_model, np.asarray(q, dtype=float)[None, :], obstacles)
        if sweep.obstacle_contacts:
            contact = sweep.obstacle_contacts[0]
            raise ScenarioError(_FIELD, f"the start state is in collision: link '{contact.first}' touches "
                                        f"{contact.second} (distance {contact.depth:.3g} m)")
        if sweep.self_contacts:
            contact = sweep.self_contacts[0]
            raise ScenarioError(_FIELD, f"the start state is in self-collision: links '{contact.first}' and "
                                        f"'{contact.second}' touch (distance {contact.depth:.3g} m)")
        return
    _check_start_spheres(q, robot, obstacles)


def _check_start_spheres(q: ArrayLike, robot: Robot, obstacles: Sequence[PlacedShape]) -> None:
    spheres = robot.collision_spheres
    if not spheres:
        return
    centers = np.asarray(robot.sphere_centers(np.asarray(q, dtype=float)), dtype=float)
    radii = robot.sphere_radii
    dimension = 2 if robot.planar else 3
    for obstacle in obstacles:
        placement = obstacle.placements[0]
        offsets = centers - np.array(placement.position)
        if robot.planar:
            offsets[:, 2] = 0.0
        gaps = shape_distance(obstacle.shape, offsets @ placement.rotation) - radii
        i = int(np.argmin(gaps))
        if gaps[i] < 0.0:
            raise ScenarioError(_FIELD, f"the start state is in collision: collision sphere {i} of link "
                                        f"'{spheres[i].link}' overlaps {obstacle.name} by {-gaps[i]:.3g} m")
    for i, j in robot.self_collision_pairs:
        gap = float(np.linalg.norm(centers[i, :dimension] - centers[j, :dimension]) - radii[i] - radii[j])
        if gap < 0.0:
            raise ScenarioError(_FIELD, f"the start state is in self-collision: collision spheres {i} "
                                        f"(link '{spheres[i].link}') and {j} (link '{spheres[j].link}') "
                                        f"overlap by {-gap:.3g} m")
