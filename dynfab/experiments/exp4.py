"""Experiment 4 scenarios: the Clearpath Boxer (differential drive) drives to a random
goal among 5 spheres (``shared/EXPERIMENTS.md``, Experiment 4).

The paper randomizes the initial pose, the goal and the 5 spheres without giving ranges;
the choices:

- start: pose ``(x, y)`` uniform in ``[-3, 3]²`` m, yaw uniform in ``[-π, π)``, at rest;
- goal: the ``base_link`` position uniform in ``[-3, 3]²``, 2-5 m from the start,
  tolerance 0.1 m;
- 5 spheres (discs in the plane) of radius uniform in ``[0.3, 0.5]`` m, centres uniform in
  ``[-3.5, 3.5]²``, at least 0.3 m of surface clearance from the robot's footprint at the
  start, 0.6 m from the goal (the footprint reaches 0.44 m ahead of ``base_link``, so the
  base can stand on its goal in any heading), and at least 0.9 m apart from each other (the footprint is
  0.66 m wide),
  so that every gap is passable;
- dt 0.01 s, 40 s.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dynfab.experiments.sampling import rounded, scatter_spheres
from dynfab.robots import load_robot

AREA = 3.0
OBSTACLE_AREA = 3.5
GOAL_DISTANCE = (2.0, 5.0)
RADIUS = (0.3, 0.5)
START_MARGIN = 0.3
GOAL_MARGIN = 0.6
PASSAGE = 0.9
DURATION = 40.0


def scenario(seed: int, planner: str = "static-fabric") -> dict[str, Any]:
    """Experiment 4, run ``seed``."""
    rng = np.random.default_rng(seed)
    robot = load_robot("boxer")
    pose = np.array([*rng.uniform(-AREA, AREA, 2), rng.uniform(-np.pi, np.pi)])
    footprint = np.asarray(robot.sphere_centers(pose))[:, :2]
    radii = np.array([s.radius for s in robot.collision_spheres])
    while True:
        goal = rng.uniform(-AREA, AREA, 2)
        if GOAL_DISTANCE[0] <= np.linalg.norm(goal - pose[:2]) <= GOAL_DISTANCE[1]:
            break
    discs = scatter_spheres(rng, 5, RADIUS, lambda: rng.uniform(-OBSTACLE_AREA, OBSTACLE_AREA, 2), footprint,
                            radii, goal, START_MARGIN, GOAL_MARGIN, PASSAGE)
    return {
        "robot": "boxer",
        "planner": planner,
        "dt": 0.01,
        "duration": DURATION,
        "initial_state": {"q": rounded(pose)},
        "goal": [{"type": "position", "link": "base_link", "position": rounded(goal), "tolerance": 0.1}],
        "obstacles": [{"type": "sphere", "position": rounded(c), "radius": round(r, 4)} for c, r in discs],
    }
