"""Experiment 6 scenarios: the Panda holds a static goal while a human hand moves through
the workspace (``shared/EXPERIMENTS.md``, Experiment 6; qualitative in the paper, which
reports a minimum distance of 0.062 m), SF vs DF.

The paper tracked a real hand with motion capture; a synthetic, recorded-like trajectory
stands in for it. The choices:

- start ``q0 = [1, 0, 0, -1.5, 0, 1.8675, 0]`` at rest; hand goal ``[0.5, 0, 0.5]``,
  tolerance 0.05 m; dt 0.01 s, 20 s;
- the hand: a sphere of radius 0.08 m whose centre follows a ``spline`` trajectory (from
  rest to rest, mean speed uniform in ``[0.15, 0.25]`` m/s, at most 17 s long). Its key
  waypoints are computed on the robot's *goal pose* (the configuration that puts the
  hand on the goal closest to ``q0``, by regularized inverse kinematics): it enters from
  one side (``y`` sign drawn at random) 0.8-1.0 m from the goal, passes the robot's
  fingertips, then one of its two forearm spheres, each at a surface gap uniform in
  ``[-0.03, 0.03]`` m (negative: it would touch a robot that kept still) from that side
  (direction ``(a, ±1, b)`` normalized, ``a, b`` Gaussian with std 0.35), and withdraws
  upward to the same side. Between key waypoints two intermediate waypoints are moved
  by a Gaussian of 0.02 m (clipped at 0.04 m): the smooth wiggle of a real hand;
- a draw is rejected unless the hand starts at least 0.3 m (surface) from the robot's
  start pose, stays 0.15 m from the spheres of the robot's base, column and shoulder
  (which can hardly move out of the way) and comes no closer than the smaller pass gap
  minus 0.02 m to any sphere of the goal pose (the wiggle may cut a little deeper).
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from dynfab.motion.spline_trajectory import SplineTrajectory
from dynfab.experiments.panda_sampling import Q0, PandaSampler, panda_scenario
from dynfab.experiments.sampling import rounded

GOAL = np.array([0.5, 0.0, 0.5])
TOLERANCE = 0.05
DURATION = 20.0
HAND_RADIUS = 0.08
SPEED = (0.15, 0.25)  # [m/s] mean speed of the hand along its path
SPLINE_DURATION = (6.0, 17.0)  # [s]
GAP = (-0.03, 0.03)  # [m] surface gap of a pass to the goal pose
DIRECTION_SPREAD = 0.35  # std of the pass direction's x and z components (side = 1)
WIGGLE = 0.02  # [m] std of the intermediate waypoints' offsets
WIGGLE_LIMIT = 0.04  # [m]
WIGGLE_POINTS = 2
WIGGLE_INTRUSION = 0.02  # [m] how much deeper than the pass gaps the wiggled path may come
START_CLEARANCE = 0.3  # [m]
FIXED_CLEARANCE = 0.15  # [m]
#: indices of the Panda's 13 hand-written spheres (``panda_robot("hand-written")``), which name
#: the parts the hand passes; the run itself uses the built-in (fitted) spheres
FIXED_SPHERES = (0, 1, 2)  # base, column, shoulder
FINGERTIPS = 12
FOREARM = (6, 7)  # forearm_low, forearm_high
IK_REGULARIZATION = 0.01
_CHECK_STEP = 0.05  # [s]


@cache
def goal_pose() -> tuple[float, ...]:
    """The configuration that puts the hand on :data:`GOAL` closest to ``q0``
    (regularized least squares within the joint limits)."""
    sampler = PandaSampler.create("hand-written")  # the indices below name its spheres
    start = np.array(Q0)

    def residual(q: np.ndarray) -> np.ndarray:
        return np.concatenate([sampler.hand_position(tuple(q)) - GOAL, IK_REGULARIZATION * (q - start)])

    solution = least_squares(residual, start, bounds=(sampler.lower, sampler.upper), xtol=1e-12, ftol=1e-12)
    return tuple(float(v) for v in solution.x)


def scenario(seed: int, planner: str = "dynamic-fabric") -> dict[str, Any]:
    """Experiment 6, run ``seed``."""
    rng = np.random.default_rng(seed)
    sampler = PandaSampler.create("hand-written")  # the indices below name its spheres
    centres = np.array(sampler.spheres(goal_pose())).T
    start_centres = np.array(sampler.spheres(Q0)).T
    fixed = list(FIXED_SPHERES)
    while True:
        side = float(rng.choice([-1.0, 1.0]))
        gaps = rng.uniform(*GAP, size=2)
        forearm = int(rng.choice(FOREARM))
        hand_pass = _pass_point(rng, centres[FINGERTIPS], sampler.sphere_radii[FINGERTIPS], gaps[0], side)
        forearm_pass = _pass_point(rng, centres[forearm], sampler.sphere_radii[forearm], gaps[1], side)
        start = GOAL + np.array([rng.uniform(-0.1, 0.3), side * rng.uniform(0.8, 1.0), rng.uniform(-0.1, 0.4)])
        end = forearm_pass + np.array([rng.uniform(-0.2, 0.2), side * rng.uniform(0.5, 0.7), rng.uniform(0.2, 0.4)])
        waypoints = _wiggled(rng, [start, hand_pass, forearm_pass, end])
        length = float(np.sum(np.linalg.norm(np.diff(waypoints, axis=0), axis=1)))
        duration = round(float(np.clip(length / rng.uniform(*SPEED), *SPLINE_DURATION)), 2)
        path = SplineTrajectory(tuple(map(tuple, waypoints)), duration).sample(np.arange(0.0, duration, _CHECK_STEP))[0]
        if (_clearance(path[:1], start_centres, sampler.sphere_radii) > START_CLEARANCE
                and _clearance(path, centres[fixed], sampler.sphere_radii[fixed]) > FIXED_CLEARANCE
                and _clearance(path, centres, sampler.sphere_radii) > gaps.min() - WIGGLE_INTRUSION):
            break
    hand = {"type": "sphere", "radius": HAND_RADIUS,
            "trajectory": {"type": "spline", "waypoints": [rounded(p) for p in waypoints], "duration": duration}}
    goal_spec = {"type": "position", "position": rounded(GOAL), "tolerance": TOLERANCE}
    return panda_scenario(planner, DURATION, goal_spec, [hand])


def _pass_point(rng: np.random.Generator, centre: np.ndarray, radius: float, gap: float, side: float) -> np.ndarray:
    """Where the hand's centre passes a robot sphere: ``gap`` from its surface, from ``side``."""
    direction = np.array([rng.normal(0.0, DIRECTION_SPREAD), side, rng.normal(0.0, DIRECTION_SPREAD)])
    return centre + (radius + HAND_RADIUS + gap) * direction / np.linalg.norm(direction)


def _wiggled(rng: np.random.Generator, keys: list[np.ndarray]) -> np.ndarray:
    """The key waypoints with :data:`WIGGLE_POINTS` jittered points between each pair."""
    points = [keys[0]]
    for a, b in zip(keys[:-1], keys[1:]):
        for k in range(1, WIGGLE_POINTS + 1):
            offset = np.clip(rng.normal(0.0, WIGGLE, 3), -WIGGLE_LIMIT, WIGGLE_LIMIT)
            points.append(a + k / (WIGGLE_POINTS + 1) * (b - a) + offset)
        points.append(b)
    return np.round(np.array(points), 4)


def _clearance(path: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> float:
    """Smallest surface distance between the hand along ``path`` and the given spheres."""
    distances = np.linalg.norm(path[:, None, :] - centres[None, :, :], axis=2) - radii[None, :] - HAND_RADIUS
    return float(distances.min())
