"""The pull toward a grasp's approach segment (issue 19): in the approach the reference the
fabric tracks is shifted across the checked segment by ``k_p e + k_i ∫e dt``, ``e`` the
robot's step across to it, so that a sideways push (the obstacle leaves near the object)
does not hold the robot beside the segment, where the clock waits for it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.motion.approach_pull import ApproachPull
from dynfab.motion.approach_segment import across_segment, along_segment, segment_offset
from dynfab.motion.guidance import GuidanceSettings, JointTarget
from dynfab.motion.reference_clock import in_approach
from dynfab.scenario.guided_controller import make_scenario_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
from dynfab.sim import simulate
from wall_scene import WALL_ENTRY, goal_near_the_wall
from coarse_panda import panda_on_planning_spheres

START = np.array([-1.3, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
DT = 0.01


@pytest.fixture(scope="module")
def panda():
    return panda_on_planning_spheres()


@pytest.fixture(scope="module")
def grasp(panda) -> np.ndarray:
    """The spheres 4 mm from the wall (the planner's margin is 10 mm): a goal approached."""
    return goal_near_the_wall(panda, 0.004)


def _controller(panda, goal: np.ndarray, settings: GuidanceSettings, duration: float = 8.0):
    data = {"robot": "panda", "planner": "dynamic-fabric", "dt": DT, "duration": duration,
            "initial_state": {"q": START.tolist()}, "goal": [{"type": "joint", "position": goal.tolist()}],
            "obstacles": [WALL_ENTRY]}
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    return make_scenario_controller(scenario, panda, scenario_references(scenario, panda), settings, plan_latency=0.0)


def test_the_step_across_a_segment_is_perpendicular_to_it_and_reaches_its_line() -> None:
    rng = np.random.default_rng(5)
    for _ in range(20):
        a, b, q = rng.normal(size=(3, 7))
        segment = a + np.linspace(0.0, 1.0, 5)[:, None] * (b - a)
        step = across_segment(segment, q)
        assert abs(step @ (b - a)) < 1e-9
        foot = q + step - a   # on the line through a and b
        assert np.linalg.norm(foot - (foot @ (b - a)) / ((b - a) @ (b - a)) * (b - a)) < 1e-9
        if 0.0 < along_segment(segment, q) < 1.0:   # inside: the step to the nearest point
            assert np.linalg.norm(step) == pytest.approx(segment_offset(segment, q), abs=1e-12)


def test_in_the_approach_the_reference_is_shifted_across_by_the_pull(panda, grasp) -> None:
    settings = GuidanceSettings()
    guided = _controller(panda, grasp, settings).guided
    guided.set_goal(JointTarget(tuple(grasp)), 0.0, START)
    plan = guided.plan
    t = 0.0
    while guided._tau < plan.approach_start:   # a robot exactly on the reference
        t += DT
        guided.update(t, plan.trajectory.evaluate(guided._tau).position.copy())
    start = plan.trajectory.waypoints[-2]
    direction = (grasp - start) / np.linalg.norm(grasp - start)
    side = np.zeros(7)
    side[3] = 1.0
    side -= (side @ direction) * direction
    side /= np.linalg.norm(side)
    beside = 0.003   # below approach_offset_slow: the clock runs
    ticks = 20
    for _ in range(ticks):
        t += DT
        robot = plan.trajectory.evaluate(guided._tau).position + beside * side
        guided.update(t, robot)
    reference = plan.trajectory.evaluate(guided._tau).position
    written = guided.fabric.parameters.goal_position[0]
    expected = -(settings.approach_pull + settings.approach_pull_rate * ticks * DT) * beside * side
    np.testing.assert_allclose(written - reference, expected, atol=1e-9)
    # held far beside, the integral stops at approach_pull_limit
    for _ in range(int(settings.approach_pull_limit / (settings.approach_pull_rate * 0.05 * DT)) + 10):
        t += DT
        guided.update(t, plan.trajectory.evaluate(guided._tau).position + 0.05 * side)
    assert guided.plan is plan
    shift = guided.fabric.parameters.goal_position[0] - plan.trajectory.evaluate(guided._tau).position
    assert np.linalg.norm(shift) == pytest.approx(settings.approach_pull * 0.05 + settings.approach_pull_limit,
                                                  rel=1e-6)
    # once the reference has ended the integral is gone: only the proportional step and one tick's
    for _ in range(int(round(plan.trajectory.duration / DT)) + 1):   # beside, but the clock runs
        t += DT
        guided.update(t, plan.trajectory.evaluate(guided._tau).position + beside * side)
    assert guided._tau >= plan.trajectory.duration
    shift = guided.fabric.parameters.goal_position[0] - grasp
    np.testing.assert_allclose(shift, -(settings.approach_pull + settings.approach_pull_rate * DT) * beside * side,
                               atol=1e-9)


def _pushed_run(panda, grasp, settings: GuidanceSettings, push: float):
    """The run to ``grasp`` with a constant acceleration ``push`` [rad/s²] across the approach
    while in it (what the obstacle leaves near a grasped object do); the controller and the record."""
    controller = _controller(panda, grasp, settings)
    guided = controller.guided

    def pushed(t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        command = controller(t, q, qdot)
        if guided.plan is None or not in_approach(guided.plan, guided._tau):
            return command
        segment = guided._segment
        direction = (segment[-1] - segment[0]) / np.linalg.norm(segment[-1] - segment[0])
        side = np.zeros(7)
        side[3] = 1.0
        side -= (side @ direction) * direction
        return command + push * side / np.linalg.norm(side)

    record = simulate(pushed, START, np.zeros(7), DT, 8.0)
    return guided, record


def test_a_robot_pushed_beside_the_approach_is_pulled_back_and_reaches_the_goal(panda, grasp) -> None:
    """Without the pull (``approach_pull`` and its rate 0, as before) the push holds the robot
    beside the segment, past ``approach_offset_stop``: the clock stops and the goal is not
    reached; with it the robot keeps near the segment and reaches it."""
    push = 1.0
    before = replace(GuidanceSettings(), approach_pull=0.0, approach_pull_rate=0.0)
    guided, record = _pushed_run(panda, grasp, before, push)
    assert np.linalg.norm(record.q[-1] - grasp) > 0.05
    assert guided._tau < guided.plan.trajectory.duration   # the clock waits for the robot
    assert segment_offset(guided._segment, record.q[-1]) > before.approach_offset_stop
    guided, record = _pushed_run(panda, grasp, GuidanceSettings(), push)
    assert np.linalg.norm(record.q[-1] - grasp) < 0.005


def test_the_pull_integrates_across_the_segment_up_to_its_limit_and_restarts_at_zero() -> None:
    settings = replace(GuidanceSettings(), approach_pull=2.0, approach_pull_rate=1.0, approach_pull_limit=0.01)
    pull = ApproachPull(settings, 3)
    segment = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    q = np.array([0.4, 0.02, 0.0])   # 20 mrad beside, inside the segment
    across = np.array([0.0, -0.02, 0.0])
    np.testing.assert_allclose(pull.shift(segment, q, 0.1), 2.0 * across + 0.1 * across, atol=1e-12)
    np.testing.assert_allclose(pull.shift(segment, q, 0.1), 2.0 * across + 0.2 * across, atol=1e-12)
    for _ in range(50):
        shift = pull.shift(segment, q, 0.1)
    np.testing.assert_allclose(shift, 2.0 * across + np.array([0.0, -0.01, 0.0]), atol=1e-12)   # at the limit
    beyond = np.array([1.5, 0.02, 0.0])   # past the goal: only the part across, none along
    assert pull.shift(segment, beyond, 0.0)[0] == 0.0
    pull.reset()
    np.testing.assert_allclose(pull.shift(segment, q, 0.0), 2.0 * across, atol=1e-12)
