"""Experiment 1 scenarios: the Panda reaches a random goal among 1-5 static spheres.

Distribution (``shared/EXPERIMENTS.md``, Experiment 1), with the choices the paper leaves
open made explicit:

- goal: an end-effector position in the box ``[-0.4, -0.4, 0.1] .. [0.7, 0.0, 1.1]`` m,
  tolerance 0.05 m. *Choice:* goals are drawn as the hand position of a random
  configuration within the joint limits (rejected until inside the box and at least
  0.1 m from the start), so every goal is reachable;
- 1-5 spheres of radius 0.15 m, centres uniform in ``[-1, -1, 0] .. [1, 0.3, 1]`` m.
  *Choice:* a sphere is rejected if it comes within 0.05 m of any robot collision sphere
  at the start, or within 0.1 m (surface) of the goal;
- start ``q0 = [1, 0, 0, -1.5, 0, 1.8675, 0]`` at rest, dt 0.01 s, 20 s.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dynfab.experiments.panda_sampling import PandaSampler, panda_scenario
from dynfab.experiments.sampling import rounded

GOAL_LOW, GOAL_HIGH = np.array([-0.4, -0.4, 0.1]), np.array([0.7, 0.0, 1.1])
OBSTACLE_LOW, OBSTACLE_HIGH = np.array([-1.0, -1.0, 0.0]), np.array([1.0, 0.3, 1.0])
OBSTACLE_RADIUS = 0.15
START_MARGIN = 0.05
GOAL_MARGIN = 0.1
DURATION = 20.0


def scenario(seed: int, planner: str = "static-fabric") -> dict[str, Any]:
    """The scenario of run ``seed`` as a scenario-file mapping (docs/design.md section 5)."""
    rng = np.random.default_rng(seed)
    sampler = PandaSampler.create()
    goal = sampler.reachable_goal(rng, GOAL_LOW, GOAL_HIGH)
    obstacles = []
    for _ in range(int(rng.integers(1, 6))):
        while True:
            centre = rng.uniform(OBSTACLE_LOW, OBSTACLE_HIGH)
            if (sampler.start_clearance(centre, OBSTACLE_RADIUS) > START_MARGIN
                    and np.linalg.norm(goal - centre) - OBSTACLE_RADIUS > GOAL_MARGIN):
                break
        obstacles.append({"type": "sphere", "position": rounded(centre), "radius": OBSTACLE_RADIUS})
    goal_spec = {"type": "position", "position": rounded(goal), "tolerance": 0.05}
    return panda_scenario(planner, DURATION, goal_spec, obstacles)
