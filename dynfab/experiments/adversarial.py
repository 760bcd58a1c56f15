"""Seeded adversarial planner calls: is every command finite and within the limits?

For each planner case (Panda, Boxer, Boxer+Panda; static and dynamic) the planner is
built once with three sphere slots and one box slot, then called on states and
parameters drawn to hurt: obstacle centres within 1e-9..1e-5 m of a robot sphere's
centre (an obstacle perceived inside the robot), obstacles on top of each other, a box
centred on the robot, goals at zero distance and 10³ m away, joints at, beyond and just
inside their position limits, speeds at and up to 10× beyond their limits, obstacles and
goals moving at up to 10 m/s. A call passes when the command is finite and
``|ü_i| ≤ a_max,i`` for every velocity coordinate.

Used by ``bench/bench_bounded_output.py`` (10⁵ calls) and by the tests (fewer).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from dynfab.fabric.parameters import ShapeSlots
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots import Robot, load_robot

#: (robot, dynamic) of every case
CASES: tuple[tuple[str, bool], ...] = tuple((robot, dynamic) for robot in ("panda", "boxer", "boxer-panda")
                                            for dynamic in (False, True))


@dataclass(frozen=True)
class CallStatistics:
    """What the calls of one case returned.

    Attributes:
        case: ``"robot static|dynamic"``.
        calls: number of calls.
        non_finite: calls with a NaN or infinite command.
        beyond_limits: calls with some ``|ü_i| > a_max,i``.
        max_acceleration_ratio: largest ``|ü_i| / a_max,i`` seen.
        fallbacks: calls answered by the planner's fallback action.
    """

    case: str
    calls: int
    non_finite: int
    beyond_limits: int
    max_acceleration_ratio: float
    fallbacks: int


def case_planner(robot_name: str, dynamic: bool) -> FabricPlanner:
    """The planner of one case: a position goal on the robot's goal link, 3 sphere slots
    and one box slot."""
    robot = load_robot(robot_name)
    goal = GoalConfig(link=robot.goal_link)
    config = PlannerConfig.for_robot(robot, (goal,), obstacle_slots=3, dynamic=dynamic,
                                     shape_slots=ShapeSlots(box=1))
    return FabricPlanner(robot, config)


def run_case(robot_name: str, dynamic: bool, calls: int, seed: int = 0) -> CallStatistics:
    """``calls`` adversarial calls of one case."""
    planner = case_planner(robot_name, dynamic)
    peak = planner.config.limits.acceleration
    rng = np.random.default_rng(seed)
    non_finite = beyond = 0
    worst = 0.0
    for q, qdot in _states(planner.robot, planner, rng, calls):
        command = planner.compute(q, qdot)
        if not np.isfinite(command).all():
            non_finite += 1
            continue
        ratio = float(np.max(np.abs(command) / peak))
        worst = max(worst, ratio)
        beyond += ratio > 1.0 + 1e-9
    kind = "dynamic" if dynamic else "static"
    return CallStatistics(f"{robot_name} {kind}", calls, non_finite, beyond, worst, planner.fallback_count)


def _states(robot: Robot, planner: FabricPlanner, rng: np.random.Generator,
            calls: int) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Draw each call's state and write its parameters into the planner."""
    for _ in range(calls):
        q = _configuration(robot, rng)
        qdot = _velocity(planner, rng)
        _write_parameters(planner, robot, q, rng)
        yield q, qdot


def _configuration(robot: Robot, rng: np.random.Generator) -> np.ndarray:
    kin = robot.kinematics
    lower = np.where(np.isfinite(kin.lower), kin.lower, -3.0)
    upper = np.where(np.isfinite(kin.upper), kin.upper, 3.0)
    span = upper - lower
    mode = rng.integers(4)
    if mode == 0:    # anywhere inside
        return rng.uniform(lower, upper)
    if mode == 1:    # exactly at a limit
        return np.where(rng.random(kin.dof) < 0.5, lower, upper)
    if mode == 2:    # beyond a limit by up to 0.5
        return np.where(rng.random(kin.dof) < 0.5, lower - rng.uniform(0, 0.5, kin.dof),
                        upper + rng.uniform(0, 0.5, kin.dof))
    return rng.uniform(lower + 0.05 * span, upper - 0.05 * span)   # 5 % inside


def _velocity(planner: FabricPlanner, rng: np.random.Generator) -> np.ndarray:
    limit = planner.config.limits.velocity
    mode = rng.integers(4)
    if mode == 0:
        return np.zeros_like(limit)
    if mode == 1:
        return rng.choice([-1.0, 1.0], limit.size) * limit
    if mode == 2:
        return rng.uniform(-10, 10, limit.size) * limit
    return rng.uniform(-1, 1, limit.size) * limit


def _write_parameters(planner: FabricPlanner, robot: Robot, q: np.ndarray, rng: np.random.Generator) -> None:
    params = planner.parameters
    centres = robot.sphere_centers(q)
    goal = params.goal_position[0]
    link_position = np.array(robot.kinematics.position(q, robot.goal_link), dtype=float).ravel()[:goal.size]
    goal_mode = rng.integers(3)
    goal[:] = (link_position if goal_mode == 0 else
               link_position + rng.normal(size=goal.size) * 1e3 if goal_mode == 1 else
               rng.uniform(-1, 1, goal.size))
    inside = centres[rng.integers(len(centres))] + rng.normal(size=3) * 10.0 ** rng.uniform(-9, -5)
    for k in range(params.obstacle_radius.size):
        mode = rng.integers(3)
        params.obstacle_position[k] = inside if mode < 2 else rng.uniform(-1.5, 1.5, 3)
        params.obstacle_radius[k] = rng.uniform(0.01, 0.5)
    box = params.boxes
    box.position[0] = centres[rng.integers(len(centres))] + rng.normal(size=3) * 10.0 ** rng.uniform(-9, -1)
    box.orientation[0] = _unit(rng.normal(size=4))
    box.dimensions[0] = rng.uniform(0.01, 1.0, 3)
    if planner.config.dynamic:
        for views in (params.goal_velocity[0], params.goal_acceleration[0]):
            views[:] = rng.normal(size=views.size) * 10.0 ** rng.uniform(-3, 1)
        for array in (params.obstacle_velocity, params.obstacle_acceleration, box.velocity, box.acceleration):
            array[:] = rng.normal(size=array.shape) * 10.0 ** rng.uniform(-3, 1)


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / np.linalg.norm(vector)
