"""Targets inside a goal's tolerance: where no inverse-kinematics solution of the exact goal
is free, guidance looks for one of a nearby target the goal still accepts.

A goal is reached within its tolerances (a point within ``tolerance`` [m], an axis within
``tolerance`` [rad]; a pose is a point and three axes). A grasp pose a fraction of a
millimetre from a scene has no solution that keeps guidance's floor on the meshes
(``mesh_goal_floor``, 2 mm), while poses a few millimetres away, still inside the goal, may:
MotionBenchMaker's table_bars problems 5 of seed 5 and 16 of seed 8 (development; each
``no_ik_solution`` before) are reached with it, and so is fresh seed 11's problem 17 (19/20
→ 20/20). Its kitchen goals of that kind (seeds 4 and 11: four, their exact solutions
0.45-1.8 mm from the kitchen) are not: two get a solution, but no path into their pocket.

A nearby target moves

- every point target by a uniform sample of the ball of radius ``f·tolerance`` (on its axes):
  ``p' = p + u``, ``‖u‖ ≤ f·tolerance``;
- every axis target by one common rotation ``R`` about a uniform random axis by an angle
  uniform in ``[0, f·tolerance]`` (the smallest tolerance of the axis targets), ``d' = R d``,
  so that a pose's three axes stay a frame and its orientation error is that angle;

with ``f`` the ``fraction`` of the tolerances used (``GuidanceSettings.goal_region``, 1/2: the
fabric settles at the solution within a few millimetres and milliradians, and the rest of
the tolerance is left for that). Targets without a tolerance stay where they are.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation

from dynfab.motion.inverse_kinematics import AxisTarget, PointTarget

__all__ = ["nearby_targets"]


def nearby_targets(targets: Sequence[PointTarget | AxisTarget], fraction: float,
                   rng: np.random.Generator) -> list[PointTarget | AxisTarget]:
    """``targets`` moved within ``fraction`` of their tolerances (module docstring)."""
    angles = [t.tolerance for t in targets if isinstance(t, AxisTarget) and t.tolerance > 0.0]
    turn = Rotation.identity()
    if angles:
        axis = rng.normal(size=3)
        turn = Rotation.from_rotvec(axis / np.linalg.norm(axis) * rng.uniform(0.0, fraction * min(angles)))
    moved: list[PointTarget | AxisTarget] = []
    for target in targets:
        if isinstance(target, PointTarget) and target.tolerance > 0.0:
            moved.append(replace(target, position=tuple(float(v) for v in np.asarray(target.position, dtype=float)
                                                        + _in_ball(len(target.position), fraction * target.tolerance,
                                                                   rng))))
        elif isinstance(target, AxisTarget) and target.tolerance > 0.0:
            moved.append(replace(target, direction=tuple(float(v) for v in turn.apply(target.direction))))
        else:
            moved.append(target)
    return moved


def _in_ball(dimension: int, radius: float, rng: np.random.Generator) -> np.ndarray:
    """A uniform sample of the ``dimension``-ball of ``radius`` [m]."""
    direction = rng.normal(size=dimension)
    return direction / np.linalg.norm(direction) * radius * rng.uniform() ** (1.0 / dimension)
