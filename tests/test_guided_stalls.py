"""Two ways a guided run stalled short of its goal on MotionBenchMaker (issues 19, 20), in
small scenes: a reference whose clock ran on around a corner the robot was held behind
(moving-sphere bookshelf_thin/0019), and a replan of a pose goal after a stall that solved
inverse kinematics again and went to a configuration far away (table_bars/0008)."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.geometry.shapes import Placement, Sphere
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import JointGuidance, JointTarget
from dynfab.motion.inverse_kinematics import PointTarget
from dynfab.motion.plan_requests import PlanRequest, make_plan
from dynfab.robots import load_robot
from dynfab.scenario.references import scenario_references
from dynfab.scenario.guided_controller import make_scenario_controller
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
from wall_scene import GOAL, START, WALL, WALL_ENTRY

DT = 0.01
#: how far [rad] the reference has moved from START where a sphere is put in its way
AHEAD = 0.06


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def _guided(panda):
    data = {"robot": "panda", "planner": "dynamic-fabric", "dt": DT, "duration": 5.0,
            "initial_state": {"q": START.tolist()}, "goal": [{"type": "joint", "position": GOAL.tolist()}],
            "obstacles": [WALL_ENTRY]}
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    return make_scenario_controller(scenario, panda, scenario_references(scenario, panda), plan_latency=0.0).guided


def _lag_after_one_second(panda, obstacle: PlacedObstacle | None) -> float:
    """The robot held at START for 1 s behind a plan made at once, with ``obstacle`` added to
    the static ones after the plan (in the way of the reference, not of the robot): how far
    [rad] the reference then is from START."""
    guided = _guided(panda)
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)
    plan = guided.plan
    if obstacle is not None:
        guided.set_obstacles((WALL, obstacle))
    for step in range(1, 101):
        guided.update(step * DT, START)
    assert guided.status.replans_stalled == 0 and guided.plan is plan
    return float(np.linalg.norm(guided.fabric.parameters.goal_position[0] - START))


def _sphere_in_the_way(panda, guided_plan_point: np.ndarray) -> PlacedObstacle:
    """A 5 mm sphere just ahead of the robot's sphere that moves most from START to ``guided_plan_point``."""
    start = np.asarray(panda.sphere_centers(START), dtype=float)
    there = np.asarray(panda.sphere_centers(guided_plan_point), dtype=float)
    i = int(np.argmax(np.linalg.norm(there - start, axis=1)))
    direction = (there[i] - start[i]) / np.linalg.norm(there[i] - start[i])
    radius = float(panda.sphere_radii[i])
    return PlacedObstacle(Sphere(0.005), Placement(tuple(there[i] + direction * radius)))


def test_the_reference_waits_for_a_robot_that_cannot_see_it(panda) -> None:
    assert _lag_after_one_second(panda, None) > 2 * AHEAD   # the lag rule alone lets the reference run on
    guided = _guided(panda)
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)
    trajectory = guided.plan.trajectory
    times = np.linspace(0.0, trajectory.duration, 2001)
    ahead = times[np.argmax(np.linalg.norm(trajectory.sample(times)[0] - START, axis=1) > AHEAD)]
    point = trajectory.evaluate(float(ahead)).position
    obstacle = _sphere_in_the_way(panda, point)
    checker = ConfigurationChecker(panda, [obstacle])
    assert checker.clearances(START)[0] > 0.0 and checker.clearances(point)[0] < 0.0
    assert _lag_after_one_second(panda, obstacle) < AHEAD   # it waits where the straight way to it is blocked


def test_a_replan_of_a_point_goal_keeps_the_configuration_the_robot_was_heading_for(panda) -> None:
    guidance = JointGuidance(panda)
    hand = tuple(float(v) for v in np.asarray(panda.kinematics.position(GOAL, panda.goal_link)).ravel())
    goal = [PointTarget(panda.goal_link, hand)]
    fresh = guidance.goal_configuration(goal, START)
    assert np.linalg.norm(fresh - GOAL) > 0.1  # inverse kinematics from START finds another configuration
    request = PlanRequest(1.0, START, goal, (WALL,), (), GOAL.copy(), 0, True, (0.005,), "held")
    outcome = make_plan(guidance, request)
    assert outcome.plan is not None
    np.testing.assert_allclose(outcome.plan.goal, GOAL)
