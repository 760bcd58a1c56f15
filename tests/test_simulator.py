"""Holonomic double-integrator simulator: exact integration, recording, errors."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray

from dynfab.sim import ControllerError, n_steps_for, simulate


def _pd(t: float, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> NDArray[np.float64]:
    """A state- and time-dependent controller: PD towards a moving point."""
    return 4.0 * (np.array([1.0, -0.5]) + 0.1 * np.sin(t) - q) - 3.0 * qdot


def test_constant_acceleration_is_integrated_exactly() -> None:
    a = np.array([0.3, -1.2, 2.0])
    q0, v0 = np.array([1.0, 2.0, -3.0]), np.array([0.5, 0.0, -0.25])
    record = simulate(lambda t, q, qdot: a, q0, v0, dt=0.01, duration=2.0)
    t = record.t[:, None]
    np.testing.assert_allclose(record.q, q0 + v0 * t + 0.5 * a * t**2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(record.qdot, v0 + a * t, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(record.qddot, np.tile(a, (200, 1)))


def test_zero_order_hold_of_a_time_varying_command() -> None:
    # qddot(t) = t held over each period: hand-integrated over two periods of 0.5 s.
    record = simulate(lambda t, q, qdot: [t], [0.0], [0.0], dt=0.5, duration=1.0)
    # step 0: a = 0 -> q = 0, v = 0; step 1: a = 0.5 -> q = 0.5 * 0.5 * 0.25, v = 0.25
    np.testing.assert_allclose(record.q[:, 0], [0.0, 0.0, 0.0625])
    np.testing.assert_allclose(record.qdot[:, 0], [0.0, 0.0, 0.25])
    np.testing.assert_allclose(record.qddot[:, 0], [0.0, 0.5])


def test_substeps_give_the_same_trajectory() -> None:
    one = simulate(_pd, [0.0, 0.0], [0.2, -0.1], dt=0.02, duration=3.0, substeps=1)
    many = simulate(_pd, [0.0, 0.0], [0.2, -0.1], dt=0.02, duration=3.0, substeps=17)
    np.testing.assert_allclose(many.q, one.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(many.qdot, one.qdot, rtol=0, atol=1e-12)
    np.testing.assert_allclose(many.qddot, one.qddot, rtol=0, atol=1e-12)


def test_record_shapes_times_and_read_only() -> None:
    record = simulate(_pd, [0.0, 0.0], [0.0, 0.0], dt=0.01, duration=30.0)
    assert record.steps == 3000
    assert record.t.shape == (3001,)
    assert record.q.shape == record.qdot.shape == (3001, 2)
    assert record.qddot.shape == (3000, 2)
    assert record.solver_time.shape == (3000,)
    assert np.all(record.solver_time >= 0.0)
    np.testing.assert_allclose(record.t, np.arange(3001) * 0.01)
    np.testing.assert_array_equal(record.q[0], [0.0, 0.0])
    for array in (record.t, record.q, record.qdot, record.qddot, record.solver_time):
        assert not array.flags.writeable


def test_controller_sees_each_state_and_cannot_corrupt_it() -> None:
    calls: list[tuple[float, NDArray[np.float64]]] = []

    def controller(t: float, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> list[float]:
        calls.append((t, q.copy()))
        q += 100.0  # must not leak into the simulation
        return [1.0]

    record = simulate(controller, [0.0], [0.0], dt=0.1, duration=0.3)
    assert [t for t, _ in calls] == pytest.approx([0.0, 0.1, 0.2])
    for k, (_, q) in enumerate(calls):
        np.testing.assert_array_equal(q, record.q[k])
    np.testing.assert_allclose(record.q[-1], [0.5 * 0.3**2])


def test_stop_when_truncates_and_progress_reports() -> None:
    seen: list[tuple[int, int]] = []
    record = simulate(
        lambda t, q, qdot: [1.0],
        [0.0],
        [0.0],
        dt=0.1,
        duration=10.0,
        stop_when=lambda t, q, qdot: bool(q[0] > 0.55),
        progress=lambda step, n: seen.append((step, n)),
    )
    # q(t) = t^2 / 2 exceeds 0.55 first at t = 1.1 s, after step 11.
    assert record.steps == 11
    assert record.t[-1] == pytest.approx(1.1)
    assert record.q.shape == (12, 1)
    assert seen == [(k, 100) for k in range(1, 12)]


def test_full_duration_without_stop_predicate() -> None:
    record = simulate(lambda t, q, qdot: [0.0], [1.0], [0.0], dt=0.25, duration=1.0)
    assert record.steps == 4
    np.testing.assert_array_equal(record.q[:, 0], np.ones(5))


def test_non_finite_command_is_a_controller_error() -> None:
    def controller(t: float, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> list[float]:
        return [0.0, np.nan] if t > 0.15 else [0.0, 0.0]

    with pytest.raises(ControllerError, match=r"non-finite acceleration at t = 0\.2000 s \(step 2\)"):
        simulate(controller, [0.0, 0.0], [0.0, 0.0], dt=0.1, duration=1.0)


def test_wrong_command_shape_is_a_controller_error() -> None:
    with pytest.raises(ControllerError, match="returned 3 accelerations .* expected 2"):
        simulate(lambda t, q, qdot: [0.0, 0.0, 0.0], [0.0, 0.0], [0.0, 0.0], dt=0.1, duration=1.0)


@pytest.mark.parametrize(
    ("q0", "qdot0", "dt", "duration", "substeps", "match"),
    [
        ([0.0], [0.0, 0.0], 0.1, 1.0, 1, "1 positions and 1 velocities"),
        ([np.inf], [0.0], 0.1, 1.0, 1, "finite"),
        ([0.0], [0.0], 0.0, 1.0, 1, "dt must be a positive"),
        ([0.0], [0.0], 0.1, 0.05, 1, "duration must be at least dt"),
        ([0.0], [0.0], 0.1, 1.0, 0, "substeps must be at least 1"),
    ],
)
def test_invalid_setup_raises(
    q0: list[float], qdot0: list[float], dt: float, duration: float, substeps: int, match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        simulate(lambda t, q, qdot: q, q0, qdot0, dt=dt, duration=duration, substeps=substeps)


def test_n_steps_absorbs_round_off() -> None:
    assert n_steps_for(30.0, 0.01) == 3000
    assert n_steps_for(0.3, 0.1) == 3
    assert n_steps_for(1.05, 0.1) == 10


def test_differential_drive_follows_an_exact_arc_at_constant_speeds() -> None:
    """Constant v, ω: the base moves on the circle of radius v/ω, whatever the sub-steps."""
    from dynfab.sim import DifferentialDrive

    v, omega = 0.5, 0.4
    record = simulate(lambda t, q, u: np.zeros(3), [0.0, 0.0, 0.0, 0.2], [v, omega, 0.1], 0.01, 5.0,
                      substeps=3, model=DifferentialDrive())
    heading = omega * record.t
    np.testing.assert_allclose(record.q[:, 2], heading, atol=1e-12)
    np.testing.assert_allclose(record.q[:, 0], v / omega * np.sin(heading), atol=1e-12)
    np.testing.assert_allclose(record.q[:, 1], v / omega * (1 - np.cos(heading)), atol=1e-12)
    np.testing.assert_allclose(record.q[:, 3], 0.2 + 0.1 * record.t, atol=1e-12)


def test_differential_drive_never_slides_sideways() -> None:
    """Each sub-step's displacement lies along the chord of an arc tangent to the heading:
    its component normal to the mean heading vanishes to machine precision."""
    from dynfab.sim.models import DifferentialDrive

    rng = np.random.default_rng(4)
    model = DifferentialDrive()
    q, u = np.array([0.3, -0.2, 0.7]), np.array([0.4, -0.3])
    for _ in range(2000):
        acceleration = rng.normal(0, 2.0, 2)
        new_q, u = model.step(q, u, acceleration, 0.01)
        dx, dy = new_q[:2] - q[:2]
        middle = 0.5 * (q[2] + new_q[2])
        assert abs(-dx * np.sin(middle) + dy * np.cos(middle)) <= 4 * np.finfo(float).eps * (1 + np.abs(q[:2]).max())
        q = new_q
