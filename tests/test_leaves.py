"""The leaves' closed forms agree with the general Euler-Lagrange path, and their shapes."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.leaves.barrier import Barrier

RNG = np.random.default_rng(5)


@pytest.mark.parametrize("barrier", [Barrier(), Barrier(geometry_gain=5.0, energy_gain=0.5, horizon=0.2),
                                     Barrier(geometry_gain=5.0, energy_gain=0.02, horizon=0.1, offset=0.005),
                                     Barrier(geometry=lambda x, xdot: -1.0 / x**2 * xdot**2, horizon=1.0)])
def test_default_barrier_closed_form_equals_euler_lagrange(barrier: Barrier) -> None:
    closed = barrier.weighted_geometry()
    lagrangian = barrier.lagrangian()
    h = closed.f_geometry / ca.fmax(closed.M, 1e-300)  # recover h where the metric is active
    general = WeightedGeometry.from_parts(ca.substitute(h, closed.x, lagrangian.x), lagrangian)
    f = ca.Function("f", [closed.x, closed.xdot, lagrangian.x, lagrangian.xdot],
                    [closed.M, closed.f_geometry, closed.f_energy, general.M, general.f_geometry, general.f_energy])
    for _ in range(200):
        x = RNG.uniform(-0.05, 1.2 * barrier.horizon)
        xdot = RNG.normal()
        values = [float(v) for v in f(x, xdot, x, xdot)]
        for a, b in zip(values[:3], values[3:]):
            assert a == pytest.approx(b, rel=1e-9, abs=1e-9)


def test_barrier_metric_active_only_while_approaching_within_range() -> None:
    barrier = Barrier(energy_gain=0.5, horizon=0.2)
    leaf = barrier.weighted_geometry()
    metric = ca.Function("m", [leaf.x, leaf.xdot], [leaf.M])
    assert float(metric(0.1, -0.3)) == pytest.approx(2 * 0.5 * (10 - 5) ** 2)
    assert float(metric(0.1, 0.3)) == 0.0
    assert float(metric(0.25, -0.3)) == 0.0
    assert np.isfinite(float(metric(-0.5, -1.0)))


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"min_clearance": 0.0}, "min_clearance"), ({"energy_gain": -1.0}, "gains"),
    ({"horizon": 1e-4}, "horizon")])
def test_barrier_rejects_bad_parameters(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Barrier(**kwargs)


def test_an_offset_barrier_is_the_plain_one_shifted_by_its_offset() -> None:
    def evaluate(barrier: Barrier, x: float, xdot: float) -> list[np.ndarray]:
        spec = barrier.weighted_geometry()
        leaf = ca.Function("leaf", [spec.x, spec.xdot], [spec.M, spec.f_geometry, spec.f_energy])
        return [np.asarray(v) for v in leaf(x, xdot)]

    plain, shifted = Barrier(energy_gain=0.5, horizon=0.2), Barrier(energy_gain=0.5, horizon=0.2, offset=0.005)
    for x, xdot in ((0.03, -0.2), (0.1, -1.0), (0.004, -0.5), (0.3, -0.1), (0.05, 0.3)):
        np.testing.assert_allclose(evaluate(shifted, x + 0.005, xdot), evaluate(plain, x, xdot), rtol=1e-12, atol=1e-12)
    assert evaluate(shifted, 0.004, -0.5)[0] > evaluate(plain, 0.004, -0.5)[0]   # 4 mm is 1 mm past the buffer


@pytest.mark.parametrize("barrier", [Barrier(geometry_gain=5.0, energy_gain=0.02, horizon=0.1, offset=0.005, braking=4.0),
                                     Barrier(energy=lambda x, xdot: 0.1 / x**2 * xdot**2, braking=2.0)])
def test_braking_barrier_is_the_euler_lagrange_spec_with_its_stopping_distance_held(barrier: Barrier) -> None:
    closed = barrier.weighted_geometry()
    held = ca.SX.sym("held")
    lagrangian = barrier.lagrangian(held)
    spec = lagrangian.spec()
    assert barrier.braking is not None
    stopping = ca.fmin(lagrangian.xdot, 0) ** 2 / (2 * barrier.braking)
    M, f = ca.substitute([spec.M, spec.f], [held], [stopping])
    f_closed = ca.Function("c", [closed.x, closed.xdot], [closed.M, closed.f_energy])
    f_general = ca.Function("g", [lagrangian.x, lagrangian.xdot], [M, f])
    for _ in range(200):
        x, xdot = RNG.uniform(-0.05, 1.2 * barrier.horizon), RNG.normal()
        for a, b in zip(f_closed(x, xdot), f_general(x, xdot)):
            assert float(a) == pytest.approx(float(b), rel=1e-9, abs=1e-9)


def test_a_braking_barrier_weights_the_clearance_left_after_a_stop() -> None:
    def evaluate(barrier: Barrier, x: float, xdot: float) -> list[float]:
        spec = barrier.weighted_geometry()
        leaf = ca.Function("leaf", [spec.x, spec.xdot], [spec.M, spec.f_geometry / spec.M, spec.f_energy])
        return [float(v) for v in leaf(x, xdot)]

    plain, braking = Barrier(energy_gain=0.5, horizon=0.2), Barrier(energy_gain=0.5, horizon=0.2, braking=4.0)
    # approaching at 0.8 m/s: a stop at 4 m/s² takes 0.08 m; the energy sees 0.15 m as 0.07 m
    metric, h, f_energy = evaluate(braking, 0.15, -0.8)
    plain_metric, _, plain_f_energy = evaluate(plain, 0.07, -0.8)
    assert (metric, f_energy) == (pytest.approx(plain_metric, rel=1e-12), pytest.approx(plain_f_energy, rel=1e-12))
    assert metric > 10 * evaluate(plain, 0.15, -0.8)[0]
    assert h == pytest.approx(evaluate(plain, 0.15, -0.8)[1], rel=1e-12)   # the geometry is the paper's
    # moving away (and at rest) nothing is taken off
    np.testing.assert_allclose(evaluate(braking, 0.05, 0.8)[::2], evaluate(plain, 0.05, 0.8)[::2], rtol=1e-12)
    np.testing.assert_allclose(evaluate(braking, 0.05, -1e-9), evaluate(plain, 0.05, -1e-9), rtol=1e-9)
    # a stop that no longer fits: clamped, finite
    assert all(np.isfinite(evaluate(braking, 0.01, -3.0)))


@pytest.mark.parametrize("braking", [0.0, -1.0, float("inf"), float("nan")])
def test_barrier_rejects_a_braking_that_is_not_a_positive_deceleration(braking: float) -> None:
    with pytest.raises(ValueError, match="Barrier.braking"):
        Barrier(braking=braking)
