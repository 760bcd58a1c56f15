"""The guidance tests' scene: a wall in front of the Panda, a start with the hand on one side
and a goal behind it (the start turned about joint 1), and goals near the wall."""

from __future__ import annotations

import numpy as np
import trimesh

from dynfab.geometry.shapes import Box, Mesh, Placement
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.inverse_kinematics import AxisTarget, PointTarget
from dynfab.robots.robot import Robot

#: The wall: 0.6 x 0.04 x 0.7 m, centred at (0.45, 0, 0.35) [m].
WALL = PlacedObstacle(Box((0.6, 0.04, 0.7)), Placement((0.45, 0.0, 0.35)))
#: The wall as a scenario file's obstacle entry.
WALL_ENTRY = {"type": "box", "position": [0.45, 0.0, 0.35], "size": [0.6, 0.04, 0.7]}
_BOX = trimesh.creation.box(extents=WALL.shape.size)
#: The wall as a triangle mesh (a scene of meshes).
MESH_WALL = PlacedObstacle(Mesh(_BOX.vertices, _BOX.faces, "wall"), WALL.placement)
#: The hand in front of the wall, at +y [rad].
START = np.array([1.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
#: START turned about joint 1: the hand behind the wall [rad].
GOAL = np.array([-1.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
#: Where the robot goes from a start at the wall (the hand away from it, at −y) [rad].
AWAY = np.array([-1.3, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])


def hand_pose_targets(robot: Robot, q: np.ndarray) -> list[PointTarget | AxisTarget]:
    """The pose of the Panda's hand at ``q`` as inverse-kinematics targets."""
    link = "panda_hand"
    rotation = np.asarray(robot.kinematics.transform(q, link))[:3, :3]
    targets: list[PointTarget | AxisTarget] = [PointTarget(link, tuple(robot.link_position(q, link)))]
    for axis in range(3):
        targets.append(AxisTarget(link, tuple(np.eye(3)[axis]), tuple(rotation[:, axis])))
    return targets


def goal_near_the_wall(robot: Robot, clearance: float) -> np.ndarray:
    """START turned about joint 1 toward the wall until its spheres are ``clearance`` [m] from it."""
    checker = ConfigurationChecker(robot, [WALL])
    goal = START.copy()
    for q1 in np.linspace(-1.3, 0.0, 1301):
        goal[0] = q1
        if checker.clearances(goal)[0] < clearance:
            return goal
    raise AssertionError("the wall is never that close")
