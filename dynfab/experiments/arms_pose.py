"""Pose reaching among boxes with arms as they ship, guided (issue 19): the five arms of
example-robot-data (UR5, Kinova j2s6s200, xArm7, Panda, Unitree Z1) and the SO-100 (its
``so100.urdf`` ships in example-robot-data 6.0 too), automatic collision spheres and
pairs, global joint-space guidance on (the default for arms with goals at rest).

Run ``seed`` uses arm ``POSE_ARM_NAMES[seed % 6]``. Distribution (our choices):

- start: the arm's home configuration, at rest; dt 0.01 s, :data:`DURATION` s;
- goal: the tool *pose* (position and orientation) of a random configuration within the
  joint limits whose link meshes keep :data:`SELF_MARGIN` from each other (the pairs the
  run metrics check), whose tool lies in front of the arm (horizontal distance 0.3-0.75
  of the arm's reach, height 0.05-0.7 of it, azimuth within 90 degrees of the start
  tool's) and at least 0.25 reach from the start tool: reachable by construction.
  Reached when the tool is within :data:`TOLERANCE` of the point and
  :data:`ANGLE_TOLERANCE` of the rotation;
- obstacles: :data:`BOXES_BETWEEN` boxes between start and goal (centre on the straight
  line between the start and goal tool positions at 30-70 %, shifted up to 0.1 reach
  sideways) and one anywhere in the workspace, edges 0.06-0.2 reach, random yaw; each is
  redrawn until its mesh distance to the arm's link meshes, both at the start and at the
  goal configuration, exceeds :data:`BOX_MARGIN` (a goal that keeps failing is redrawn).

A run succeeds when the pose is reached and no link mesh touches a box or another checked
link (the run's mesh metrics).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from dynfab.experiments.arms import _ERD, ARMS, Arm
from dynfab.experiments.sampling import rounded
from dynfab.geometry.shapes import Box, Placement
from dynfab.robots.joint_bounds import finite_joint_bounds
from dynfab.robots.mesh_collision import MeshCollisionModel, mesh_collision_model
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes

DURATION = 20.0
#: position tolerance of the pose goal [m]
TOLERANCE = 0.01
#: orientation tolerance of the pose goal [rad]
ANGLE_TOLERANCE = 0.05
#: least mesh distance between a box and the arm at the start and at the goal [m]
BOX_MARGIN = 0.04
#: least mesh distance between checked link pairs at the goal configuration [m]
SELF_MARGIN = 0.01
#: boxes between the start and the goal; one more goes anywhere
BOXES_BETWEEN = 2
#: draws of one box before the goal is redrawn
BOX_TRIES = 100
#: largest azimuth between the start tool position and the goal, about the base's z axis [rad]
MAX_TURN = np.radians(90.0)

POSE_ARMS: dict[str, Arm] = {
    **ARMS,
    "z1": Arm(_ERD + "z1_description/urdf/z1.urdf", "link06", (0.0, 1.2, -1.2, 0.0, 0.0, 0.0), reach=0.7,
              joints=tuple(f"joint{i}" for i in range(1, 7)), locked=(("jointGripper", 0.0),)),
    "so100": Arm(_ERD + "so_arm_description/urdf/so100.urdf", "gripper", (0.0, 1.6, -1.6, 0.0, 0.0), reach=0.4,
                 joints=("shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll"),
                 locked=(("gripper", 0.0),)),
}
POSE_ARM_NAMES: tuple[str, ...] = tuple(POSE_ARMS)


@dataclass(frozen=True)
class Pose:
    """A tool pose: ``position`` [m] and ``orientation`` as a unit quaternion (w, x, y, z)."""

    position: NDArray[np.float64]
    orientation: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class _PoseGeometry:
    """An arm's tool transform and link meshes, for drawing scenarios.

    Attributes:
        arm: the arm.
        tool: ``q ↦`` the tool's 4x4 transform in the world.
        meshes: the link meshes and checked pairs, as the run metrics build them (pairs
            touching at the zero configuration clipped into the limits are left out).
        lower, upper: finite joint bounds [rad].
    """

    arm: Arm
    tool: ca.Function
    meshes: MeshCollisionModel
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]

    @classmethod
    @cache
    def of(cls, name: str) -> _PoseGeometry:
        arm = POSE_ARMS[name]
        kin = arm.kinematics()
        q = ca.SX.sym("q", kin.dof)
        tool = ca.Function("tool", [q], [kin.transform(q, arm.tool)])
        lower, upper = finite_joint_bounds(kin.lower, kin.upper)
        meshes = mesh_collision_model(kin, np.clip(np.zeros(kin.dof), lower, upper))
        assert meshes is not None, f"{arm.urdf} has no collision geometry"
        return cls(arm, tool, meshes, lower, upper)

    def pose(self, q: NDArray[np.float64]) -> Pose:
        transform = np.array(self.tool(q))
        w_last = Rotation.from_matrix(transform[:3, :3]).as_quat()
        return Pose(transform[:3, 3], np.roll(w_last, 1))

    def self_distance(self, q: NDArray[np.float64]) -> float:
        distance = sweep_meshes(self.meshes, q[None], []).min_self_distance
        return np.inf if distance is None else distance

    def clearance(self, q: NDArray[np.float64], box: Box, placement: Placement) -> float:
        sweep = sweep_meshes(self.meshes, q[None], [PlacedShape("box", box, (placement,))])
        assert sweep.clearance is not None
        return sweep.clearance

    def goal(self, rng: np.random.Generator) -> tuple[NDArray[np.float64], Pose]:
        """A goal configuration and its tool pose (module docstring)."""
        home, reach = np.array(self.arm.home), self.arm.reach
        start = self.pose(home).position
        while True:
            q = rng.uniform(self.lower, self.upper)
            pose = self.pose(q)
            goal = pose.position
            horizontal = float(np.hypot(goal[0], goal[1]))
            turn = np.angle(complex(goal[0], goal[1]) / complex(start[0], start[1]))
            if (0.3 * reach < horizontal < 0.75 * reach and 0.05 * reach < goal[2] < 0.7 * reach
                    and abs(turn) < MAX_TURN and np.linalg.norm(goal - start) > 0.25 * reach
                    and self.self_distance(q) > SELF_MARGIN):
                return q, pose


def _box(rng: np.random.Generator, centre: NDArray[np.float64], reach: float) -> tuple[Box, Placement]:
    yaw = float(rng.uniform(-np.pi, np.pi))
    size = rng.uniform(0.06, 0.2, size=3) * reach
    return Box(tuple(size)), Placement(tuple(centre), (np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)))


def _between(rng: np.random.Generator, start: NDArray[np.float64], goal: NDArray[np.float64],
             reach: float) -> NDArray[np.float64]:
    """A point at 30-70 % of the segment start-goal, up to 0.1 reach off it sideways."""
    direction = (goal - start) / np.linalg.norm(goal - start)
    side = np.cross(direction, rng.normal(size=3))
    side /= np.linalg.norm(side)
    return start + rng.uniform(0.3, 0.7) * (goal - start) + rng.uniform(0.0, 0.1) * reach * side


def _boxes(rng: np.random.Generator, geometry: _PoseGeometry, q_goal: NDArray[np.float64],
           goal: NDArray[np.float64]) -> list[tuple[Box, Placement]] | None:
    """The boxes of a scenario, or None if one found no place within :data:`BOX_TRIES`."""
    home, reach = np.array(geometry.arm.home), geometry.arm.reach
    start = geometry.pose(home).position
    boxes: list[tuple[Box, Placement]] = []
    while len(boxes) < BOXES_BETWEEN + 1:
        for _ in range(BOX_TRIES):
            centre = (_between(rng, start, goal, reach) if len(boxes) < BOXES_BETWEEN else
                      rng.uniform([-0.7, -0.7, 0.0], [0.7, 0.7, 0.8]) * reach)
            box, placement = _box(rng, centre, reach)
            if (geometry.clearance(home, box, placement) > BOX_MARGIN
                    and geometry.clearance(q_goal, box, placement) > BOX_MARGIN):
                boxes.append((box, placement))
                break
        else:
            return None
    return boxes


def scenario(seed: int, planner: str = "static-fabric") -> dict[str, Any]:
    """The scenario of run ``seed`` as a scenario-file mapping (module docstring)."""
    name = POSE_ARM_NAMES[seed % len(POSE_ARM_NAMES)]
    geometry = _PoseGeometry.of(name)
    rng = np.random.default_rng(seed)
    while True:
        q_goal, pose = geometry.goal(rng)
        boxes = _boxes(rng, geometry, q_goal, pose.position)
        if boxes is not None:
            break
    obstacles = [{"type": "box", "position": rounded(np.array(placement.position)), "size": rounded(np.array(box.size)),
                  "orientation": rounded(np.array(placement.orientation))} for box, placement in boxes]
    goal = {"type": "pose", "position": rounded(pose.position), "orientation": rounded(pose.orientation, 6),
            "tolerance": TOLERANCE, "angle_tolerance": ANGLE_TOLERANCE}
    return geometry.arm.scenario_mapping(planner, DURATION, goal, obstacles)
