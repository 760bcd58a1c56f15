"""Checks of a scenario's start state before anything runs (ScenarioError, exit 2).

- Every joint within its limits: ``lower - JOINT_LIMIT_TOLERANCE <= q_i <= upper + ...``.
- No collision with an obstacle and no self-collision at ``t = 0``: on the collision
  meshes for a robot that has them (scenario/exact_metrics.py), else on the collision
  spheres (obstacle clearance ``||p_i - p_o|| - r_i - r_o < 0``, in the xy-plane for
  planar robots; self pairs ``||p_i - p_j|| - r_i - r_j < 0``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.robots.mesh_collision import MeshCollisionModel
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes
from dynfab.robots.robot import Robot
from dynfab.scenario.schema import ScenarioError

__all__ = ["JOINT_LIMIT_TOLERANCE", "check_joint_limits", "check_start_collisions"]

#: A start value this far beyond a limit is still accepted (round-off in files) [rad or m].
JOINT_LIMIT_TOLERANCE = 1e-9

_FIELD = "initial_state.q"


def check_joint_limits(q: ArrayLike, robot: Robot) -> None:
    """Raise if a start joint value is outside its limits.

    Raises:
        ScenarioError: ``initial_state.q[3] (elbow_joint): 3.5 is outside [-3.14159, 3.14159]``.
    """
    kinematics = robot.kinematics
    for i, value in enumerate(np.asarray(q, dtype=float)):
        lower, upper = kinematics.lower[i], kinematics.upper[i]
        if not lower - JOINT_LIMIT_TOLERANCE <= value <= upper + JOINT_LIMIT_TOLERANCE:
            raise ScenarioError(f"{_FIELD}[{i}] ({kinematics.joint_names[i]})",
                                f"{value:.6g} is outside [{lower:.6g}, {upper:.6g}]")


def check_start_collisions(q: ArrayLike, robot: Robot, mesh_model: MeshCollisionModel | None,
                           obstacles: Sequence[PlacedShape], obstacle_centers: NDArray[np.float64],
                           obstacle_radii: NDArray[np.float64]) -> None:
    """Raise if the robot starts in collision with an obstacle or with itself.

    Args:
        q: Start configuration, shape (dof,).
        robot: The robot.
        mesh_model: Its mesh model, or None to check its collision spheres.
        obstacles: The obstacles placed at ``t = 0`` (used with meshes).
        obstacle_centers: Obstacle centres at ``t = 0``, shape (m, 2 or 3) (spheres).
        obstacle_radii: Their radii, shape (m,) (spheres).

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
    _check_start_spheres(q, robot, obstacle_centers, obstacle_radii)


def _check_start_spheres(q: ArrayLike, robot: Robot, obstacle_centers: NDArray[np.float64],
                         obstacle_radii: NDArray[np.float64]) -> None:
    spheres = robot.collision_spheres
    if not spheres:
        return
    centers = np.asarray(robot.sphere_centers(np.asarray(q, dtype=float)), dtype=float)
    radii = robot.sphere_radii
    dimension = 2 if robot.planar else 3
    if len(obstacle_radii):
        others = np.asarray(obstacle_centers, dtype=float)[:, :dimension]
        gaps = (np.linalg.norm(centers[:, None, :dimension] - others[None], axis=-1)
                - radii[:, None] - np.asarray(obstacle_radii)[None, :])
        i, k = np.unravel_index(int(np.argmin(gaps)), gaps.shape)
        if gaps[i, k] < 0.0:
            raise ScenarioError(_FIELD, f"the start state is in collision: collision sphere {i} of link "
                                        f"'{spheres[i].link}' overlaps obstacles[{k}] by {-gaps[i, k]:.3g} m")
    for i, j in robot.self_collision_pairs:
        gap = float(np.linalg.norm(centers[i, :dimension] - centers[j, :dimension]) - radii[i] - radii[j])
        if gap < 0.0:
            raise ScenarioError(_FIELD, f"the start state is in self-collision: collision spheres {i} "
                                        f"(link '{spheres[i].link}') and {j} (link '{spheres[j].link}') "
                                        f"overlap by {-gap:.3g} m")
