"""The command bounds: every output inside the acceleration limits, velocity and position
limits kept over a run, the fabric's direction kept where the bounds allow."""

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.command_bounds import CommandBounds
from dynfab.robots.limits import MotionLimits

DT = 0.01
LIMITS = MotionLimits(("a", "b", "c"), np.array([2.0, 1.0, 3.0]), np.array([10.0, 5.0, 20.0]))
LOWER, UPPER = np.array([-1.0, -np.inf, 0.0]), np.array([1.0, np.inf, 0.5])


def bounded_function(limits: MotionLimits = LIMITS, dt: float = DT) -> ca.Function:
    q, v, a, previous = (ca.SX.sym(name, limits.size) for name in ("q", "v", "a", "previous"))
    bounds = CommandBounds(limits, LOWER, UPPER, dt)
    command = bounds.bounded(q, v, a, previous if limits.jerk is not None else None)
    return ca.Function("bounded", [q, v, a, previous], [command])


def evaluate(function: ca.Function, q, v, a, previous=np.zeros(3)) -> np.ndarray:
    return np.array(function(q, v, a, previous)).ravel()


def test_every_command_is_within_the_acceleration_limits_whatever_the_input() -> None:
    function = bounded_function()
    rng = np.random.default_rng(0)
    for _ in range(3000):
        q = rng.uniform(-3, 3, 3)                      # inside and beyond the position limits
        v = rng.uniform(-10, 10, 3)                    # inside and beyond the velocity limits
        a = rng.normal(size=3) * 10.0 ** rng.uniform(-3, 12)
        command = evaluate(function, q, v, a)
        assert np.isfinite(command).all()
        assert (np.abs(command) <= LIMITS.acceleration * (1 + 1e-12)).all()


def test_a_robot_pushed_at_its_limits_never_crosses_them() -> None:
    """An adversarial fabric pushes every joint outward as hard as it can for 3 s: the
    positions stay inside the limits, the speeds below theirs."""
    function = bounded_function()
    rng = np.random.default_rng(1)
    for _ in range(20):
        q, v = np.array([0.0, 0.0, 0.25]), rng.uniform(-0.5, 0.5, 3)
        push = rng.choice([-1.0, 1.0], 3) * 10.0 ** rng.uniform(0, 6, 3)
        for _ in range(300):
            a = evaluate(function, q, v, push + rng.normal(size=3))
            q, v = q + v * DT + 0.5 * a * DT**2, v + a * DT
            assert (q >= LOWER - 1e-12).all() and (q <= UPPER + 1e-12).all()
            assert (np.abs(v) <= LIMITS.velocity + 1e-12).all()


def test_a_command_inside_the_limits_passes_unchanged() -> None:
    command = evaluate(bounded_function(), [0.0, 0.0, 0.25], [0.1, -0.2, 0.0], [3.0, -2.0, 1.0])
    np.testing.assert_allclose(command, [3.0, -2.0, 1.0], rtol=0, atol=1e-15)


def test_too_large_a_command_is_scaled_keeping_its_direction() -> None:
    a = np.array([40.0, -10.0, 20.0])  # 4x, 2x and 1x the limits
    command = evaluate(bounded_function(), [0.0, 0.0, 0.25], [0.0, 0.0, 0.0], a)
    np.testing.assert_allclose(command, a / 4, rtol=1e-12)


def test_a_joint_at_its_velocity_limit_slows_the_motion_along_its_path() -> None:
    """Joint a at +2 rad/s is pushed further: the command brakes along the velocity
    (a + γ v), so joint b, moving at 0.5 rad/s with no push, brakes in proportion."""
    v = np.array([2.0, 0.5, 0.0])
    command = evaluate(bounded_function(), [0.0, 0.0, 0.25], v, [4.0, 0.0, 0.0])
    assert command[0] == pytest.approx(0.0, abs=1e-12)
    assert command[1] == pytest.approx(-4.0 * 0.5 / 2.0)


def test_a_non_finite_fabric_command_stays_non_finite_for_the_fallback() -> None:
    function = bounded_function()
    for bad in (np.nan, np.inf, -np.inf):
        command = evaluate(function, [0.0, 0.0, 0.25], [0.1, 0.0, 0.0], [bad, 1.0, 0.0])
        assert not np.isfinite(command).all()


def test_a_jerk_limit_bounds_the_change_of_command() -> None:
    limits = MotionLimits(LIMITS.names, LIMITS.velocity, LIMITS.acceleration, jerk=np.array([100.0, 50.0, 200.0]))
    function = bounded_function(limits)
    rng = np.random.default_rng(2)
    previous = np.zeros(3)
    for _ in range(200):
        command = evaluate(function, [0.0, 0.0, 0.25], rng.uniform(-0.1, 0.1, 3), rng.normal(size=3) * 30, previous)
        assert (np.abs(command - previous) <= limits.jerk * DT * (1 + 1e-12)).all()
        previous = command


def test_bounds_refuse_bad_values() -> None:
    with pytest.raises(ValueError, match="time_step"):
        CommandBounds(LIMITS, LOWER, UPPER, 0.0)
    with pytest.raises(ValueError, match="lower must be 3 numbers"):
        CommandBounds(LIMITS, LOWER[:2], UPPER)


def test_a_joint_resting_at_its_limit_and_pushed_into_it_does_not_freeze_the_others() -> None:
    command = evaluate(bounded_function(), [-1.0, 0.0, 0.25], [0.0, 0.0, 0.0], [-5.0, 2.0, 1.0])
    np.testing.assert_allclose(command, [0.0, 2.0, 1.0], atol=1e-12)
