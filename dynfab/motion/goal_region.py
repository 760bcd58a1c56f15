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

from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from dynfab.motion.inverse_kinematics import AxisTarget, IkResult, IkSettings, PointTarget, solve_ik
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.robots.robot import Robot

__all__ = ["nearby_solution", "nearby_targets", "roomier_configuration"]


def nearby_solution(robot: Robot, goal: Sequence[PointTarget | AxisTarget], q: NDArray[np.float64],
                    free: Callable[[NDArray[np.float64]], bool], fraction: float, count: int, ik: IkSettings,
                    bounds: tuple[NDArray[np.float64], NDArray[np.float64]]) -> IkResult | None:
    """The first solution ``free`` accepts of up to ``count`` nearby targets
    (:func:`nearby_targets` within ``fraction`` of the tolerances; the ``k``-th solved with
    ``ik`` seeded ``ik.seed + 1 + k``, the targets drawn from ``ik.seed``), nearest ``q``
    within ``bounds`` (lower, upper); None if none is found or no target has a tolerance."""
    if not any(target.tolerance > 0.0 for target in goal):
        return None
    rng = np.random.default_rng(ik.seed)
    for k in range(count):
        result = solve_ik(robot, nearby_targets(goal, fraction, rng), q, free, replace(ik, seed=ik.seed + 1 + k),
                          *bounds)
        if result.q is not None:
            return result
    return None


def roomier_configuration(target: NDArray[np.float64], radius: float, meshes: MeshGoalCheck, floor: float,
                          count: int, bounds: tuple[NDArray[np.float64], NDArray[np.float64]],
                          rng: np.random.Generator) -> NDArray[np.float64] | None:
    """Of ``count`` configurations uniform in the ball of ``radius`` [rad] about ``target``
    (clipped to ``bounds``), the one free on the robot's ``meshes`` by ``floor`` [m] that is
    farthest from the scene on them, if farther than ``target`` is; else None (a joint goal's
    counterpart of :func:`nearby_solution`, for a goal with no way in)."""
    directions = rng.normal(size=(count, target.size))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radii = radius * rng.uniform(size=(count, 1)) ** (1.0 / target.size)
    best, room = None, meshes.clearance(target)[0]
    for candidate in np.clip(target + radii * directions, *bounds):
        clearance = meshes.clearance(candidate)[0]
        if clearance > room and meshes.free(candidate, floor):
            best, room = candidate, clearance
    return best


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
