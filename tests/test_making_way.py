"""Making way for a moving sphere that sweeps the goal: what sweeps, the refuge, when to go
back, and the MBM run that drove the arm through a shelf wall before."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.problem_run import run_case
from dynfab.benchmarks.mbm.problems import load_problems
from dynfab.benchmarks.mbm.variants import prepare_case
from dynfab.geometry.shapes import Box, Placement, Sphere
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.guidance import JointGuidance, JointTarget
from dynfab.motion.guidance_status import GuidanceStatus
from dynfab.motion.making_way import REFUGE_RADII, moving_reason, refuge, refuge_plan, sweeps
from dynfab.motion.swept_obstacles import swept_obstacle
from dynfab.robots import load_robot

READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


@pytest.fixture(scope="module")
def guidance() -> JointGuidance:
    return JointGuidance(load_robot("panda"))


def _hand(guidance: JointGuidance, q: np.ndarray) -> np.ndarray:
    return np.asarray(guidance.robot.link_position(q, "panda_hand"), dtype=float)


def _sphere_toward(guidance: JointGuidance, q: np.ndarray, distance: float, speed: float) -> PlacedObstacle:
    """A 6 cm sphere ``distance`` [m] from the hand at ``q`` along +y, moving at ``speed`` [m/s]
    along −y (toward the hand for a positive speed)."""
    hand = _hand(guidance, q)
    centre = hand + np.array([0.0, distance, 0.0])
    return PlacedObstacle(Sphere(0.06), Placement(tuple(centre)), (0.0, -speed, 0.0))


def test_what_a_sphere_sweeps_within_the_horizon_counts_only_if_it_comes_at_the_robot(guidance) -> None:
    coming = _sphere_toward(guidance, READY, 0.4, 0.5)        # at the hand within 0.8 s of a 1 s horizon
    leaving = _sphere_toward(guidance, READY, 0.4, -0.5)
    assert len(sweeps(guidance, READY, [coming])) == 1
    assert sweeps(guidance, READY, [leaving]) == ()


def test_the_robot_stays_where_it_is_if_nothing_sweeps_it(guidance) -> None:
    leaving = _sphere_toward(guidance, READY, 0.4, -0.5)
    assert np.array_equal(refuge(guidance, READY, (), (leaving,), seed=0), READY)


def test_a_refuge_keeps_the_margin_from_the_capsule_and_its_way_from_the_sphere(guidance) -> None:
    coming = _sphere_toward(guidance, READY, 0.3, 0.4)
    capsule = swept_obstacle(coming, guidance.settings.sweep_horizon)
    floor = PlacedObstacle(Box((2.0, 2.0, 0.1)), Placement((0.0, 0.0, -0.06)))
    target = refuge(guidance, READY, (floor,), (coming,), seed=0)
    assert target is not None and 0.0 < np.linalg.norm(target - READY) <= REFUGE_RADII[-1] + 1e-9
    margin = guidance.settings.path.margin
    assert guidance.obstacle_clearance(target, capsule) >= margin
    assert guidance.obstacle_clearance(target, floor) >= margin
    guidance.checker.set_obstacles((floor, coming))
    assert guidance.checker.motion_free(READY, target, guidance.settings.path.resolution, margin, 0.0)[0]
    plan = refuge_plan(guidance, READY, (floor,), (coming,), seed=0)
    limits = guidance.robot.limits
    times = np.linspace(0.0, plan.trajectory.duration, 50)
    velocities = np.array([plan.trajectory.evaluate(t).velocity for t in times])
    assert np.all(np.abs(velocities) <= limits.velocity * (1 + 1e-6))
    assert np.allclose(plan.trajectory.evaluate(plan.trajectory.duration).position, plan.goal, atol=1e-6)


def test_what_moves_asks_for_a_refuge_while_it_sweeps_the_goal_and_for_the_goal_once_it_has_passed(guidance) -> None:
    plan = guidance.plan(READY, JointTarget(tuple(READY + 0.1)), ())
    coming = _sphere_toward(guidance, plan.goal, 0.3, 0.4)
    away = _sphere_toward(guidance, plan.goal, 0.3, -0.4)
    assert moving_reason(guidance, plan, 0.0, READY, None, [coming]) == "refuge"
    assert moving_reason(guidance, plan, 0.0, READY, None, [away]) is None
    assert moving_reason(guidance, plan, 0.0, READY, plan.goal, [away]) == "return"


def test_a_sphere_sweeping_an_arm_at_its_goal_in_a_shelf_is_let_pass_from_a_refuge() -> None:
    """Moving-sphere MBM bookshelf_thin/0087 (seed 1): a 5.6 cm sphere at 0.42 m/s sweeps
    the forearm of the arm at its grasp inside a shelf; the sphere's leaf drove the hand
    53.7 mm into the shelf's wall. The arm now waits out of the sphere's way and then reaches
    the goal, clean on Franka's meshes."""
    problem = next(p for p in load_problems(["bookshelf_thin"], per_type=1, skip=87 - 9) if p.number == 87)
    case = prepare_case(problem, "moving-sphere", franka(), seed=1)
    assert case.invalid is None
    outcome = run_case(case.mapping)
    metrics, check = outcome["metrics"], outcome["check"]
    assert metrics["goal_reached"] and metrics["guided"], (metrics["failure"], metrics["final_distance"])
    assert check["collisions"] == [] and check["self_collisions"] == [] and check["joint_limit_violations"] == []
    assert metrics["recovered"] >= 1


