"""When a guided fabric replans: a robot held behind its reference, a reference blocked by
something moving, and what the replan keeps clear of."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.geometry.shapes import Box, Placement, Sphere
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import JointGuidance, JointTarget
from dynfab.motion.joint_planning import polyline_samples
from dynfab.robots import load_robot
from dynfab.scenario.guided_controller import GUIDED_MOVING_MARGIN, SIMULATED_PLAN_LATENCY, make_scenario_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
from wall_scene import GOAL, START, WALL_ENTRY

DT = 0.01


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def _controller(panda, moving_sphere: dict | None = None, plan_latency: float = SIMULATED_PLAN_LATENCY):
    obstacles = [WALL_ENTRY]
    if moving_sphere is not None:
        obstacles.append(moving_sphere)
    data = {"robot": "panda", "planner": "dynamic-fabric", "dt": DT, "duration": 5.0,
            "initial_state": {"q": START.tolist()}, "goal": [{"type": "joint", "position": GOAL.tolist()}],
            "obstacles": obstacles}
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    return make_scenario_controller(scenario, panda, scenario_references(scenario, panda), plan_latency=plan_latency)


def test_a_robot_held_behind_its_reference_replans_after_stall_lag_time(panda) -> None:
    guided = _controller(panda).guided
    settings = guided.guidance.settings
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)
    lagging_since = None
    for step in range(1, 400):   # the robot never moves
        t = step * DT
        guided.update(t, START)
        lag = float(np.linalg.norm(START - guided.fabric.parameters.goal_position[0]))
        if lagging_since is None and guided.plan is not None and lag > settings.lag_slow:   # not before it arrives
            lagging_since = t
        if guided.status.replans_stalled:
            break
    assert lagging_since is not None and guided.status.replans_stalled == 1
    assert t == pytest.approx(lagging_since + settings.stall_lag_time + DT, abs=1.5 * DT)
    assert t < settings.stall_window + lagging_since   # before the clock's own test would notice


def test_a_sphere_at_the_goal_is_left_out_of_replans_which_come_at_most_every_blocked_interval(panda) -> None:
    controller = _controller(panda, plan_latency=0.0)   # the plan at once: its clock starts at 0
    guided = controller.guided
    settings = guided.guidance.settings
    hand = np.asarray(panda.kinematics.position(GOAL, "panda_hand")).ravel()
    at_goal = PlacedObstacle(Sphere(0.05), Placement(tuple(hand)))   # on the reference's end, touching the goal
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)
    duration = guided.plan.trajectory.duration
    for step in range(1, 101):   # 1 s; the reference's last second is in the check horizon
        guided.update(duration - settings.check_horizon + step * DT, START, (at_goal,))
    blocked = guided.status.replans_blocked
    assert 1 <= blocked <= int(1.0 / settings.blocked_interval) + 1
    assert guided.plan.approach == 0.0   # planned to the goal itself, not around where the sphere is now


def test_a_replan_after_a_stall_first_keeps_the_stall_margin(panda) -> None:
    middle = START.copy()
    middle[0] = 0.0
    hand = np.asarray(panda.kinematics.position(middle, "panda_hand")).ravel()
    block = PlacedObstacle(Box((0.12, 0.12, 0.12)), Placement(tuple(hand)))   # where turning joint 1 takes the hand
    guidance = JointGuidance(panda)
    checker = ConfigurationChecker(panda, [block])
    settings = guidance.settings
    assert min(checker.clearances(START)[0], checker.clearances(GOAL)[0]) > settings.stall_margin

    def closest(wide: bool) -> float:
        plan = guidance.plan(START, JointTarget(tuple(GOAL)), [block], wide=wide)
        return float(checker.batch(polyline_samples(plan.trajectory.waypoints, 0.005))[:, 0].min())

    assert closest(False) < 0.5 * (settings.path.margin + settings.stall_margin)   # hugs the block
    assert closest(True) >= settings.stall_margin - 1e-3   # the motion check's resolution aside


def test_the_guided_fabric_sees_a_moving_sphere_larger_than_it_is(panda) -> None:
    sphere = {"type": "sphere", "radius": 0.06,
              "trajectory": {"type": "linear", "start": [0.5, -0.5, 0.8], "velocity": [0.0, 0.3, 0.0]}}
    controller = _controller(panda, sphere)
    radius = controller.inner.planner.parameters.obstacle_radius[0]
    assert radius == pytest.approx(0.06 + GUIDED_MOVING_MARGIN)

