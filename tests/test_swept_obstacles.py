"""A moving sphere seen by guidance as the capsule it sweeps soon: the shape itself, the
reference's check that sees it about to cross, and a replan that leaves its line."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.geometry.distance import placed_distance
from dynfab.geometry.shapes import Box, Capsule, Placement, Sphere
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import GuidanceSettings, JointGuidance, JointTarget
from dynfab.motion.joint_planning import polyline_samples
from dynfab.motion.plan_requests import PlanRequest, make_plan
from dynfab.motion.swept_obstacles import swept_clear_of, swept_obstacle
from dynfab.robots import load_robot
from dynfab.scenario.guided_controller import make_scenario_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
from wall_scene import GOAL, START, WALL, WALL_ENTRY

#: the sphere's velocity: toward the robot's base, across the plan over the wall [m/s]
VELOCITY = np.array([-0.4, 0.0, 0.0])
#: how long before it reaches the plan's middle the sphere is placed [s]
LEAD = 0.6


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


#: the reference at one speed along its way: the tests place a sphere by the reference's
#: time (at :data:`NOW`), and where the way passes near the wall a reference slowed there
#: (``slow_clearance``) would be elsewhere at that time
#: the way not slowed, and the plan the spheres below were placed on (session 22's detour
#: rule at 1.5 plans this way again and keeps a quicker one, ahead of them at NOW)
#: ... and a sweep of 1 s: the spheres are placed :data:`LEAD` before the reference, so that
#: what they sweep then misses the robot where it is and meets the reference ahead
STEADY = replace(GuidanceSettings(), slow_clearance=0.0, detour_ratio=3.0, sweep_horizon=1.0)


@pytest.fixture(scope="module")
def wall_plan(panda):
    return JointGuidance(panda, STEADY).plan(START, JointTarget(tuple(GOAL)), [WALL])


def _coming(panda, q: np.ndarray, velocity: np.ndarray = VELOCITY) -> PlacedObstacle:
    """A 5 cm sphere that reaches the Panda's hand at ``q`` ``LEAD`` seconds from now."""
    hand = np.asarray(panda.link_position(q, "panda_hand"), dtype=float)
    return PlacedObstacle(Sphere(0.05), Placement(tuple(hand - VELOCITY * LEAD)), tuple(velocity))


def test_a_moving_sphere_sweeps_the_capsule_along_its_velocity() -> None:
    sphere = PlacedObstacle(Sphere(0.07), Placement((0.1, 0.2, 0.3)), (0.0, 0.4, -0.3))
    swept = swept_obstacle(sphere, 2.0)
    assert isinstance(swept.shape, Capsule)
    assert swept.shape.radius == 0.07 and swept.shape.length == pytest.approx(1.0)
    there = np.array([0.1, 0.2 + 0.8, 0.3 - 0.6])   # where it is after 2 s
    points = np.array([[0.1, 0.2, 0.3], there, there + [0.069, 0.0, 0.0], there + [0.0, 0.4, -0.3]])
    inside = placed_distance(swept.shape, swept.placement, points)
    assert inside[:3].max() < 0.0 and inside[3] == pytest.approx(0.5 - 0.07)


def test_what_does_not_move_or_is_no_sphere_is_swept_as_it_is() -> None:
    still = PlacedObstacle(Sphere(0.07), Placement((0.1, 0.2, 0.3)))
    box = PlacedObstacle(Box((0.1, 0.1, 0.1)), Placement((0.0, 0.0, 0.0)), (0.3, 0.0, 0.0))
    assert swept_obstacle(still, 1.0) is still and swept_obstacle(box, 1.0) is box
    with pytest.raises(ValueError, match="sweep horizon"):
        swept_obstacle(still, -1.0)


