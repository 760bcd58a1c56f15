"""Franka's own Panda, the ground truth of the benchmark: example-robot-data's description
with its collision meshes, the 7 arm joints active and the fingers open 0.04 m each (the
open hand of MBM's grasp goals).

Runs execute on dynfab's built-in ``panda``; validity, the grasped object and every run's
outcome are measured here, on the meshes (:mod:`dynfab.scenario.recording_check`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from dynfab.benchmarks.mbm.moveit import ARM_JOINTS
from dynfab.robots.mesh_collision import MeshCollisionModel
from dynfab.robots.panda_sphere_fit import PANDA_URDF
from dynfab.robots.robot import Robot
from dynfab.scenario.exact_metrics import mesh_model_for
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import scenario_from_dict

__all__ = ["FINGER_OPENING", "HAND_LINKS", "LIMIT_SLACK", "TCP_LINK", "Franka", "franka", "franka_robot_mapping"]

#: Opening of each finger [m] (fully open).
FINGER_OPENING = 0.04
#: The hand's links with meshes: what "the hand" is when measuring distances to objects.
HAND_LINKS: tuple[str, ...] = ("panda_hand", "panda_leftfinger", "panda_rightfinger")
#: The point between the fingertips (the built-in ``panda``'s ``panda_hand``).
TCP_LINK = "panda_hand_tcp"
#: A joint value this close to a limit counts as at the limit (values rounded when written) [rad].
LIMIT_SLACK = 1e-6


def franka_robot_mapping() -> dict[str, Any]:
    """The scenario ``robot:`` mapping of Franka's Panda (module doc)."""
    return {"urdf": PANDA_URDF, "goal_link": TCP_LINK, "joints": list(ARM_JOINTS),
            "locked": {"panda_finger_joint1": FINGER_OPENING}}


@dataclass(frozen=True, eq=False)
class Franka:
    """Franka's Panda and its mesh model.

    Attributes:
        robot: The robot (no collision spheres: it is only measured, never planned for).
        meshes: Its collision meshes and checked self-collision pairs.
    """

    robot: Robot
    meshes: MeshCollisionModel

    def tcp(self, q: Sequence[float]) -> np.ndarray:
        """Position of :data:`TCP_LINK` at ``q`` [m], shape (3,)."""
        return np.array(self.robot.kinematics.position(np.asarray(q, dtype=float), TCP_LINK), dtype=float).ravel()

    def limit_problem(self, q: Sequence[float]) -> str | None:
        """The first joint of ``q`` more than :data:`LIMIT_SLACK` outside its limits, as
        ``panda_joint4 = -0.043 is outside [-3.0718, -0.0698]``; None if all are within."""
        kinematics = self.robot.kinematics
        for i, value in enumerate(q):
            lower, upper = float(kinematics.lower[i]), float(kinematics.upper[i])
            if not lower - LIMIT_SLACK <= value <= upper + LIMIT_SLACK:
                return f"{kinematics.joint_names[i]} = {value:.6g} is outside [{lower:.6g}, {upper:.6g}]"
        return None

    def clipped(self, q: Sequence[float]) -> tuple[float, ...]:
        """``q`` clipped into the joint limits (moves values within :data:`LIMIT_SLACK` onto them)."""
        kinematics = self.robot.kinematics
        return tuple(float(v) for v in np.clip(np.asarray(q, dtype=float), kinematics.lower, kinematics.upper))


@cache
def franka() -> Franka:
    """Franka's Panda (loaded once per process).

    Raises:
        ScenarioError: example-robot-data is not installed (``pip install dynfab[robots]``).
    """
    scenario = scenario_from_dict({"robot": franka_robot_mapping(), "planner": "static-fabric", "dt": 0.01,
                                   "duration": 0.01, "initial_state": {"q": [0.0] * len(ARM_JOINTS)},
                                   "goal": [{"type": "joint", "position": [0.0] * len(ARM_JOINTS)}]})
    robot = robot_for(scenario)
    meshes = mesh_model_for(robot)
    assert meshes is not None  # example-robot-data's Panda has collision meshes
    return Franka(robot, meshes)
