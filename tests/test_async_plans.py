"""The robot never waits for a plan (issue 19, item 1): a guided fabric commands the robot at
once on a new goal, heads for the goal while the plan is made (on a worker thread in real
time, after a fixed latency in simulation), and joins the plan where the robot is when it
arrives."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from dynfab.motion.guidance import GuidanceError, JointTarget
from dynfab.robots import load_robot
from dynfab.scenario.guided_controller import SIMULATED_PLAN_LATENCY, make_scenario_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
from wall_scene import GOAL, START, WALL_ENTRY, goal_near_the_wall

DT = 0.01


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def _scenario(duration: float = 5.0) -> dict:
    return {"robot": "panda", "planner": "dynamic-fabric", "dt": DT, "duration": duration,
            "initial_state": {"q": START.tolist()}, "goal": [{"type": "joint", "position": GOAL.tolist()}],
            "obstacles": [WALL_ENTRY]}


def _controller(panda, plan_latency: float | None, data: dict | None = None):
    scenario = validate_for_robot(scenario_from_dict(_scenario() if data is None else data), panda)
    return make_scenario_controller(scenario, panda, scenario_references(scenario, panda), plan_latency=plan_latency)


def _within_limits(controller, qddot: np.ndarray) -> bool:
    peak = controller.inner.planner.config.limits.acceleration
    return bool(np.all(np.isfinite(qddot)) and np.all(np.abs(qddot) <= peak + 1e-9))


def test_a_new_goal_returns_a_command_before_the_plan_is_made_on_the_worker_thread(panda) -> None:
    controller = _controller(panda, plan_latency=None)
    guided = controller.guided
    gate = threading.Event()
    plan = guided.guidance.plan

    def held_plan(*args, **kwargs):   # the plan cannot finish before the test lets it
        assert gate.wait(60.0)
        return plan(*args, **kwargs)

    guided.guidance.plan = held_plan
    try:
        guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)   # returns although the plan is held
        assert guided.planning and guided.plan is None
        qddot = guided.compute(0.0, START, np.zeros(7))
        assert _within_limits(controller, qddot)
        reference = guided.fabric.parameters.goal_position[0]
        step = 0
        while step < 2000 and np.linalg.norm(reference - GOAL) > np.linalg.norm(START - GOAL) - 0.01:
            step += 1   # the goal configuration is published before the path is planned
            time.sleep(0.005)
            guided.update(step * DT, START)
        assert np.linalg.norm(reference - GOAL) <= np.linalg.norm(START - GOAL) - 0.01   # heading for the goal
        assert guided.plan is None and guided.planning
        gate.set()
        while step < 8000 and guided.plan is None:
            step += 1
            time.sleep(0.005)
            guided.update(step * DT, START)
        assert guided.plan is not None and not guided.planning and guided.status.plans == 1
        np.testing.assert_allclose(reference, START, atol=1e-6)   # the robot stayed: joined at the plan's start
    finally:
        gate.set()
        guided.close()


def test_in_simulation_the_robot_moves_toward_the_goal_until_the_plan_arrives_and_joins_it(panda) -> None:
    latency = 0.2
    controller = _controller(panda, plan_latency=latency)
    guided = controller.guided
    q, qdot = START.copy(), np.zeros(7)
    arrived_at, lag_at_arrival, start_lag = None, None, None
    for step in range(60):
        t = step * DT
        qddot = controller(t, q, qdot)
        assert _within_limits(controller, qddot), t
        if guided.plan is None:
            assert guided.planning and t < latency - 1e-9
        elif arrived_at is None:
            arrived_at = t
            lag_at_arrival = float(np.linalg.norm(q - guided.fabric.parameters.goal_position[0]))
            start_lag = float(np.linalg.norm(q - guided.plan.trajectory.evaluate(0.0).position))
            assert np.linalg.norm(q - GOAL) < np.linalg.norm(START - GOAL) - 0.01   # it moved toward the goal
        q, qdot = q + DT * qdot + 0.5 * DT**2 * qddot, qdot + DT * qddot
    assert arrived_at == pytest.approx(latency)   # the first tick at the latency: not before, not later
    assert lag_at_arrival <= start_lag            # joined no farther back than where the plan began
    assert lag_at_arrival < guided.guidance.settings.lag_slow   # the reference's clock runs at once


def test_from_a_start_nearer_the_obstacles_than_the_margin_the_robot_waits_for_the_plans_way_out(panda) -> None:
    latency = 0.2
    start = goal_near_the_wall(panda, 0.005)   # 5 mm from the wall on the spheres: the planner's 1 cm refuses it
    data = _scenario()
    data["initial_state"]["q"], data["goal"] = start.tolist(), [{"type": "joint", "position": START.tolist()}]
    controller = _controller(panda, latency, data)
    guided, params = controller.guided, controller.guided.fabric.parameters
    q, qdot = start.copy(), np.zeros(7)
    for step in range(30):
        t = step * DT
        qddot = controller(t, q, qdot)
        assert _within_limits(controller, qddot), t
        if t < latency - 1e-9:
            assert guided.plan is None
            np.testing.assert_array_equal(params.goal_position[0], q)   # held where the robot is
            np.testing.assert_array_equal(params.goal_velocity[0], np.zeros(7))
        q, qdot = q + DT * qdot + 0.5 * DT**2 * qddot, qdot + DT * qddot
    assert guided.plan is not None and guided.plan.departure > 0.0   # the plan's way out of the blocked start
    assert not guided.guidance.clear_of_obstacles(start) and guided.guidance.clear_of_obstacles(START)


def test_a_guided_run_with_a_plan_latency_reaches_its_goal_and_reproduces(panda) -> None:
    scenario = scenario_from_dict(_scenario(duration=9.0))   # reached at 7.2 s (5.3 s before the way slowed near the wall)
    first, second = run_scenario(scenario), run_scenario(scenario)
    assert first.metrics.success and first.metrics.guided and not first.metrics.collision
    np.testing.assert_array_equal(first.record.q, second.record.q)   # plans made at once, applied on a tick
    assert SIMULATED_PLAN_LATENCY > DT   # the robot moved before the plan came: not the old synchronous path
    assert np.linalg.norm(first.record.q[int(round(SIMULATED_PLAN_LATENCY / DT))] - START) > 0.0


def test_while_a_replan_is_made_the_old_reference_stands_still(panda) -> None:
    latency = 0.2
    guided = _controller(panda, plan_latency=latency).guided
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)
    params = guided.fabric.parameters
    asked_at, held = None, None
    for step in range(1, 600):   # the robot never moves: it stalls behind the reference, a replan is asked for
        t = step * DT
        guided.update(t, START)
        if asked_at is None and guided.status.replans_stalled:
            asked_at, held = t, params.goal_position[0].copy()
        elif asked_at is not None and guided.planning:
            np.testing.assert_array_equal(params.goal_position[0], held)
            np.testing.assert_array_equal(params.goal_velocity[0], 0.0)
        elif asked_at is not None:
            break
    assert asked_at is not None and guided.status.plans == 2
    assert t == pytest.approx(asked_at + latency)   # the replan arrived after the latency, not before


def test_a_replan_that_finds_no_plan_is_counted_as_failed_not_as_a_plan(panda) -> None:
    """``status.plans`` counts plans made; a replan that found none is in ``failed_plans``
    and the old reference is kept."""
    guided = _controller(panda, plan_latency=0.2).guided
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, START)

    def no_path(*args, **kwargs):
        raise GuidanceError("no_path", "no path within the planning budget (test)")

    step = 1
    while guided.plan is None:
        guided.update(step * DT, START)
        step += 1
    first = guided.plan
    guided.guidance.plan = no_path
    while guided.status.failed_plans == 0 and step < 1000:   # the robot never moves: it stalls, a replan fails
        guided.update(step * DT, START)
        step += 1
    assert guided.status.failed_plans == 1 and guided.status.plans == 1 and guided.status.replans_stalled == 1
    assert guided.status.failure == "no_path" and guided.plan is first


def test_a_plan_asked_for_in_a_tick_starts_once_the_ticks_command_is_computed(panda) -> None:
    """In real time the worker starts after the tick's command (it would hold the
    interpreter while the command is computed); a caller that only updates starts it at its
    next tick."""
    controller = _controller(panda, plan_latency=None)
    guided = controller.guided
    events: list[str] = []
    plan, inner = guided.guidance.plan, controller.inner

    def recorded_plan(*args, **kwargs):
        events.append("plan")
        return plan(*args, **kwargs)

    def recorded_inner(*args, **kwargs):
        events.append("command")
        return inner(*args, **kwargs)

    guided.guidance.plan = recorded_plan
    controller.inner = recorded_inner
    try:
        controller(0.0, START, np.zeros(7))
        step = 0
        while step < 2000 and guided.plan is None:
            step += 1
            time.sleep(0.005)
            guided.update(step * DT, START)
        assert guided.plan is not None and events[:2] == ["command", "plan"]
        events.clear()
        guided.set_goal(JointTarget(tuple(START)), 1.0, GOAL)   # update() alone, a later tick: started there
        guided.update(1.0, GOAL)
        time.sleep(0.2)
        assert guided.planning and events == []
        guided.update(1.0 + DT, GOAL)
        while step < 4000 and guided.planning:
            step += 1
            time.sleep(0.005)
            guided.update(1.0 + DT * (step + 1), GOAL)
        assert events == ["plan"] and guided.status.plans == 2
    finally:
        guided.close()
