"""Scenario references (:mod:`dynfab.scenario.references`): static goals and obstacles as trajectories
at rest, dimension checks naming the field, and ``rrt`` goals planned around static spheres."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from dynfab.motion.references import References
from dynfab.scenario.references import RRT_MARGIN, scenario_references
from dynfab.robots.robot import Robot
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import Scenario, ScenarioError, scenario_from_dict, validate_for_robot
from dynfab.motion.spline_trajectory import SplineTrajectory
from dynfab.motion.trajectories import (
    CircleTrajectory,
    ExpressionTrajectory,
    LinearTrajectory,
    StaticPoint,
    Trajectory,
)

PANDA_Q0 = [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]
TIMES = np.array([0.0, 0.7, 3.0, 25.0])
RRT_GOAL = [0.45, -0.45, 0.45]

#: Spheres that block the straight line from the hand's start to the goal (per case).
BLOCKING_SPHERES: dict[str, tuple[list[float], list[tuple[list[float], float]]]] = {
    "two": ([0.45, -0.45, 0.45], [([0.4, 0.08, 0.5], 0.12), ([0.45, -0.22, 0.45], 0.08)]),
    "wall": ([0.45, -0.45, 0.45], [([0.4, 0.0, 0.5], 0.12), ([0.4, 0.0, 0.75], 0.12), ([0.4, 0.0, 0.25], 0.12)]),
    "three": ([0.5, -0.4, 0.6], [([0.42, 0.1, 0.6], 0.1), ([0.48, -0.15, 0.6], 0.1), ([0.5, -0.05, 0.4], 0.1)]),
}


def scenario(goals: list[dict[str, Any]], obstacles: list[dict[str, Any]] | None = None,
             robot: str = "panda", q: list[float] | None = None) -> dict[str, Any]:
    """A scenario mapping for the references (the planner does not matter to them)."""
    return {
        "robot": robot,
        "planner": "dynamic-fabric",
        "dt": 0.01,
        "duration": 10.0,
        "initial_state": {"q": q if q is not None else (PANDA_Q0 if robot == "panda" else [0.0, 0.0])},
        "goal": goals,
        "obstacles": obstacles or [],
    }


def prepare(data: dict[str, Any]) -> tuple[Scenario, Robot]:
    """Validate a mapping for its robot, as the runner does before building references."""
    parsed = scenario_from_dict(data)
    robot = robot_for(parsed)
    return validate_for_robot(parsed, robot), robot


def references(data: dict[str, Any]) -> References:
    """The references of a scenario mapping."""
    return scenario_references(*prepare(data))


def path_goal(trajectory: dict[str, Any], **extra: Any) -> dict[str, Any]:
    """A Panda path goal for the hand."""
    return {"type": "path", "link": "panda_hand", "trajectory": trajectory, **extra}


def rrt(goal: list[float] = RRT_GOAL, duration: float = 8.0, **extra: Any) -> dict[str, Any]:
    """An ``rrt`` trajectory mapping."""
    return {"type": "rrt", "goal": goal, "duration": duration, **extra}


def sphere(position: list[float], radius: float) -> dict[str, Any]:
    """A static sphere obstacle."""
    return {"type": "sphere", "position": position, "radius": radius}


def hand_start(scenario_: Scenario, robot: Robot) -> np.ndarray:
    """The hand's position in the scenario's initial configuration."""
    q = np.asarray(scenario_.initial_state.q)
    return np.asarray(robot.kinematics.position(q, "panda_hand")).ravel()


def segment_distance(a: np.ndarray, b: np.ndarray, point: np.ndarray) -> float:
    """Distance from ``point`` to the segment from ``a`` to ``b``."""
    direction = b - a
    along = np.clip((point - a) @ direction / (direction @ direction), 0.0, 1.0)
    return float(np.linalg.norm(point - a - along * direction))


def assert_at_rest(trajectory: Trajectory, position: list[float]) -> None:
    """``trajectory`` is a point at rest at ``position`` at every time of TIMES."""
    assert isinstance(trajectory, StaticPoint)
    positions, velocities, accelerations = trajectory.sample(TIMES)
    np.testing.assert_array_equal(positions, np.tile(position, (TIMES.size, 1)))
    assert not velocities.any() and not accelerations.any()


def raises_for(data: dict[str, Any], field: str) -> ScenarioError:
    """Building the references of ``data`` fails naming exactly ``field``."""
    with pytest.raises(ScenarioError) as caught:
        references(data)
    assert caught.value.field == field, str(caught.value)
    assert str(caught.value).startswith(f"{field}: ")
    return caught.value


# -- static goals and obstacles ---------------------------------------------------------

def test_static_goals_and_obstacles_become_trajectories_at_rest() -> None:
    joint_target = [-0.5, -0.4, 0.3, -2.2, 0.2, 1.9, 0.6]
    refs = references(scenario(
        [{"type": "position", "link": "panda_hand", "position": [0.5, -0.3, 0.4]},
         {"type": "position", "link": "panda_link7", "axes": "xy", "position": [0.5, -0.3], "weight": 0.5},
         {"type": "joint", "position": joint_target, "weight": 0.1}],
        [sphere([0.5, 0.2, 0.5], 0.15), sphere([0.1, -0.5, 0.8], 0.1)]))
    assert len(refs.goals) == 3 and len(refs.obstacles) == 2
    assert_at_rest(refs.goals[0], [0.5, -0.3, 0.4])
    assert_at_rest(refs.goals[1], [0.5, -0.3])
    assert_at_rest(refs.goals[2], joint_target)
    assert_at_rest(refs.obstacles[0], [0.5, 0.2, 0.5])
    assert_at_rest(refs.obstacles[1], [0.1, -0.5, 0.8])


def test_planar_static_obstacle_keeps_its_two_coordinates() -> None:
    refs = references(scenario([{"type": "position", "link": "point", "position": [1.0, 0.5]}],
                               [sphere([0.4, 0.2], 0.2), sphere([-0.3, 0.6, 0.0], 0.1)], robot="point"))
    assert_at_rest(refs.goals[0], [1.0, 0.5])
    assert_at_rest(refs.obstacles[0], [0.4, 0.2])
    assert_at_rest(refs.obstacles[1], [-0.3, 0.6, 0.0])


def test_moving_goal_and_obstacles_keep_their_trajectories_in_order() -> None:
    circle = {"type": "circle", "center": [0.45, 0.0, 0.55], "radius": 0.2, "angular_velocity": 0.6,
              "normal": [1, 0, 0], "phase": 1.5708}
    linear = {"type": "linear", "start": [-1.0, -0.4, 0.7], "velocity": [0.1, 0.0, 0.0]}
    expression = {"type": "expression", "x": ["0.3", "0.1*t", "0.5 + 0.1*sin(t)"]}
    refs = references(scenario([path_goal(circle)],
                               [{"type": "sphere", "radius": 0.1, "trajectory": linear},
                                sphere([0.1, -0.5, 0.8], 0.1),
                                {"type": "sphere", "radius": 0.1, "trajectory": expression}]))
    assert isinstance(refs.goals[0], CircleTrajectory)
    assert isinstance(refs.obstacles[0], LinearTrajectory)
    assert isinstance(refs.obstacles[1], StaticPoint)
    assert isinstance(refs.obstacles[2], ExpressionTrajectory)
    np.testing.assert_allclose(refs.obstacles[0].evaluate(2.0).position, [-0.8, -0.4, 0.7])
    np.testing.assert_allclose(refs.obstacles[0].evaluate(2.0).velocity, [0.1, 0.0, 0.0])
    np.testing.assert_allclose(refs.goals[0].evaluate(0.0).position, [0.45, 0.0, 0.75], atol=1e-5)


# -- dimensions -------------------------------------------------------------------------

def test_path_goal_dimension_must_match_its_axes() -> None:
    circle_2d = {"type": "circle", "center": [0.45, 0.0], "radius": 0.2, "angular_velocity": 0.6}
    line_3d = {"type": "linear", "start": [0.3, 0.3, 0.5], "velocity": [0.0, 0.0, 0.0]}
    line_2d = {"type": "linear", "start": [0.3, 0.3], "velocity": [0.01, 0.0]}
    error = raises_for(scenario([path_goal(circle_2d)]), "goal[0].trajectory")
    assert "expected 3 coordinates" in error.problem and "got 2" in error.problem
    error = raises_for(scenario([path_goal(line_3d, axes="xy")]), "goal[0].trajectory")
    assert "expected 2 coordinates" in error.problem and "got 3" in error.problem
    error = raises_for(scenario([{"type": "position", "link": "panda_hand", "position": [0.5, 0.0, 0.4]},
                                 path_goal(line_2d)]), "goal[1].trajectory")
    assert "expected 3 coordinates" in error.problem
    planar_goal = {"type": "path", "link": "point", "trajectory": line_3d}
    error = raises_for(scenario([planar_goal], robot="point"), "goal[0].trajectory")
    assert "expected 2 coordinates" in error.problem
    assert references(scenario([path_goal(line_2d, axes="xz")])).goals[0].dimension == 2


def test_obstacle_trajectory_of_wrong_dimension_is_rejected() -> None:
    flat = {"type": "linear", "start": [0.0, 0.0], "velocity": [0.1, 0.0]}
    goal = {"type": "position", "link": "panda_hand", "position": [0.5, 0.0, 0.4]}
    error = raises_for(scenario([goal], [sphere([0.5, 0.2, 0.5], 0.1),
                                         {"type": "sphere", "radius": 0.1, "trajectory": flat}]),
                       "obstacles[1].trajectory")
    assert "expected 3 coordinates, got 2" in error.problem
    planar = references(scenario([{"type": "position", "link": "point", "position": [1.0, 0.0]}],
                                 [{"type": "sphere", "radius": 0.1, "trajectory": flat}], robot="point"))
    assert planar.obstacles[0].dimension == 2


def test_invalid_trajectory_field_is_named_with_its_scenario_path() -> None:
    bad_velocity = {"type": "linear", "start": [0.0, 0.0, 0.5], "velocity": [0.1, 0.0]}
    goal = {"type": "position", "link": "panda_hand", "position": [0.5, 0.0, 0.4]}
    raises_for(scenario([goal], [{"type": "sphere", "radius": 0.1, "trajectory": bad_velocity}]),
               "obstacles[0].trajectory.velocity")
    raises_for(scenario([path_goal({"type": "spline", "waypoints": [[0.3, 0.3, 0.5]], "duration": 4.0})]),
               "goal[0].trajectory.waypoints")


# -- rrt --------------------------------------------------------------------------------

@pytest.mark.parametrize("case", list(BLOCKING_SPHERES))
@pytest.mark.parametrize("seed", range(3))
def test_rrt_spline_runs_from_the_hand_to_the_goal_around_static_spheres(case: str, seed: int) -> None:
    goal, spheres = BLOCKING_SPHERES[case]
    data = scenario([path_goal(rrt(goal, duration=8.0, seed=seed))], [sphere(c, r) for c, r in spheres])
    parsed, robot = prepare(data)
    start = hand_start(parsed, robot)
    assert any(segment_distance(start, np.asarray(goal), np.asarray(c)) < r for c, r in spheres), \
        "the straight line should be blocked, so that the RRT has to detour"
    trajectory = scenario_references(parsed, robot).goals[0]
    assert isinstance(trajectory, SplineTrajectory)
    assert trajectory.duration == 8.0
    assert len(trajectory.waypoints) >= 3, "no detour around the blocking spheres"
    begin, end = trajectory.evaluate(0.0), trajectory.evaluate(8.0)
    np.testing.assert_allclose(begin.position, start, atol=1e-9)
    np.testing.assert_allclose(end.position, goal, atol=1e-9)
    np.testing.assert_allclose(begin.velocity, 0.0, atol=1e-12)  # clamped: from rest to rest
    assert not end.velocity.any()
    positions = trajectory.sample(np.linspace(0.0, 8.0, 200))[0]
    for k, (centre, radius) in enumerate(spheres):
        closest = float(np.min(np.linalg.norm(positions - np.asarray(centre), axis=1)))
        assert closest >= radius + RRT_MARGIN - 0.02, \
            f"{case} seed {seed}: spline {closest:.4f} m from sphere {k}, needs {radius + RRT_MARGIN:.2f} m"


def test_rrt_is_deterministic_for_a_seed() -> None:
    goal, spheres = BLOCKING_SPHERES["wall"]
    data = scenario([path_goal(rrt(goal, seed=4))], [sphere(c, r) for c, r in spheres])
    first = references(data).goals[0]
    assert isinstance(first, SplineTrajectory)
    assert first == references(data).goals[0]


def test_rrt_ignores_moving_obstacles() -> None:
    """A sphere on a trajectory is left to the reactive planner: the RRT neither avoids it
    nor refuses a goal that it starts on."""
    on_goal = {"type": "sphere", "radius": 0.15,
               "trajectory": {"type": "linear", "start": RRT_GOAL, "velocity": [0.0, 0.05, 0.0]}}
    data = scenario([path_goal(rrt())], [on_goal])
    parsed, robot = prepare(data)
    with_moving = scenario_references(parsed, robot).goals[0]
    without = references(scenario([path_goal(rrt())])).goals[0]
    assert isinstance(with_moving, SplineTrajectory)
    assert with_moving == without
    assert len(with_moving.waypoints) == 2, "free space: the RRT path is the straight segment"
    np.testing.assert_allclose(with_moving.waypoints[0], hand_start(parsed, robot), atol=1e-9)
    np.testing.assert_allclose(with_moving.waypoints[-1], RRT_GOAL)


def test_planar_rrt_plans_in_the_plane() -> None:
    goal = {"type": "path", "link": "point", "trajectory": rrt([1.0, 0.5], duration=5.0)}
    trajectory = references(scenario([goal], [sphere([0.5, 0.25], 0.1)], robot="point")).goals[0]
    assert isinstance(trajectory, SplineTrajectory) and trajectory.dimension == 2
    np.testing.assert_allclose(trajectory.waypoints[0], [0.0, 0.0])
    np.testing.assert_allclose(trajectory.waypoints[-1], [1.0, 0.5])
    positions = trajectory.sample(np.linspace(0.0, 5.0, 200))[0]
    assert np.min(np.linalg.norm(positions - [0.5, 0.25], axis=1)) >= 0.1 + RRT_MARGIN - 0.02


@pytest.mark.parametrize(("trajectory", "field", "problem"), [
    (rrt(speed=0.1), "goal[0].trajectory.speed", "unknown key"),
    (rrt(waypoints=[[0.0, 0.0, 0.0]]), "goal[0].trajectory.waypoints", "unknown key"),
    (rrt(duration=0), "goal[0].trajectory.duration", "must be >= 0.01 s, got 0"),
    (rrt(duration=-3.0), "goal[0].trajectory.duration", "must be >= 0.01 s, got -3"),
    (rrt(duration="5"), "goal[0].trajectory.duration", "expected a number, got str '5'"),
    (rrt(duration=True), "goal[0].trajectory.duration", "expected a number, got boolean true"),
    (rrt(duration=float("inf")), "goal[0].trajectory.duration", "expected a finite number"),
    (rrt(duration=1e300), "goal[0].trajectory.duration", "must be at most 10000 s"),
    ({"type": "rrt", "goal": RRT_GOAL}, "goal[0].trajectory.duration", "missing required key"),
    (rrt(goal=[0.45, -0.45]), "goal[0].trajectory.goal", "expected 3 numbers, got 2"),
    (rrt(goal=[0.45, -0.45, 0.45, 0.0]), "goal[0].trajectory.goal", "expected at most 3 numbers, got 4"),
    (rrt(goal=[0.45, -0.45, 1e300]), "goal[0].trajectory.goal[2]", "must be at most 1000 m"),
    (rrt(goal="far away"), "goal[0].trajectory.goal", "expected a list, got str 'far away'"),
    ({"type": "rrt", "duration": 5.0}, "goal[0].trajectory.goal", "missing required key"),
    (rrt(seed=-1), "goal[0].trajectory.seed", "expected an integer from 0 to 2147483647, got -1"),
    (rrt(seed=10**20), "goal[0].trajectory.seed", "expected an integer from 0 to 2147483647, got 1e+20"),
    (rrt(seed=1.5), "goal[0].trajectory.seed", "expected an integer, got float 1.5"),
])
def test_invalid_rrt_fields_are_named(trajectory: dict[str, Any], field: str, problem: str) -> None:
    error = raises_for(scenario([path_goal(trajectory)]), field)
    assert problem in error.problem


def test_rrt_goal_inside_a_sphere_is_named() -> None:
    error = raises_for(scenario([path_goal(rrt())], [sphere([0.1, -0.5, 0.8], 0.1), sphere([0.45, -0.4, 0.45], 0.1)]),
                       "goal[0].trajectory.goal")
    assert "goal" in error.problem and "sphere 1" in error.problem, error.problem


def test_rrt_start_inside_a_sphere_is_named() -> None:
    error = raises_for(scenario([path_goal(rrt())], [sphere([0.33, 0.5, 0.6], 0.05)]), "goal[0].trajectory")
    assert "start" in error.problem and "sphere 0" in error.problem, error.problem


def test_rrt_on_a_subset_of_axes_uses_those_axes_of_the_spheres() -> None:
    # Seen on y, z this sphere is at (0.45, 3.0), far from everything; its x, y are the goal's y, z.
    far_above = sphere([-0.45, 0.45, 3.0], 0.1)
    trajectory = references(scenario([path_goal(rrt([-0.45, 0.45]), axes="yz")], [far_above])).goals[0]
    assert isinstance(trajectory, SplineTrajectory)
    np.testing.assert_allclose(trajectory.waypoints[-1], [-0.45, 0.45])
