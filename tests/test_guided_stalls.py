"""Two ways a guided run stalled short of its goal on MotionBenchMaker (issues 19, 20), in
small scenes: a reference whose clock ran on around a corner the robot was held behind
(moving-sphere bookshelf_thin/0019), and a replan of a pose goal after a stall that solved
inverse kinematics again and went to a configuration far away (table_bars/0008)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.geometry.shapes import Placement, Sphere
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import JointGuidance, JointTarget
from dynfab.motion.inverse_kinematics import PointTarget
from dynfab.motion.plan_requests import PlanRequest, make_plan
from dynfab.scenario.references import scenario_references
from dynfab.scenario.guided_controller import make_scenario_controller
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
from wall_scene import GOAL, START, WALL, WALL_ENTRY
from coarse_panda import panda_on_planning_spheres

DT = 0.01
#: how far [rad] from START the reference is when a sphere is put halfway between them
AHEAD = 0.2


@pytest.fixture(scope="module")
def panda():
    return panda_on_planning_spheres()


def _guided(panda):
    data = {"robot": "panda", "planner": "dynamic-fabric", "dt": DT, "duration": 5.0,
            "initial_state": {"q": START.tolist()}, "goal": [{"type": "joint", "position": GOAL.tolist()}],
            "obstacles": [WALL_ENTRY]}
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    guided = make_scenario_controller(scenario, panda, scenario_references(scenario, panda), plan_latency=0.0).guided
    # the plan the sphere in the way is placed on (session 22's detour rule at 1.5 plans this
    # way again and keeps a quicker one, which passes the sphere's side)
    guided.guidance.settings = replace(guided.guidance.settings, detour_ratio=3.0)
    return guided


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


def _sphere_in_the_way(panda, point: np.ndarray) -> PlacedObstacle:
    """A 5 mm sphere that a robot sphere overlaps by 3 mm halfway from START to ``point``,
    beside it (horizontally, across its motion), where START and ``point`` are clearest of it."""
    start, there, halfway = (np.asarray(panda.sphere_centers(q), dtype=float)
                             for q in (START, point, (START + point) / 2))
    best: tuple[float, PlacedObstacle] | None = None
    for i, radius in enumerate(panda.sphere_radii):
        across = np.cross(there[i] - start[i], (0.0, 0.0, 1.0))
        if np.linalg.norm(across) < 1e-9:
            continue
        for side in (1.0, -1.0):
            centre = halfway[i] + side * across / np.linalg.norm(across) * (float(radius) + 0.002)
            obstacle = PlacedObstacle(Sphere(0.005), Placement(tuple(centre)))
            checker = ConfigurationChecker(panda, [obstacle])
            ends = min(checker.clearances(START)[0], checker.clearances(point)[0])
            if best is None or ends > best[0]:
                best = (ends, obstacle)
    assert best is not None
    return best[1]


def test_the_reference_waits_for_a_robot_that_cannot_see_it(panda) -> None:
    assert _lag_after_one_second(panda, None) > AHEAD + 0.03   # the lag rule alone lets the reference run on
    guided = _guided(panda)
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)
    trajectory = guided.plan.trajectory
    times = np.linspace(0.0, trajectory.duration, 2001)
    ahead = times[np.argmax(np.linalg.norm(trajectory.sample(times)[0] - START, axis=1) > AHEAD)]
    point = trajectory.evaluate(float(ahead)).position
    planning = panda.planning_robot   # the spheres the guided fabric's sight test reads
    obstacle = _sphere_in_the_way(planning, point)
    checker = ConfigurationChecker(planning, [obstacle])
    assert min(checker.clearances(START)[0], checker.clearances(point)[0]) > 0.01   # in the way, not at its ends
    assert checker.clearances((START + point) / 2)[0] < 0.0
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
