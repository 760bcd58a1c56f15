"""The MPC baseline on a differential-drive base (the Boxer, Experiment 4, and the Boxer
with the Panda): the plan rolls on arcs without sliding, commands in actuated velocities,
runs end to end, and the arc's sinc is smooth through zero."""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np
import pytest

from dynfab.experiments import exp4
from dynfab.mpc import MpcConfig, MpcController, Plan
from dynfab.mpc.model import sinc
from dynfab.scenario.runner import BASE_SUBSTEPS, RunResult, link_path
from dynfab.sim import DifferentialDrive, simulate
from mpc_helpers import BLOCKED_LINE, LIMIT_TOLERANCE, STAGE_CLEARANCE_TOLERANCE, controller_for, run, solve

# -- robots on a differential-drive base: state (q, u), u = (v, ω, arm rates) ------------


def boxer_scenario(goal: list[float], obstacles: list[dict[str, Any]], duration: float,
                   q0: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> dict[str, Any]:
    """The Boxer at rest at ``q0`` with a base_link goal (tolerance 0.1 m), MPC planner."""
    return {"robot": "boxer", "planner": "mpc", "dt": 0.01, "duration": duration,
            "initial_state": {"q": list(q0)},
            "goal": [{"type": "position", "link": "base_link", "position": goal, "tolerance": 0.1}],
            "obstacles": obstacles}


def lateral_and_forward(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per step of ``q`` (rows ``(x, y, θ, ...)``), the base's displacement across and along
    the mean heading ``m = (θ_k + θ_{k+1}) / 2``: ``−Δx sin m + Δy cos m`` and
    ``Δx cos m + Δy sin m`` [m]."""
    dx, dy = np.diff(q[:, 0]), np.diff(q[:, 1])
    middle = 0.5 * (q[1:, 2] + q[:-1, 2])
    return -dx * np.sin(middle) + dy * np.cos(middle), dx * np.cos(middle) + dy * np.sin(middle)


def graze_bound(result: RunResult) -> float:
    """The between-stage graze ``(s h)² / (8 R)`` [m] of a run (``dynfab.mpc.problem``):
    ``s`` the largest speed of a robot sphere's centre (finite differences of the record;
    a turning base moves its front discs faster than ``v``), ``h`` the stage length,
    ``R`` the smallest sum of a robot sphere's and an obstacle's radius."""
    centres = np.asarray([result.robot.sphere_centers(q) for q in result.record.q])[:, :, :2]
    speed = np.linalg.norm(np.diff(centres, axis=0), axis=2).max() / result.scenario.dt
    radii = min(o.radius for o in result.scenario.obstacles) + result.robot.sphere_radii.min()
    return float((speed * MpcConfig().stage_length) ** 2 / (8 * radii))


def check_base_plan(plan: Plan, controller: MpcController, q0: np.ndarray, u0: np.ndarray) -> None:
    """A Boxer plan: starts at the measured state, each stage is the simulator's
    differential-drive step (one arc), the chord lies along the mean heading, and the
    velocities respect the base's bounds."""
    h = controller.config.stage_length
    base = controller.problem.robot.base
    assert base is not None
    horizon = controller.config.stages
    assert plan.q.shape == (horizon + 1, 3) and plan.qdot.shape == (horizon + 1, 2) and plan.qddot.shape == (horizon, 2)
    np.testing.assert_allclose(plan.q[0], q0, atol=1e-9)
    np.testing.assert_allclose(plan.qdot[0], u0, atol=1e-9)
    model = DifferentialDrive()
    for k in range(horizon):
        q_next, u_next = model.step(plan.q[k], plan.qdot[k], plan.qddot[k], h)
        np.testing.assert_allclose(plan.q[k + 1], q_next, atol=1e-7, err_msg=f"stage {k}")
        np.testing.assert_allclose(plan.qdot[k + 1], u_next, atol=1e-9, err_msg=f"stage {k}")
    lateral, forward = lateral_and_forward(plan.q)
    assert np.abs(lateral).max() < 1e-7, "the predicted base never slides sideways"
    assert np.abs(forward).sum() > 0.5 and np.abs(np.diff(plan.q[:, 2])).sum() > 0.1, "the plan drives and turns"
    assert np.all(np.abs(plan.qdot[1:, 0]) <= base.max_forward_speed + LIMIT_TOLERANCE)
    assert np.all(np.abs(plan.qdot[1:, 1]) <= base.max_yaw_rate + LIMIT_TOLERANCE)


def test_boxer_plan_rolls_without_sliding_sideways() -> None:
    """Single solves for Experiment 4 run 0 (5 discs), from rest and while driving and
    turning: the predicted base motion satisfies ``ẏ cos θ − ẋ sin θ = 0`` (each stage
    is an arc whose chord lies along the mean heading; measured |lateral| ≤ 5e-11 m)."""
    data = exp4.scenario(0, planner="mpc")
    controller = controller_for(data, MpcConfig())
    assert controller.problem.model.differential_drive and controller.problem.model.velocity_size == 2
    q0 = np.array(data["initial_state"]["q"])
    for u0 in (np.zeros(2), np.array([0.6, -0.8])):
        result = solve(controller, q0, u0, None)
        assert result.success, result.status
        check_base_plan(result.plan, controller, q0, u0)
        assert result.plan.slack.max() < STAGE_CLEARANCE_TOLERANCE


def test_boxer_controller_takes_and_returns_actuated_velocities() -> None:
    controller = controller_for(boxer_scenario([1.5, 0.5], [], 1.0), MpcConfig())
    q0 = np.zeros(3)
    with pytest.raises(ValueError, match="qdot"):
        controller(0.0, q0, np.zeros(3))  # configuration-sized velocity: not (v, ω)
    command = controller(0.0, q0, np.zeros(2))
    assert command.shape == (2,) and np.isfinite(command).all()
    assert controller.plan is not None
    np.testing.assert_array_equal(command, controller.plan.qddot[0])
    assert command[0] > 0.0, "the goal lies ahead: accelerate forward"


def test_boxer_reaches_a_goal_behind_it() -> None:
    """base_link's goal 2 m behind and 0.8 m to the left of the start: neither driving
    straight ahead nor straight back reaches it, the base must turn while it drives.
    Measured: reached at 3.45 s backing up (v down to −1.12 m/s) while turning 0.7 rad."""
    result, controller = run(boxer_scenario([-2.0, 0.8], [], 6.0))
    metrics = result.metrics
    assert metrics.success, str(metrics)
    assert metrics.time_to_goal is not None and metrics.time_to_goal < 5.0
    assert np.linalg.norm(result.goal_positions[-1] - [-2.0, 0.8]) < 0.1
    q, u = result.record.q, result.record.qdot
    assert np.abs(q[:, 2]).max() > 0.3, "the base turned"
    assert u.shape == (q.shape[0], 2)
    assert np.abs(u[:, 0]).max() <= 1.9 + LIMIT_TOLERANCE and np.abs(u[:, 1]).max() <= 2.0 + LIMIT_TOLERANCE
    assert controller.failures == 0


def test_commands_keep_the_next_velocity_within_its_limits() -> None:
    """At (and beyond) the velocity limit, a plan that asks for more speed is clipped so that
    ``u + u̇ Δt`` stays within ``±u_max`` (IPOPT's bounds hold to 1e-8 only), and a state
    beyond the limit brakes at most at ``a_max``."""
    controller = controller_for(BLOCKED_LINE, MpcConfig())
    assert controller.control_period == 0.01
    speed = controller.problem.model.velocity_limits
    peak = controller.problem.model.acceleration_limits
    for qdot in (np.array([speed[0], 0.0]), np.array([speed[0] * 1.5, -speed[1] * 1.5])):
        command = controller(0.0, np.array([-1.5, 0.0]), qdot)
        assert (np.abs(command) <= peak).all()
        next_speed = np.abs(qdot + 0.01 * command)
        assert ((next_speed <= speed) | (np.abs(command) == peak) & (next_speed < np.abs(qdot))).all()
    with pytest.raises(ValueError, match="control_period"):
        MpcController(controller.problem, controller.references, controller.obstacle_radii, control_period=0.0)


def test_experiment4_seed0_runs_end_to_end() -> None:
    """Experiment 4 run 0 with ``planner: mpc`` through ``run_scenario`` (cut from 40 s to
    6 s: the goal is reached at 4.13 s and held).

    Measured on the full 40 s run: goal reached at 4.13 s, path 5.15 m, median solve
    12.7 ms (IPOPT, 4 iterations), no failed solve; clearance at the stage times
    +0.3 mm, between them −7.3 mm (the metrics' ``collision`` flag is then set): the
    front discs pass a disc at 2.1 m/s, a graze of up to (0.21 m)² / (8 · 0.49 m) =
    11 mm is allowed by the discrete-time constraints of the benchmark's formulation."""
    data = exp4.scenario(0, planner="mpc")
    data["duration"] = 6.0
    result, controller = run(data)
    metrics = result.metrics
    assert metrics.goal_reached and metrics.time_to_goal is not None and metrics.time_to_goal < 5.0, str(metrics)
    assert np.linalg.norm(result.goal_positions[-1] - data["goal"][0]["position"]) < 0.1
    assert result.clearance[::10].min() >= -STAGE_CLEARANCE_TOLERANCE, "constraints hold at the solve times"
    assert metrics.clearance is not None and metrics.clearance >= -graze_bound(result), str(metrics)
    assert controller.failures == 0
    assert metrics.solver_time_ms is not None and metrics.solver_time_ms > 0.0   # measured; bounds are bench/'s
    assert len(controller.solve_times) == result.record.steps // 10
    u = result.record.qdot
    assert u.shape[1] == 2 and np.isfinite(result.record.qddot).all()
    assert np.abs(u[:, 0]).max() <= 1.9 + LIMIT_TOLERANCE and np.abs(u[:, 1]).max() <= 2.0 + LIMIT_TOLERANCE
    assert metrics.max_velocity_ratio <= 1.0 + 1e-15 and metrics.max_acceleration_ratio <= 1.0 + 1e-15


def test_collision_margin_keeps_experiment4_seed0_clear_between_stages() -> None:
    """``MpcConfig.collision_margin`` = 1 cm covers the graze of run 0 (−7.3 mm with the
    benchmark's 0): measured clearance +2.8 mm, goal still reached at 4.13 s."""
    data = exp4.scenario(0, planner="mpc")
    controller = controller_for(data, MpcConfig(collision_margin=0.01))
    robot = controller.problem.robot
    record = simulate(controller, data["initial_state"]["q"], np.zeros(2), 0.01, 6.0, substeps=BASE_SUBSTEPS,
                      model=DifferentialDrive())
    centres = np.asarray([robot.sphere_centers(q) for q in record.q])[:, :, :2]
    clearance = min(float((np.linalg.norm(centres - o["position"], axis=2) - robot.sphere_radii - o["radius"]).min())
                    for o in data["obstacles"])
    assert clearance > 0.0
    base_link = link_path(robot, "base_link", record.q)[:, :2]
    distance = np.linalg.norm(base_link - data["goal"][0]["position"], axis=1)
    assert distance[-1] < 0.1 and np.argmax(distance < 0.1) * 0.01 < 5.0
    assert controller.failures == 0


def test_boxer_panda_plan_drives_the_base_on_arcs_and_the_arm_as_double_integrators() -> None:
    """The mobile manipulator: ``q = (x, y, θ, 7 joints)``, ``u = (v, ω, 7 rates)``. One
    solve toward a hand goal 2 m ahead past a sphere: the arm joints follow
    ``q_{k+1} = q_k + h u_k + ½ h² u̇_k`` within their limits, the base rolls on arcs."""
    arm = [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]
    data = {"robot": "boxer-panda", "planner": "mpc", "dt": 0.01, "duration": 1.0,
            "initial_state": {"q": [0.0, 0.0, 0.0, *arm]},
            "goal": [{"type": "position", "link": "panda_hand", "position": [2.0, 0.6, 0.7], "tolerance": 0.05}],
            "obstacles": [{"type": "sphere", "position": [1.2, -0.2, 0.3], "radius": 0.3}]}
    controller = controller_for(data, MpcConfig())
    q0 = np.array(data["initial_state"]["q"])
    u0 = np.array([0.3, 0.2, *np.zeros(7)])
    result = solve(controller, q0, u0, None)
    assert result.success, result.status
    plan, h = result.plan, controller.config.stage_length
    assert plan.q.shape == (31, 10) and plan.qdot.shape == (31, 9) and plan.qddot.shape == (30, 9)
    np.testing.assert_allclose(plan.q[1:, 3:], plan.q[:-1, 3:] + h * plan.qdot[:-1, 2:]
                               + 0.5 * h * h * plan.qddot[:, 2:], atol=1e-9)
    np.testing.assert_allclose(plan.qdot[1:], plan.qdot[:-1] + h * plan.qddot, atol=1e-9)
    model = DifferentialDrive()
    for k in range(30):
        np.testing.assert_allclose(plan.q[k + 1], model.step(plan.q[k], plan.qdot[k], plan.qddot[k], h)[0], atol=1e-7)
    lateral, forward = lateral_and_forward(plan.q)
    assert np.abs(lateral).max() < 1e-7 and forward.sum() > 0.5, "the base drives toward the goal, rolling"
    kin = controller.problem.robot.kinematics
    assert np.all(plan.q[1:, 3:] >= kin.lower[3:] - LIMIT_TOLERANCE)
    assert np.all(plan.q[1:, 3:] <= kin.upper[3:] + LIMIT_TOLERANCE)
    assert np.all(np.abs(plan.qdot[1:, 2:]) <= kin.velocity_limits[3:] + LIMIT_TOLERANCE)
    assert np.all(np.abs(plan.qdot[1:, 0]) <= 1.9 + LIMIT_TOLERANCE)
    assert np.all(np.abs(plan.qdot[1:, 1]) <= 2.0 + LIMIT_TOLERANCE)


def test_plan_shift_on_a_base_extends_along_the_arc() -> None:
    """Shifting a Boxer plan appends stages at constant ``(v, ω)`` with the
    differential-drive model: the axle moves on its circle of radius ``v / ω`` about
    ``(x − (v/ω) sin θ, y + (v/ω) cos θ)``, the heading grows by ``ω h``."""
    v, omega, h = 1.0, 0.5, 0.1
    q = np.array([[0.0, 0.0, 0.0], [0.1, 0.0025, 0.05]])
    plan = Plan(q=q, qdot=np.array([[v, omega], [v, omega]]), qddot=np.zeros((1, 2)), slack=np.zeros(1))
    shifted = plan.shifted(1, h, DifferentialDrive())
    np.testing.assert_array_equal(shifted.q[0], q[1])
    radius = v / omega
    centre = q[1, :2] + radius * np.array([-np.sin(q[1, 2]), np.cos(q[1, 2])])
    assert np.linalg.norm(shifted.q[1, :2] - centre) == pytest.approx(radius, abs=1e-12)
    assert shifted.q[1, 2] == pytest.approx(q[1, 2] + omega * h, abs=1e-15)
    np.testing.assert_array_equal(shifted.qdot, [[v, omega], [v, omega]])


def sinc_series(a: float) -> tuple[float, float, float]:
    """sin(a)/a and its first two derivatives from the series ``Σ (−1)^k a^{2k} / (2k+1)!``
    (15 terms: exact in double precision for |a| ≤ 2, no cancellation near 0)."""
    terms = [(-1) ** k / math.factorial(2 * k + 1) for k in range(15)]
    value = sum(c * a ** (2 * k) for k, c in enumerate(terms))
    first = sum(c * 2 * k * a ** (2 * k - 1) for k, c in enumerate(terms) if k >= 1)
    second = sum(c * 2 * k * (2 * k - 1) * a ** (2 * k - 2) for k, c in enumerate(terms) if k >= 1)
    return value, first, second


def test_sinc_of_the_arc_is_smooth_through_zero() -> None:
    """``sinc`` switches to its Taylor polynomial below |a| = 0.1: value, first and second
    derivatives are those of sin(a)/a (1, 0, −1/3 at 0) on both sides of the switch."""
    a = ca.SX.sym("a")
    value = sinc(a)
    first = ca.jacobian(value, a)
    function = ca.Function("sinc", [a], [value, first, ca.jacobian(first, a)])
    for point in (0.0, 1e-12, 1e-3, -0.0999, 0.0999, 0.1001, 0.3, -1.2, 2.0):
        got = [float(x) for x in function(point)]
        np.testing.assert_allclose(got, sinc_series(point), rtol=0, atol=1e-12, err_msg=f"a = {point}")
