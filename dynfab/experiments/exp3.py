"""Experiment 3 scenarios: the Panda holds a random static goal while two spheres move
through the workspace (``shared/EXPERIMENTS.md``, Experiment 3), SF vs DF.

- start ``q0 = [1, 0, 0, -1.5, 0, 1.8675, 0]`` at rest; 70 s; tolerance 0.02 m;
- goal: a reachable hand position (drawn as in Experiment 1) in the benchmark box
  ``[0.3, -0.6, 0.25] .. [0.7, 0.6, 1.1]``;
- spheres of radius 0.1 m moving as ``[-1 + 0.1 t, -0.4, 0.7]`` and
  ``[-1 + 0.2 t, 1 − 0.1 t, 0.3]``: SF see their position each tick, DF also their
  velocity and acceleration.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dynfab.experiments.panda_sampling import PandaSampler, panda_scenario
from dynfab.experiments.sampling import rounded

GOAL_LOW, GOAL_HIGH = np.array([0.3, -0.6, 0.25]), np.array([0.7, 0.6, 1.1])
DURATION = 70.0
OBSTACLES = (
    {"type": "sphere", "radius": 0.1, "trajectory": {"type": "linear", "start": [-1.0, -0.4, 0.7], "velocity": [0.1, 0.0, 0.0]}},
    {"type": "sphere", "radius": 0.1, "trajectory": {"type": "linear", "start": [-1.0, 1.0, 0.3], "velocity": [0.2, -0.1, 0.0]}},
)


def scenario(seed: int, planner: str = "dynamic-fabric") -> dict[str, Any]:
    """Experiment 3, run ``seed``."""
    rng = np.random.default_rng(seed)
    goal = PandaSampler.create().reachable_goal(rng, GOAL_LOW, GOAL_HIGH)
    goal_spec = {"type": "position", "position": rounded(goal), "tolerance": 0.02}
    return panda_scenario(planner, DURATION, goal_spec, [dict(o) for o in OBSTACLES])
