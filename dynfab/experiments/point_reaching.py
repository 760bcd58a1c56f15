"""Planar analogue of Experiment 1: the ``point`` robot reaches a goal among 1-5 discs.

The built-in ``point`` robot (holonomic x, y; one collision disc of radius 0.1 m on the
goal link ``point``) starts at rest and must bring its centre within 0.05 m of a goal.

Distribution (all positions in metres, in the 4 m x 4 m square ``[-2, 2]^2``):

- start: uniform in the square, zero velocity;
- goal: at a distance uniform in ``[1.5, 3]`` from the start in a uniform direction,
  redrawn until it lies in the square; tolerance 0.05 m;
- 1-5 discs (number uniform), radius uniform in ``[0.2, 0.4]``. The first disc blocks the
  straight segment start -> goal: its centre is the point at a fraction uniform in
  ``[0.3, 0.7]`` of the segment, moved sideways by at most half its radius, so the
  straight line would collide and avoidance is exercised. The other centres are uniform
  in the square;
- every disc is redrawn (keeping its radius) until its surface is more than 0.05 m from
  the robot's disc at the start (centre distance > radius + 0.1 + 0.05) and more than
  0.1 m from the goal point (centre distance > radius + 0.1), as in Experiment 1, and
  more than the robot's diameter + 0.1 m from every other disc, so that every gap between
  discs is passable: two discs closer than the robot is wide form a pocket, a local
  minimum that no reactive planner is expected to leave (the paper's "deadlocks");
- dt 0.01 s, duration 20 s, static fabric planner unless told otherwise.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dynfab.experiments.sampling import rounded

HALF_SIDE = 2.0
GOAL_DISTANCE = (1.5, 3.0)
DISC_RADIUS = (0.2, 0.4)
BLOCKING_FRACTION = (0.3, 0.7)
ROBOT_RADIUS = 0.1
START_MARGIN = 0.05
GOAL_MARGIN = 0.1
PASSAGE_MARGIN = 0.1
TOLERANCE = 0.05
DT = 0.01
DURATION = 20.0


def scenario(seed: int, planner: str = "static-fabric") -> dict[str, Any]:
    """The scenario of run ``seed`` as a scenario-file mapping (docs/design.md section 5).

    Args:
        seed: Seed of the random generator; the same seed gives the same scenario.
        planner: Planner name written into the scenario.

    Returns:
        A mapping accepted by :func:`dynfab.scenario.scenario_from_dict`.
    """
    rng = np.random.default_rng(seed)
    start = rng.uniform(-HALF_SIDE, HALF_SIDE, 2)
    goal = _goal(rng, start)
    obstacles: list[dict[str, Any]] = []
    discs: list[tuple[np.ndarray, float]] = []
    for index in range(int(rng.integers(1, 6))):
        radius = float(rng.uniform(*DISC_RADIUS))
        while True:
            centre = _blocking_centre(rng, start, goal, radius) if index == 0 else rng.uniform(-HALF_SIDE, HALF_SIDE, 2)
            start_gap = np.linalg.norm(centre - start) - radius - ROBOT_RADIUS
            goal_gap = np.linalg.norm(centre - goal) - radius
            passable = all(np.linalg.norm(centre - other) - radius - other_radius > 2 * ROBOT_RADIUS + PASSAGE_MARGIN
                           for other, other_radius in discs)
            if start_gap > START_MARGIN and goal_gap > GOAL_MARGIN and passable:
                break
        discs.append((centre, radius))
        obstacles.append({"type": "sphere", "position": rounded(centre), "radius": round(radius, 4)})
    return {
        "robot": "point",
        "planner": planner,
        "dt": DT,
        "duration": DURATION,
        "initial_state": {"q": rounded(start)},
        "goal": [{"type": "position", "link": "point", "position": rounded(goal), "tolerance": TOLERANCE}],
        "obstacles": obstacles,
    }


def _goal(rng: np.random.Generator, start: np.ndarray) -> np.ndarray:
    """A point 1.5-3 m from ``start`` in a uniform direction, inside the square."""
    while True:
        angle = rng.uniform(0.0, 2.0 * np.pi)
        goal = start + rng.uniform(*GOAL_DISTANCE) * np.array([np.cos(angle), np.sin(angle)])
        if np.all(np.abs(goal) <= HALF_SIDE):
            return goal


def _blocking_centre(rng: np.random.Generator, start: np.ndarray, goal: np.ndarray, radius: float) -> np.ndarray:
    """A disc centre on the segment start -> goal, offset sideways by at most radius / 2."""
    direction = (goal - start) / np.linalg.norm(goal - start)
    normal = np.array([-direction[1], direction[0]])
    along = start + rng.uniform(*BLOCKING_FRACTION) * (goal - start)
    return along + rng.uniform(-0.5, 0.5) * radius * normal