def test_a_sphere_coming_at_the_goal_is_seen_soon_enough_to_make_way() -> None:
    """Moving-sphere MBM table_pick/0099 (seed 13): a 6 cm sphere at 0.47 m/s comes down on
    the arm near its goal by a table. Seen sweeping the goal 0.25 s before it reached the arm
    (a 1 s horizon), the refuge came too late: the sphere's leaf pushed the hand 92 mm into a
    box. Seen within 1.5 s, the arm makes way in time and then reaches the goal."""
    problem = next(p for p in load_problems(["table_pick"], per_type=1, skip=99 - 9) if p.number == 99)
    case = prepare_case(problem, "moving-sphere", franka(), seed=13)
    assert case.invalid is None
    outcome = run_case(case.mapping)
    metrics, check = outcome["metrics"], outcome["check"]
    assert metrics["goal_reached"] and not metrics["collision"], (metrics["failure"], metrics["clearance"])
    assert check["collisions"] == [] and check["self_collisions"] == [] and check["joint_limit_violations"] == []


def test_a_sphere_at_rest_sweeps_nothing(guidance) -> None:
    resting = _sphere_toward(guidance, READY, 0.05, 0.0)
    assert sweeps(guidance, READY, [resting]) == ()


def test_a_robot_at_a_refuge_goes_back_even_after_its_replans_are_spent() -> None:
    """The replan budget bounds the plans to the goal; a refuge is off that way, so the
    return to the goal is asked for even after the last replan was spent on the refuge."""
    from dynfab.scenario.guided_controller import make_scenario_controller
    from dynfab.scenario.references import scenario_references
    from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
    panda = load_robot("panda")
    goal = READY + 0.2
    data = {"robot": "panda", "planner": "dynamic-fabric", "dt": 0.01, "duration": 5.0,
            "initial_state": {"q": READY.tolist()}, "goal": [{"type": "joint", "position": goal.tolist()}]}
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    guided = make_scenario_controller(scenario, panda, scenario_references(scenario, panda), plan_latency=0.0).guided
    guided.set_goal(JointTarget(tuple(goal)), 0.0, READY)
    settings = guided.guidance.settings
    hand = np.asarray(panda.link_position(goal, "panda_hand"), dtype=float)
    passing = PlacedObstacle(Sphere(0.06), Placement(tuple(hand + [0.0, 0.3, 0.0])), (0.0, -0.4, 0.0))
    gone = PlacedObstacle(Sphere(0.06), Placement(tuple(hand + [0.0, -2.0, 0.0])), (0.0, -0.4, 0.0))
    guided.status = GuidanceStatus(guided=True, plans=settings.replans)   # the budget spent but one
    guided.update(0.1, READY, (passing,))
    assert guided.status.refuges == 1 and guided.status.plans == settings.replans + 1   # the refuge: the last one
    guided.update(0.7, READY, (gone,))
    assert guided.status.plans == settings.replans + 2   # back to the goal all the same
    assert np.allclose(guided.plan.goal, goal)
