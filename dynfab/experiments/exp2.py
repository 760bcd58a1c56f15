"""Experiment 2 scenarios: the Panda's hand follows a path among spheres, SF vs DF.

``shared/EXPERIMENTS.md`` leaves the curve and the sphere distribution open; the choices:

- (a) ``analytic``: the hand follows a circle of radius 0.2 m about ``[0.45, 0, 0.55]`` in
  the plane normal to x, at 0.6 rad/s (0.12 m/s, the speed of the paper's moving
  obstacles in Experiment 3), starting at the top, for 20 s; three
  spheres of radius 0.1 m, centres uniform in ``[0, -0.6, 0.2] .. [0.8, 0.6, 1.0]``, not
  within 0.05 m of the robot at the start and not within 0.05 m of the curve (the path
  stays feasible, the spheres crowd it);
- (b) ``rrt``: a goal drawn as in Experiment 1 (at least 0.3 m from the start), three
  spheres of radius 0.15 m (0.05 m clear of the start pose, 0.1 m of the goal): the
  first one blocks the straight line from the hand's start to the goal (its centre on
  that segment, at 30-70 % of its length, moved sideways by at most half its radius), so
  that the global planner has to detour; the others uniform in the Experiment-1 box; the
  reference ``{type: rrt, goal, duration}``: an RRT path for the hand around the spheres,
  splined to reach the goal after ``max(4 s, length / 0.1 m/s)``; the run lasts 5 s more.
  Scenarios whose RRT start or goal lies within the planner's margin of a sphere are
  redrawn.

Both: tolerance 0.05 m; summed error = mean distance between hand and reference from the
first time within tolerance (docs/design.md section 6).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dynfab.experiments.panda_sampling import PandaSampler, panda_scenario
from dynfab.experiments.sampling import rounded
from dynfab.motion.global_planning import GlobalPlanningError, plan_path, path_duration
from dynfab.scenario.references import RRT_MARGIN

CIRCLE_CENTER = np.array([0.45, 0.0, 0.55])
CIRCLE_RADIUS = 0.2
CIRCLE_SPEED = 0.6  # [rad/s]
ANALYTIC_DURATION = 20.0
ANALYTIC_SPHERE_RADIUS = 0.1
ANALYTIC_LOW, ANALYTIC_HIGH = np.array([0.0, -0.6, 0.2]), np.array([0.8, 0.6, 1.0])
RRT_GOAL_LOW, RRT_GOAL_HIGH = np.array([-0.4, -0.4, 0.1]), np.array([0.7, 0.0, 1.1])
RRT_SPHERE_RADIUS = 0.15
RRT_LOW, RRT_HIGH = np.array([-1.0, -1.0, 0.0]), np.array([1.0, 0.3, 1.0])
RRT_SPEED = 0.1  # [m/s]
MARGIN = 0.05
_MAX_DRAWS = 200


def _circle_points(samples: int = 200) -> np.ndarray:
    angles = np.linspace(0, 2 * np.pi, samples, endpoint=False)
    return CIRCLE_CENTER + CIRCLE_RADIUS * np.stack([np.zeros_like(angles), np.cos(angles), np.sin(angles)], axis=1)


def analytic_scenario(seed: int, planner: str = "dynamic-fabric") -> dict[str, Any]:
    """Experiment 2a, run ``seed``."""
    rng = np.random.default_rng(seed)
    sampler = PandaSampler.create()
    curve = _circle_points()
    obstacles = []
    while len(obstacles) < 3:
        centre = rng.uniform(ANALYTIC_LOW, ANALYTIC_HIGH)
        to_curve = np.min(np.linalg.norm(curve - centre, axis=1)) - ANALYTIC_SPHERE_RADIUS
        if sampler.start_clearance(centre, ANALYTIC_SPHERE_RADIUS) > MARGIN and to_curve > MARGIN:
            obstacles.append({"type": "sphere", "position": rounded(centre), "radius": ANALYTIC_SPHERE_RADIUS})
    circle = {"type": "circle", "center": rounded(CIRCLE_CENTER), "radius": CIRCLE_RADIUS,
              "angular_velocity": CIRCLE_SPEED, "normal": [1.0, 0.0, 0.0], "phase": float(np.pi / 2)}
    return _scenario(planner, ANALYTIC_DURATION, circle, obstacles)


def rrt_scenario(seed: int, planner: str = "dynamic-fabric") -> dict[str, Any]:
    """Experiment 2b, run ``seed``."""
    rng = np.random.default_rng(seed)
    sampler = PandaSampler.create()
    start = sampler.hand_position()
    while True:
        goal = sampler.reachable_goal(rng, RRT_GOAL_LOW, RRT_GOAL_HIGH, min_distance_from_start=0.3)
        spheres = []
        for _ in range(_MAX_DRAWS):
            centre = _blocking_centre(rng, start, goal) if not spheres else rng.uniform(RRT_LOW, RRT_HIGH)
            if (sampler.start_clearance(centre, RRT_SPHERE_RADIUS) > MARGIN
                    and np.linalg.norm(goal - centre) - RRT_SPHERE_RADIUS > 2 * MARGIN):
                spheres.append(centre)
            if len(spheres) == 3:
                break
        else:
            continue  # no room for a blocking sphere between start and this goal: redraw the goal
        blocked = any(np.linalg.norm(point - c) < RRT_SPHERE_RADIUS + RRT_MARGIN for c in spheres for point in (start, goal))
        if blocked:
            continue
        try:
            path = plan_path(start, goal, [(c, RRT_SPHERE_RADIUS) for c in spheres], margin=RRT_MARGIN,
                             bounds_low=RRT_LOW - 0.5, bounds_high=RRT_HIGH + 0.5)
        except GlobalPlanningError:
            continue
        break
    duration = round(max(4.0, path_duration(path, RRT_SPEED)), 2)
    obstacles = [{"type": "sphere", "position": rounded(c), "radius": RRT_SPHERE_RADIUS} for c in spheres]
    return _scenario(planner, round(duration + 5.0, 2), {"type": "rrt", "goal": rounded(goal), "duration": duration},
                     obstacles)


def _blocking_centre(rng: np.random.Generator, start: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """A sphere centre on the segment start -> goal, moved sideways by at most half a radius."""
    direction = (goal - start) / np.linalg.norm(goal - start)
    sideways = np.cross(direction, rng.normal(size=3))
    sideways /= np.linalg.norm(sideways)
    along = start + rng.uniform(0.3, 0.7) * (goal - start)
    return along + rng.uniform(0.0, 0.5) * RRT_SPHERE_RADIUS * sideways


def _scenario(planner: str, duration: float, trajectory: dict[str, Any], obstacles: list[dict[str, Any]]) -> dict[str, Any]:
    return panda_scenario(planner, duration, {"type": "path", "tolerance": 0.05, "trajectory": trajectory}, obstacles)