def test_a_capsule_the_robot_is_in_is_shortened_until_clear_of_it_else_the_sphere() -> None:
    sphere = PlacedObstacle(Sphere(0.05), Placement((0.0, 0.0, 0.0)), (1.0, 0.0, 0.0))
    robot_at = {"near": np.array([0.4]), "on": np.array([0.02])}   # a point robot on the x axis [m]

    def clearance(q: np.ndarray, obstacle: PlacedObstacle) -> float:
        return float(placed_distance(obstacle.shape, obstacle.placement, [[q[0], 0.0, 0.0]])[0])

    shortened = swept_clear_of(sphere, 1.0, [robot_at["near"]], clearance, 0.01)
    assert shortened.shape == Capsule(0.05, 0.25)   # 1 s and 0.5 s reach the robot, 0.25 s does not
    assert swept_clear_of(sphere, 1.0, [robot_at["on"]], clearance, 0.01) is sphere   # inside: none clears it


#: the reference's time [s] at which the sphere is placed half a check horizon ahead of it,
#: the robot there clear of the whole capsule
NOW = 1.2


def test_the_reference_check_sees_a_sphere_about_to_cross_it(panda, wall_plan) -> None:
    guidance = JointGuidance(panda, STEADY)
    horizon = guidance.settings.sweep_horizon
    sphere = _coming(panda, wall_plan.trajectory.evaluate(NOW + 0.5 * guidance.settings.check_horizon).position)
    assert guidance.obstacle_clearance(wall_plan.trajectory.evaluate(NOW).position,
                                       swept_obstacle(sphere, horizon)) > guidance.settings.path.margin
    assert not guidance.blocked_ahead(wall_plan, NOW, [sphere])   # where it is now, it is clear of the reference
    assert guidance.blocked_ahead(wall_plan, NOW, [swept_obstacle(sphere, horizon)])


def _wall_controller(panda):
    data = {"robot": "panda", "planner": "dynamic-fabric", "dt": 0.01, "duration": 5.0,
            "initial_state": {"q": START.tolist()}, "goal": [{"type": "joint", "position": GOAL.tolist()}],
            "obstacles": [WALL_ENTRY]}
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    return make_scenario_controller(scenario, panda, scenario_references(scenario, panda), STEADY, plan_latency=0.0)


@pytest.mark.parametrize("speed, blocked", [(1.0, 1), (0.0, 0)])
def test_a_guided_fabric_replans_for_a_sphere_about_to_cross_its_reference(panda, speed, blocked) -> None:
    guided = _wall_controller(panda).guided
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)
    plan, dt = guided.plan, 0.01
    for step in range(int(round(NOW / dt))):   # the robot on its reference, nothing moving
        guided.update(step * dt, guided.fabric.parameters.goal_position[0].copy())
    q = guided.fabric.parameters.goal_position[0].copy()
    ahead = plan.trajectory.evaluate(NOW + 0.5 * guided.guidance.settings.check_horizon).position
    assert np.linalg.norm(q - plan.trajectory.evaluate(NOW).position) < 0.05   # the reference clock kept time
    guided.update(NOW, q, (_coming(panda, ahead, speed * VELOCITY),))
    assert guided.status.replans_blocked == blocked


def test_a_replan_around_a_moving_sphere_leaves_its_swept_line(panda, wall_plan) -> None:
    waypoints = polyline_samples(wall_plan.trajectory.waypoints, 0.01)
    sphere = _coming(panda, waypoints[len(waypoints) // 2])
    guidance = JointGuidance(panda, replace(GuidanceSettings(), sweep_horizon=STEADY.sweep_horizon))
    swept = ConfigurationChecker(panda, [swept_obstacle(sphere, guidance.settings.sweep_horizon)])

    def closest(moving: PlacedObstacle) -> float:
        request = PlanRequest(0.0, START, JointTarget(tuple(GOAL)), (WALL,), (moving,), GOAL, 0, False, (0.005,),
                              "blocked")
        outcome = make_plan(guidance, request)
        assert outcome.plan is not None
        return float(swept.batch(polyline_samples(outcome.plan.trajectory.waypoints, 0.005))[:, 0].min())

    assert closest(PlacedObstacle(sphere.shape, sphere.placement)) < 0.0   # frozen: through the sphere's line
    assert closest(sphere) >= 0.0
