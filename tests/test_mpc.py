"""The MPC baseline (Experiment 1's receding-horizon controller): closed-loop runs of the
point robot and the Panda through ``run_scenario``, single solves of the NLP, the
controller's safe action on failure, and its configuration. A differential-drive base:
tests/test_mpc_base.py."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from dynfab.experiments import exp1
from dynfab.mpc import MpcConfig, MpcController, MpcProblem, Plan
from dynfab.robots import load_robot
from mpc_helpers import (BLOCKED_LINE, CLEARANCE_TOLERANCE, LIMIT_TOLERANCE, STAGE_CLEARANCE_TOLERANCE, controller_for,
                         point_scenario, run, solve)

def test_point_robot_goes_around_a_disc_to_its_goal() -> None:
    result, controller = run(BLOCKED_LINE)
    metrics = result.metrics
    assert metrics.goal_reached, metrics
    assert np.abs(result.goal_positions[:, 1]).max() > 0.4, "the path must leave the blocked line"
    assert result.clearance[::10].min() >= -STAGE_CLEARANCE_TOLERANCE, "constraints hold at the solve times"
    # Between stage times the robot moves on a chord of length L ≤ v_max h, which cuts at most
    # L² / (8 R) into the disc of radius R = r_robot + r_disc (the discrete-time constraint's graze).
    speed = np.linalg.norm(result.record.qdot, axis=1).max()
    assert metrics.clearance is not None and metrics.clearance >= -(speed * 0.1) ** 2 / (8 * 0.5)
    assert controller.failures == 0
    assert len(controller.solve_times) == result.record.steps // 10, "one solve per 0.1 s"
    assert all(t > 0.0 for t in controller.solve_times)


def test_point_robot_dodges_a_disc_driving_at_it_and_returns() -> None:
    disc = {"type": "sphere", "radius": 0.3, "trajectory": {"type": "linear", "start": [-2.0, 0.05],
                                                            "velocity": [0.5, 0.0]}}
    data = point_scenario({"type": "position", "position": [0.0, 0.0], "tolerance": 0.05}, [disc], [0.0, 0.0], 9.0)
    result, controller = run(data)
    assert result.metrics.clearance is not None and result.metrics.clearance > -CLEARANCE_TOLERANCE
    assert np.abs(result.goal_positions[:, 1]).max() > 0.3, "the robot must step aside"
    assert np.linalg.norm(result.goal_positions[-1]) < 0.05, "and come back once the disc has passed"
    assert controller.failures == 0


def test_point_robot_reaches_a_joint_goal() -> None:
    data = point_scenario({"type": "joint", "position": [0.8, -0.6], "tolerance": 0.05}, [], [0.0, 0.0], 6.0)
    result, _ = run(data)
    assert result.metrics.goal_reached
    np.testing.assert_allclose(result.record.q[-1], [0.8, -0.6], atol=0.05)


def test_references_are_sampled_at_the_stage_times(monkeypatch: pytest.MonkeyPatch) -> None:
    goal = {"type": "path", "tolerance": 0.05,
            "trajectory": {"type": "circle", "center": [0.0, 0.0], "radius": 0.5, "angular_velocity": 0.5}}
    disc = {"type": "sphere", "radius": 0.2, "trajectory": {"type": "linear", "start": [-2.0, 1.0, 0.3],
                                                            "velocity": [0.5, 0.0, 0.0]}}
    controller = controller_for(point_scenario(goal, [disc], [0.5, 0.0], 5.0), MpcConfig())
    seen: list[tuple[Any, ...]] = []
    solve_once = controller.problem.solve

    def recording_solve(*args: Any) -> Any:
        seen.append(args)
        return solve_once(*args)

    monkeypatch.setattr(controller.problem, "solve", recording_solve)
    controller(0.3, np.array([0.5, 0.0]), np.zeros(2))
    assert len(seen) == 1
    _, _, goals, centres, radii, _ = seen[0]
    times = 0.3 + 0.1 * np.arange(1, 31)
    angles = 0.5 * times
    np.testing.assert_allclose(goals[0], 0.5 * np.column_stack([np.cos(angles), np.sin(angles)]), atol=1e-12)
    np.testing.assert_allclose(centres[0], np.column_stack([-2.0 + 0.5 * times, np.ones(30)]), atol=1e-12)
    np.testing.assert_array_equal(radii, [0.2])


def test_point_robot_follows_a_moving_reference() -> None:
    goal = {"type": "path", "tolerance": 0.05,
            "trajectory": {"type": "circle", "center": [0.0, 0.0], "radius": 0.5, "angular_velocity": 0.5}}
    result, _ = run(point_scenario(goal, [], [0.5, 0.0], 10.0))
    assert result.metrics.success
    # The benchmark's velocity weight makes the plan lag the reference (0.25 m/s here) a little.
    assert result.metrics.summed_error is not None and result.metrics.summed_error < 0.1
    assert result.metrics.path_length > 0.8 * 0.5 * 0.5 * 10.0


@pytest.mark.parametrize("seed", [2, 9])
def test_panda_reaches_experiment1_goal_within_its_constraints(seed: int) -> None:
    data = exp1.scenario(seed, planner="mpc")
    data["duration"] = 6.0
    result, controller = run(data)
    metrics = result.metrics
    assert metrics.success, f"exp1 seed {seed}: {metrics}"
    assert metrics.clearance is not None and metrics.clearance >= -CLEARANCE_TOLERANCE
    assert result.clearance[::10].min() >= -STAGE_CLEARANCE_TOLERANCE
    kin = result.robot.kinematics
    assert np.all(result.record.q >= kin.lower - LIMIT_TOLERANCE)
    assert np.all(result.record.q <= kin.upper + LIMIT_TOLERANCE)
    assert np.all(np.abs(result.record.qdot) <= kin.velocity_limits + LIMIT_TOLERANCE)
    assert controller.failures == 0
    assert np.isfinite(result.record.qddot).all()


def exp1_problem(seed: int, config: MpcConfig) -> tuple[MpcController, np.ndarray]:
    """The controller of Experiment 1 run ``seed`` and its start configuration."""
    data = exp1.scenario(seed, planner="mpc")
    return controller_for(data, config), np.array(data["initial_state"]["q"])


def test_fatrop_with_structure_detection_finds_the_plan_ipopt_finds() -> None:
    plans = {}
    for solver in ("ipopt", "fatrop"):
        controller, q0 = exp1_problem(2, MpcConfig(solver=solver))
        result = solve(controller, q0, np.zeros(7), None)
        assert result.success, f"{solver}: {result.status}"
        plans[solver] = result.plan
    np.testing.assert_allclose(plans["fatrop"].q, plans["ipopt"].q, atol=1e-3)
    np.testing.assert_allclose(plans["fatrop"].qddot[0], plans["ipopt"].qddot[0], atol=5e-2)


def test_warm_start_from_the_shifted_plan_needs_fewer_iterations() -> None:
    controller, q0 = exp1_problem(2, MpcConfig())
    first = solve(controller, q0, np.zeros(7), None)
    assert first.success
    q1, qdot1 = first.plan.q[1], first.plan.qdot[1]
    cold = solve(controller, q1, qdot1, None)
    warm = solve(controller, q1, qdot1, first.plan.shifted(1, controller.config.stage_length))
    assert cold.success and warm.success
    assert warm.iterations < cold.iterations, (warm.iterations, cold.iterations)
    np.testing.assert_allclose(warm.plan.q, cold.plan.q, atol=1e-3)


def test_controller_brakes_finitely_when_every_solve_fails() -> None:
    controller, q0 = exp1_problem(2, MpcConfig(max_iter=1))
    qdot = np.full(7, 0.2)
    commands = [controller(0.01 * k, q0, qdot) for k in range(21)]
    assert controller.failures == 3, "solves at t = 0, 0.1 and 0.2 s, all failed"
    assert controller.plan is None
    for command in commands:
        np.testing.assert_allclose(command, -controller.config.braking_gain * qdot)


def test_controller_keeps_executing_the_previous_plan_when_a_solve_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    data = BLOCKED_LINE
    controller = controller_for(data, MpcConfig())
    q0, qdot = np.array([-1.5, 0.0]), np.zeros(2)
    first = controller(0.0, q0, qdot)
    plan = controller.plan
    assert plan is not None and controller.failures == 0
    np.testing.assert_array_equal(first, plan.qddot[0])
    solve_once = controller.problem.solve

    def failing_solve(*args: Any) -> Any:
        result = solve_once(*args)
        nan_plan = Plan(*(np.full_like(a, np.nan) for a in (plan.q, plan.qdot, plan.qddot, plan.slack)))
        return dataclasses.replace(result, plan=nan_plan, success=False)

    monkeypatch.setattr(controller.problem, "solve", failing_solve)
    second = controller(0.1, plan.q[1], plan.qdot[1])
    between = controller(0.15, plan.q[1], plan.qdot[1])
    third = controller(0.2, plan.q[2], plan.qdot[2])
    assert controller.failures == 2
    np.testing.assert_array_equal(second, plan.qddot[1])
    np.testing.assert_array_equal(between, plan.qddot[1])
    np.testing.assert_array_equal(third, plan.qddot[2])
    assert controller.plan is plan


def test_plan_shift_drops_stages_and_extends_at_constant_velocity() -> None:
    q = np.arange(8.0).reshape(4, 2)
    plan = Plan(q=q, qdot=np.ones((4, 2)), qddot=np.full((3, 2), 2.0), slack=np.array([0.1, 0.2, 0.3]))
    shifted = plan.shifted(1, 0.5)
    np.testing.assert_array_equal(shifted.q[:3], q[1:])
    np.testing.assert_array_equal(shifted.q[3], q[3] + 0.5)
    np.testing.assert_array_equal(shifted.qddot, [[2.0, 2.0], [2.0, 2.0], [0.0, 0.0]])
    np.testing.assert_array_equal(shifted.slack, [0.2, 0.3, 0.0])


def test_problem_is_exact_for_piecewise_constant_accelerations() -> None:
    controller = controller_for(BLOCKED_LINE, MpcConfig())
    result = solve(controller, np.array([-1.5, 0.0]), np.array([0.3, -0.2]), None)
    assert result.success
    plan, h = result.plan, controller.config.stage_length
    np.testing.assert_allclose(plan.q[1:], plan.q[:-1] + h * plan.qdot[:-1] + 0.5 * h * h * plan.qddot, atol=1e-9)
    np.testing.assert_allclose(plan.qdot[1:], plan.qdot[:-1] + h * plan.qddot, atol=1e-9)
    np.testing.assert_allclose(plan.q[0], [-1.5, 0.0], atol=1e-9)


@pytest.mark.parametrize("change", [{"stages": 0}, {"horizon": -1.0}, {"solver": "osqp"}, {"slack_weight": np.nan}])
def test_config_rejects_invalid_values(change: dict[str, Any]) -> None:
    with pytest.raises(ValueError, match="MpcConfig"):
        MpcConfig(**change)


def test_config_defaults_are_the_benchmark_s() -> None:
    config = MpcConfig()
    assert (config.horizon, config.stages, config.solve_period) == (3.0, 30, 0.1)
    assert config.stage_length == pytest.approx(0.1)
    assert (config.goal_weight, config.input_weight, config.velocity_weight, config.slack_weight) == (10, 5, 5, 1e10)


def test_problem_needs_a_goal() -> None:
    with pytest.raises(ValueError, match="goal"):
        MpcProblem(load_robot("point"), (), 0, MpcConfig())
