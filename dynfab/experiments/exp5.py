"""Experiment 5 scenarios: the mobile manipulator (Boxer base + Panda, "Albert" in the
paper) brings its hand to a random goal among 8 spheres in a 7 m x 7 m room
(``shared/EXPERIMENTS.md``, Experiment 5).

The paper gives the room and the number of spheres; the choices:

- start: the base at rest at the room's centre with a random heading, the arm in the
  default pose ``[1, 0, 0, −1.5, 0, 1.8675, 0]``;
- goal: a hand position with ``(x, y)`` uniform in the room ``[-3.5, 3.5]²`` at 1.5-3.5 m
  from the start and height uniform in ``[0.3, 1.2]`` m, tolerance 0.05 m;
- 8 spheres of radius uniform in ``[0.2, 0.4]`` m, centres uniform in the room at heights
  ``[0.2, 1.2]`` m, at least 0.3 m of surface clearance from the robot at the start and
  0.2 m from the goal, and 0.7 m apart (every gap passable for the 0.55 m wide base);
- dt 0.01 s, 40 s.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dynfab.experiments.sampling import rounded, scatter_spheres
from dynfab.robots import load_robot

HALF_ROOM = 3.5
GOAL_DISTANCE = (1.5, 3.5)
GOAL_HEIGHT = (0.3, 1.2)
RADIUS = (0.2, 0.4)
HEIGHT = (0.2, 1.2)
START_MARGIN = 0.3
GOAL_MARGIN = 0.2
PASSAGE = 0.7
ARM_Q0 = (1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0)
DURATION = 40.0


def scenario(seed: int, planner: str = "static-fabric") -> dict[str, Any]:
    """Experiment 5, run ``seed``."""
    rng = np.random.default_rng(seed)
    robot = load_robot("boxer-panda")
    q0 = np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi), *ARM_Q0])
    centres = np.asarray(robot.sphere_centers(q0))
    radii = np.array([s.radius for s in robot.collision_spheres])
    while True:
        goal = np.array([*rng.uniform(-HALF_ROOM, HALF_ROOM, 2), rng.uniform(*GOAL_HEIGHT)])
        if GOAL_DISTANCE[0] <= np.linalg.norm(goal[:2]) <= GOAL_DISTANCE[1]:
            break
    spheres = scatter_spheres(
        rng, 8, RADIUS, lambda: np.array([*rng.uniform(-HALF_ROOM, HALF_ROOM, 2), rng.uniform(*HEIGHT)]),
        centres, radii, goal, START_MARGIN, GOAL_MARGIN, PASSAGE)
    return {
        "robot": "boxer-panda",
        "planner": planner,
        "dt": 0.01,
        "duration": DURATION,
        "initial_state": {"q": rounded(q0)},
        "goal": [{"type": "position", "link": "panda_hand", "position": rounded(goal), "tolerance": 0.05}],
        "obstacles": [{"type": "sphere", "position": rounded(c), "radius": round(r, 4)} for c, r in spheres],
    }
