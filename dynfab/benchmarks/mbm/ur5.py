"""The UR5 of example-robot-data with its gripper, as shipped (``ur5_gripper.urdf``), for
MBM's scenes: its description, mesh model and the conversion of the Panda's grasp pose
into a goal for its tool.

The UR5's ``base_link`` stands where the Panda's base stands (the scene's origin, MBM
writes scenes in the Panda's base frame). Its gripper is three boxes on ``tool0``: two
finger plates at x = ±0.03 m spanning z 0.01-0.06 m and a palm at z 0.01 m. So

- the **approach axis** is ``tool0``'s z (the Panda's: ``panda_hand_tcp``'s z);
- the **closing axis** is ``tool0``'s x (the Panda's: its hand's y, the fingers' joint
  axis);
- the **grasp point** is :data:`GRASP_OFFSET` on ``tool0``: between the finger plates,
  0.01 m in from their tips (the Panda's ``panda_hand_tcp`` lies about 0.009 m in from its
  fingertips).

The UR5 grasp frame at a Panda grasp pose ``(p, R)`` (``panda_hand_tcp`` at the Panda's
goal configuration) is therefore: the point :data:`GRASP_OFFSET` of ``tool0`` at ``p``
and ``tool0``'s rotation ``R · Rz(+90°)`` (maps ``tool0``'s x onto the Panda's y and
keeps z): :func:`tool_rotation`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from dynfab.benchmarks.mbm.franka import TCP_LINK, Franka
from dynfab.motion.inverse_kinematics import AxisTarget, IkResult, IkSettings, PointTarget, solve_ik
from dynfab.robots.mesh_collision import MeshCollisionModel
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes
from dynfab.robots.robot import Robot
from dynfab.scenario.exact_metrics import mesh_model_for
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import scenario_from_dict

__all__ = ["GRASP_OFFSET", "HOME", "TOOL_LINK", "UR5_URDF", "GraspPose", "Ur5", "panda_grasp_pose", "tool_rotation",
           "ur5", "ur5_robot_mapping"]

#: example-robot-data's UR5 with its gripper.
UR5_URDF = "package://example-robot-data/robots/ur_description/urdf/ur5_gripper.urdf"
#: The goal link: the UR flange frame, the gripper's parent.
TOOL_LINK = "tool0"
#: The grasp point in :data:`TOOL_LINK`'s frame [m] (module doc).
GRASP_OFFSET: tuple[float, float, float] = (0.0, 0.0, 0.05)
#: The start configuration: arm up, tool down in front (dynfab.experiments.arms) [rad].
HOME: tuple[float, ...] = (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0)
#: ``Rz(+90°)``: the Panda grasp frame's rotation to ``tool0``'s (module doc).
_PANDA_TO_TOOL = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def ur5_robot_mapping() -> dict[str, Any]:
    """The scenario ``robot:`` mapping of the UR5: URDF as shipped, automatic spheres and pairs."""
    return {"urdf": UR5_URDF, "goal_link": TOOL_LINK, "collision_spheres": "auto", "self_collision_pairs": "auto"}


@dataclass(frozen=True)
class GraspPose:
    """A grasp frame in the scene: ``position`` [m] and ``rotation`` (3x3, columns: the
    frame's axes in the world; z the approach axis)."""

    position: NDArray[np.float64]
    rotation: NDArray[np.float64]

    def quaternion(self) -> tuple[float, float, float, float]:
        """``rotation`` as a unit quaternion ``(w, x, y, z)``."""
        x, y, z, w = Rotation.from_matrix(self.rotation).as_quat()
        return float(w), float(x), float(y), float(z)


def panda_grasp_pose(robot: Franka, q: Sequence[float]) -> GraspPose:
    """The Panda's grasp frame (``panda_hand_tcp``) at ``q`` [rad]."""
    transform = np.array(robot.robot.kinematics.transform(np.asarray(q, dtype=float), TCP_LINK), dtype=float)
    return GraspPose(transform[:3, 3], transform[:3, :3])


def tool_rotation(grasp: GraspPose) -> NDArray[np.float64]:
    """``tool0``'s rotation that puts the UR5 gripper's axes on ``grasp``'s (module doc)."""
    return np.asarray(grasp.rotation @ _PANDA_TO_TOOL, dtype=float)


@dataclass(frozen=True, eq=False)
class Ur5:
    """The UR5 and its mesh model.

    Attributes:
        robot: The robot as a scenario loads it (automatic collision spheres).
        meshes: Its link meshes and checked self-collision pairs (what the runs are checked on).
    """

    robot: Robot
    meshes: MeshCollisionModel

    def grasp_pose(self, q: Sequence[float]) -> GraspPose:
        """The UR5's grasp frame at ``q`` [rad]: :data:`GRASP_OFFSET` on ``tool0``, rotated
        back into the Panda's convention (``tool0``'s x is the Panda frame's y)."""
        transform = np.array(self.robot.kinematics.transform(np.asarray(q, dtype=float), TOOL_LINK), dtype=float)
        rotation = transform[:3, :3]
        return GraspPose(transform[:3, 3] + rotation @ np.array(GRASP_OFFSET), rotation @ _PANDA_TO_TOOL.T)

    def contact(self, q: Sequence[float], shapes: Sequence[PlacedShape]) -> str | None:
        """The first mesh contact of ``q`` with ``shapes`` or itself, in words; None if free."""
        sweep = sweep_meshes(self.meshes, np.asarray(q, dtype=float)[None], shapes)
        if sweep.obstacle_contacts:
            contact = sweep.obstacle_contacts[0]
            return f"{contact.first} touches {contact.second} (distance {contact.depth:.3g} m)"
        if sweep.self_contacts:
            contact = sweep.self_contacts[0]
            return f"{contact.first} touches {contact.second} (self-collision, distance {contact.depth:.3g} m)"
        return None

    def free_ik(self, grasp: GraspPose, shapes: Sequence[PlacedShape], settings: IkSettings) -> IkResult:
        """IK of ``grasp``: its ``q`` is a configuration within the limits that puts the
        grasp frame on ``grasp`` and is free of ``shapes`` and of self-collision on the
        meshes (nearest :data:`HOME`), or None if none of the seeds finds one (then
        ``converged`` says whether any solution within the limits was found at all)."""
        rotation = tool_rotation(grasp)
        targets: list[PointTarget | AxisTarget] = [
            PointTarget(TOOL_LINK, tuple(float(v) for v in grasp.position), GRASP_OFFSET)]
        targets += [AxisTarget(TOOL_LINK, tuple(float(v) for v in np.eye(3)[k]),
                               tuple(float(v) for v in rotation[:, k])) for k in range(3)]
        return solve_ik(self.robot, targets, np.array(HOME), lambda q: self.contact(q, shapes) is None, settings)


@cache
def ur5() -> Ur5:
    """The UR5 (loaded once per process).

    Raises:
        ScenarioError: example-robot-data is not installed (``pip install dynfab[robots]``).
    """
    scenario = scenario_from_dict({"robot": ur5_robot_mapping(), "planner": "static-fabric", "dt": 0.01,
                                   "duration": 0.01, "initial_state": {"q": list(HOME)},
                                   "goal": [{"type": "joint", "position": list(HOME)}]})
    robot = robot_for(scenario)
    meshes = mesh_model_for(robot)
    assert meshes is not None  # example-robot-data's UR5 has collision meshes
    return Ur5(robot, meshes)
