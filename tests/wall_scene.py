"""The guidance tests' scene: a wall in front of the Panda, a start with the hand on one side
and a goal behind it (the start turned about joint 1), and goals near the wall."""

from __future__ import annotations

import numpy as np

from dynfab.geometry.shapes import Box, Placement
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.robots.robot import Robot

#: The wall: 0.6 x 0.04 x 0.7 m, centred at (0.45, 0, 0.35) [m].
WALL = PlacedObstacle(Box((0.6, 0.04, 0.7)), Placement((0.45, 0.0, 0.35)))
#: The wall as a scenario file's obstacle entry.
WALL_ENTRY = {"type": "box", "position": [0.45, 0.0, 0.35], "size": [0.6, 0.04, 0.7]}
#: The hand in front of the wall, at +y [rad].
START = np.array([1.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
#: START turned about joint 1: the hand behind the wall [rad].
GOAL = np.array([-1.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])


def goal_near_the_wall(robot: Robot, clearance: float) -> np.ndarray:
    """START turned about joint 1 toward the wall until its spheres are ``clearance`` [m] from it."""
    checker = ConfigurationChecker(robot, [WALL])
    goal = START.copy()
    for q1 in np.linspace(-1.3, 0.0, 1301):
        goal[0] = q1
        if checker.clearances(goal)[0] < clearance:
            return goal
    raise AssertionError("the wall is never that close")
