"""The goal and obstacle trajectories of a scenario (docs/design.md section 5).

Static goals and obstacles become trajectories at rest; ``trajectory:`` mappings are built
by :func:`dynfab.motion.trajectory_mapping.trajectory_from_mapping`, except ``{type: rrt, goal: P,
duration: T}``, which needs the scenario: an RRT (OMPL) plans a path for the goal link
from its start position to ``P`` around the scenario's static spheres (other shapes are
left to the fabric), and a spline through that path's waypoints reaches ``P`` at ``T``.
An obstacle's trajectory is that of its centre (a plane's point).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from dynfab.geometry.shapes import quaternion_matrix
from dynfab.motion.directions import RotatingDirections
from dynfab.motion.global_planning import GlobalPlanningError, plan_path
from dynfab.motion.reference_checks import first_non_finite
from dynfab.motion.references import References
from dynfab.motion.spline_trajectory import SplineTrajectory
from dynfab.motion.trajectories import (
    StaticPoint,
    Trajectory,
    TrajectoryError,
)
from dynfab.motion.trajectory_mapping import trajectory_from_mapping
from dynfab.robots.robot import Robot
from dynfab.scenario.schema import GoalSpec, Scenario, ScenarioError

_AXES = "xyz"
#: extra room around start, goal and spheres for the RRT's bounding box [m]
RRT_BOUNDS_MARGIN = 0.5
#: clearance the RRT path keeps from sphere surfaces, for the hand's own size [m]
RRT_MARGIN = 0.1


def goal_axes(goal: GoalSpec, robot: Robot) -> list[int]:
    """Indices of the controlled axes of a position or path goal."""
    axes = goal.axes if goal.axes is not None else ("xy" if robot.planar else "xyz")
    return [_AXES.index(a) for a in axes]


def scenario_references(scenario: Scenario, robot: Robot) -> References:
    """Trajectories of every goal (in its coordinates) and obstacle centre (a plane's point).

    Raises:
        ScenarioError: naming the field of an invalid trajectory, or of an RRT goal that
            cannot be planned.
    """
    goals = tuple(_goal_reference(scenario, robot, i) for i in range(len(scenario.goals)))
    obstacles = []
    for k, obstacle in enumerate(scenario.obstacles):
        if obstacle.trajectory is None:
            obstacles.append(StaticPoint(tuple(obstacle.position)))
            continue
        trajectory = _from_mapping(obstacle.trajectory, f"{obstacle.name(k)}.trajectory")
        allowed = (2, 3) if robot.planar else (3,)
        if trajectory.dimension not in allowed:
            raise ScenarioError(f"{obstacle.name(k)}.trajectory", f"expected {' or '.join(map(str, allowed))} "
                                f"coordinates, got {trajectory.dimension}")
        obstacles.append(trajectory)
    orientations = tuple(_orientation_reference(goal) for goal in scenario.goals)
    named = [(f"goal[{i}].trajectory", t) for i, t in enumerate(goals)]
    named += [(f"{o.name(k)}.trajectory", t) for k, (o, t) in enumerate(zip(scenario.obstacles, obstacles))]
    named += [(f"goal[{i}].angular_velocity", t) for i, t in enumerate(orientations) if t is not None]
    for field, trajectory in named:
        _check_finite_over_run(trajectory, field, scenario)
    return References(goals, tuple(obstacles), orientations)


def _check_finite_over_run(trajectory: Trajectory, field: str, scenario: Scenario) -> None:
    """Refuse a reference that turns NaN or infinite during the run (motion/reference_checks.py)."""
    if isinstance(trajectory, StaticPoint):
        return
    failure = first_non_finite(trajectory, scenario.duration, scenario.dt)
    if failure is not None:
        time, quantity = failure
        raise ScenarioError(field, f"the reference's {quantity} is not finite at t = {time:g} s "
                            f"(checked over the run, 0..{scenario.duration:g} s)")


def _orientation_reference(goal: GoalSpec) -> Trajectory | None:
    """Stacked target directions: the columns of a pose goal's rotation, or an axis
    goal's direction (turning at its angular velocity, if any)."""
    if goal.type == "pose":
        return StaticPoint(tuple(quaternion_matrix(goal.orientation).T.ravel()))
    if goal.type == "axis" and goal.angular_velocity is not None:
        return RotatingDirections((goal.direction,), goal.angular_velocity)
    if goal.type == "axis":
        return StaticPoint(goal.direction)
    return None


def _goal_reference(scenario: Scenario, robot: Robot, index: int) -> Trajectory:
    goal = scenario.goals[index]
    field = f"goal[{index}].trajectory"
    if goal.type == "axis":
        return _orientation_reference(goal)
    if goal.type != "path":
        return StaticPoint(tuple(goal.position))
    dimension = len(goal_axes(goal, robot))
    if goal.trajectory.get("type") == "rrt":
        trajectory = _rrt_reference(scenario, robot, goal, field)
    else:
        trajectory = _from_mapping(goal.trajectory, field)
    if trajectory.dimension != dimension:
        raise ScenarioError(field, f"expected {dimension} coordinates for this goal, got {trajectory.dimension}")
    return trajectory


def _from_mapping(data: Mapping[str, Any], field: str) -> Trajectory:
    try:
        return trajectory_from_mapping(data, field)
    except TrajectoryError as error:
        raise ScenarioError(error.field, error.problem) from None


def _rrt_reference(scenario: Scenario, robot: Robot, goal: GoalSpec, field: str) -> Trajectory:
    # keys and ranges were checked with the scenario (scenario/trajectory_schema.py)
    target = np.asarray(goal.trajectory["goal"], dtype=float)
    duration = goal.trajectory["duration"]
    seed = goal.trajectory.get("seed", 0)
    if goal.parent_link is not None:
        raise ScenarioError(f"goal[{scenario.goals.index(goal)}].parent_link",
                            "rrt paths are planned in the world frame; remove parent_link")
    axes = goal_axes(goal, robot)
    start_position = np.asarray(robot.kinematics.position(np.asarray(scenario.initial_state.q),
                                                          goal.link, offset=goal.offset)).ravel()[axes]
    if len(target) != len(axes):
        raise ScenarioError(f"{field}.goal", f"expected {len(axes)} numbers, got {len(target)}")
    spheres = [(np.asarray(o.position, dtype=float)[axes], o.radius)
               for o in scenario.obstacles if o.trajectory is None and o.type == "sphere"]
    for k, (centre, radius) in enumerate(spheres):
        for name, point, where in (("start", start_position, field), ("goal", target, f"{field}.goal")):
            gap = float(np.linalg.norm(point - centre)) - radius
            if gap < RRT_MARGIN:
                raise ScenarioError(where, f"the path's {name} {np.round(point, 3).tolist()} is {gap:.3f} m from "
                                    f"the surface of static sphere {k}; the RRT keeps {RRT_MARGIN} m")
    points = np.vstack([start_position, target] + [centre for centre, _ in spheres])
    extent = max((radius for _, radius in spheres), default=0.0) + RRT_BOUNDS_MARGIN
    try:
        waypoints = plan_path(start_position, target, spheres, margin=RRT_MARGIN, seed=seed,
                              bounds_low=points.min(axis=0) - extent, bounds_high=points.max(axis=0) + extent)
    except GlobalPlanningError as error:
        raise ScenarioError(field, f"RRT found no path: {error}") from None
    return SplineTrajectory(tuple(map(tuple, waypoints)), float(duration))

