"""Reaching with arms as they ship: UR5, Kinova (j2s6s200), xArm7 and Panda from
example-robot-data, automatic collision spheres and pairs, sphere and box obstacles.

Run ``seed`` uses arm ``ARM_NAMES[seed % 4]``. Distribution (our choices, no paper figures):

- start: the arm's home configuration (:data:`ARMS`), at rest; dt 0.01 s, 15 s;
- goal: the tool position of a random configuration within the joint limits whose tool
  lies in front of the arm (horizontal distance 0.3-0.65 of the arm's reach, height
  0.1-0.7 of it above the base, azimuth within 70 degrees of the start tool's, like the
  goal box of the paper's Experiment 1 in front of the Panda) and at least 0.15 m from
  the start, tolerance 0.03 m;
- obstacles: one sphere (radius 0.04-0.08 m) and one box (edges 0.04-0.15 m, random yaw)
  near the straight line from the start tool position to the goal (centre on the line
  at 30-70 %, shifted 0.12-0.25 m sideways), a second sphere anywhere in the workspace;
  each rejected if it comes within 0.05 m of the arm's collision meshes at the start or
  within 0.1 m of the goal.

Every link's collision mesh is checked against the obstacles and against the other links
when the run is measured (``dynfab run`` on these scenarios reports the mesh figures).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import trimesh

from dynfab.experiments.sampling import rounded
from dynfab.robots import Kinematics, load_urdf
from dynfab.robots.joint_bounds import finite_joint_bounds
from dynfab.robots.link_meshes import link_collision_meshes
from dynfab.robots.mesh_paths import resolve_uri

DURATION = 15.0
TOLERANCE = 0.03
START_MARGIN = 0.05
GOAL_MARGIN = 0.1
#: largest azimuth between the start tool position and the goal, about the base's z axis [rad]
MAX_TURN = np.radians(70.0)


@dataclass(frozen=True)
class Arm:
    """An arm of example-robot-data as a scenario names it.

    Attributes:
        urdf: ``package://`` URI of its URDF.
        tool: The goal link.
        home: Start configuration of the active joints [rad].
        reach: Approximate reach from the base [m].
        joints: Active joints (``None``: every movable one).
        locked: Values of the others (gripper fingers).
    """

    urdf: str
    tool: str
    home: tuple[float, ...]
    reach: float
    joints: tuple[str, ...] | None = None
    locked: tuple[tuple[str, float], ...] = ()

    def kinematics(self) -> Kinematics:
        """Its kinematics, read from example-robot-data's URDF (active joints, locked ones).

        Raises:
            FileNotFoundError: example-robot-data is not installed.
        """
        return Kinematics(load_urdf(installed_urdf(self.urdf)), joints=self.joints, locked=dict(self.locked))

    def scenario_mapping(self, planner: str, duration: float, goal: dict[str, Any],
                         obstacles: list[dict[str, Any]]) -> dict[str, Any]:
        """A scenario file's mapping: this arm from its home configuration at rest to ``goal``
        among ``obstacles``, dt 0.01 s, ``duration`` [s]."""
        return {"robot": self.robot_mapping(), "planner": planner, "dt": 0.01, "duration": duration,
                "initial_state": {"q": list(self.home)}, "goal": [goal], "obstacles": obstacles}

    def robot_mapping(self) -> dict[str, Any]:
        """The ``robot:`` block of a scenario file."""
        robot: dict[str, Any] = {"urdf": self.urdf, "goal_link": self.tool,
                                 "collision_spheres": "auto", "self_collision_pairs": "auto"}
        if self.joints is not None:
            robot["joints"] = list(self.joints)
        if self.locked:
            robot["locked"] = dict(self.locked)
        return robot


def installed_urdf(uri: str) -> Path:
    """The file a ``package://`` ``uri`` of example-robot-data names.

    Raises:
        FileNotFoundError: example-robot-data is not installed.
    """
    path = resolve_uri(uri, None)
    if path is None:
        raise FileNotFoundError(f"{uri}: install dynfab[robots] (example-robot-data)")
    return Path(path)


_ERD = "package://example-robot-data/robots/"
ARMS: dict[str, Arm] = {
    "ur5": Arm(_ERD + "ur_description/urdf/ur5_robot.urdf", "tool0",
               (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0), reach=0.85),
    "kinova": Arm(_ERD + "kinova_description/robots/kinova.urdf", "j2s6s200_end_effector",
                  (0.0, 2.9, 1.3, -2.07, 1.4, 0.0), reach=0.9),
    "xarm7": Arm(_ERD + "xarm_description/urdf/xarm7.urdf", "link_eef",
                 (0.0, -0.2, 0.0, 0.9, 0.0, 1.1, 0.0), reach=0.7),
    "panda": Arm(_ERD + "panda_description/urdf/panda.urdf", "panda_hand_tcp",
                 (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785), reach=0.85,
                 joints=tuple(f"panda_joint{i}" for i in range(1, 8)),
                 locked=(("panda_finger_joint1", 0.02),)),
}
ARM_NAMES: tuple[str, ...] = tuple(ARMS)


@dataclass(frozen=True)
class _ArmGeometry:
    """Numeric tool position and points of the link meshes' surfaces at the start (vertices
    and 400 samples per mesh), for drawing scenarios."""

    arm: Arm
    kinematics: Kinematics
    tool: ca.Function
    start_points: np.ndarray

    @classmethod
    @cache
    def of(cls, name: str) -> _ArmGeometry:
        arm = ARMS[name]
        kin = arm.kinematics()
        model = kin.model
        q = ca.SX.sym("q", kin.dof)
        tool = ca.Function("tool", [q], [kin.position(q, arm.tool)])
        points = []
        for link in model.links:
            transform = np.array(kin.transform(np.array(arm.home), link.name))
            for mesh in link_collision_meshes(model, link.name):
                surface = np.concatenate([mesh.vertices, trimesh.sample.sample_surface(mesh, 400, seed=0)[0]])
                points.append(surface @ transform[:3, :3].T + transform[:3, 3])
        return cls(arm, kin, tool, np.concatenate(points))

    def tool_position(self, q: np.ndarray) -> np.ndarray:
        return np.array(self.tool(q)).ravel()

    def goal(self, rng: np.random.Generator) -> np.ndarray:
        start, reach = self.tool_position(np.array(self.arm.home)), self.arm.reach
        low, high = finite_joint_bounds(self.kinematics.lower, self.kinematics.upper)
        while True:
            goal = self.tool_position(rng.uniform(low, high))
            horizontal = float(np.hypot(goal[0], goal[1]))
            turn = np.angle(complex(goal[0], goal[1]) / complex(start[0], start[1]))
            if (0.3 * reach < horizontal < 0.65 * reach and 0.1 * reach < goal[2] < 0.7 * reach
                    and abs(turn) < MAX_TURN and np.linalg.norm(goal - start) > 0.15):
                return goal


def _near_line(rng: np.random.Generator, start: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """A point at 30-70 % of the segment start-goal, 0.12-0.25 m off it sideways."""
    direction = (goal - start) / np.linalg.norm(goal - start)
    side = np.cross(direction, rng.normal(size=3))
    side /= np.linalg.norm(side)
    return start + rng.uniform(0.3, 0.7) * (goal - start) + rng.uniform(0.12, 0.25) * side


def scenario(seed: int, planner: str = "static-fabric") -> dict[str, Any]:
    """The scenario of run ``seed`` as a scenario-file mapping (module docstring)."""
    name = ARM_NAMES[seed % len(ARM_NAMES)]
    geometry = _ArmGeometry.of(name)
    rng = np.random.default_rng(seed)
    goal = geometry.goal(rng)
    start = geometry.tool_position(np.array(geometry.arm.home))
    points = geometry.start_points
    obstacles: list[dict[str, Any]] = []
    while len(obstacles) < 3:
        kind = ("sphere", "box", "sphere")[len(obstacles)]
        centre = (_near_line(rng, start, goal) if len(obstacles) < 2 else
                  rng.uniform([-0.7, -0.7, 0.0], [0.7, 0.7, 0.8]) * geometry.arm.reach)
        if kind == "sphere":
            radius = float(rng.uniform(0.04, 0.08))
            start_gap = np.min(np.linalg.norm(points - centre, axis=1)) - radius
            goal_gap = np.linalg.norm(goal - centre) - radius
            entry: dict[str, Any] = {"type": "sphere", "position": rounded(centre), "radius": round(radius, 4)}
        else:
            size = rng.uniform(0.04, 0.15, size=3)
            yaw = float(rng.uniform(-np.pi, np.pi))
            half_diagonal = 0.5 * float(np.linalg.norm(size))
            start_gap = np.min(np.linalg.norm(points - centre, axis=1)) - half_diagonal
            goal_gap = np.linalg.norm(goal - centre) - half_diagonal
            entry = {"type": "box", "position": rounded(centre), "size": rounded(size),
                     "orientation": rounded([np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])}
        if start_gap > START_MARGIN and goal_gap > GOAL_MARGIN and centre[2] > 0.02:
            obstacles.append(entry)
    return geometry.arm.scenario_mapping(planner, DURATION, {"type": "position", "position": rounded(goal),
                                                             "tolerance": TOLERANCE}, obstacles)
