"""Numerical checks of the spec algebra (paper section III) on random inputs."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.energy import Lagrangian, WeightedGeometry, energize, finsler_energy
from dynfab.fabric.linalg import cholesky_solve, congruence
from dynfab.fabric.maps import DifferentialMap
from dynfab.fabric.spec import Spec

RNG = np.random.default_rng(7)


def _symbols(n: int, name: str) -> tuple[ca.SX, ca.SX]:
    return ca.SX.sym(name, n), ca.SX.sym(name + "dot", n)


def _evaluate(expressions: list[ca.SX], symbols: list[ca.SX], values: list[np.ndarray]) -> list[np.ndarray]:
    function = ca.Function("f", symbols, expressions)
    return [np.array(v) for v in function(*values)] if len(expressions) > 1 else [np.array(function(*values))]


def _arm_map(q: ca.SX, qdot: ca.SX) -> DifferentialMap:
    """A nonlinear 3 -> 2 map (planar three-link arm tip)."""
    angles = ca.cumsum(q)
    phi = ca.vertcat(ca.sum1(ca.cos(angles) * ca.DM([1.0, 0.7, 0.4])),
                     ca.sum1(ca.sin(angles) * ca.DM([1.0, 0.7, 0.4])))
    return DifferentialMap.from_expression(phi, q, qdot)


def _task_lagrangian(x: ca.SX, xdot: ca.SX) -> Lagrangian:
    """A non-trivial Lagrangian with a position-dependent metric and a potential."""
    metric = ca.SX.eye(2) * (1 + 0.3 * ca.dot(x, x)) + 0.2 * ca.mtimes(x, x.T)
    return Lagrangian(0.5 * ca.mtimes([xdot.T, metric, xdot]) - ca.sin(x[0]) * x[1], x, xdot)


def test_pullback_of_lagrangian_spec_equals_spec_of_pulled_lagrangian() -> None:
    q, qdot = _symbols(3, "q")
    x, xdot = _symbols(2, "x")
    dmap = _arm_map(q, qdot)
    lagrangian = _task_lagrangian(x, xdot)
    pulled_spec = lagrangian.spec().pull(dmap)
    spec_of_pulled = lagrangian.pull(dmap).spec()
    for _ in range(20):
        values = [RNG.normal(size=3), RNG.normal(size=3)]
        M1, f1, M2, f2 = _evaluate([pulled_spec.M, pulled_spec.f, spec_of_pulled.M, spec_of_pulled.f],
                                   [q, qdot], values)
        np.testing.assert_allclose(M1, M2, atol=1e-10)
        np.testing.assert_allclose(f1, f2, atol=1e-10)


def test_pullbacks_compose() -> None:
    q, qdot = _symbols(3, "q")
    y, ydot = _symbols(2, "y")
    x, xdot = _symbols(2, "x")
    inner = _arm_map(q, qdot)
    outer = DifferentialMap.from_expression(ca.vertcat(ca.sin(y[0]) * y[1], y[0] ** 2 + ca.exp(y[1])), y, ydot)
    spec = _task_lagrangian(x, xdot).spec()
    twice = spec.pull(outer).pull(inner)
    once = spec.pull(outer.after(inner))
    for _ in range(20):
        values = [RNG.normal(size=3), RNG.normal(size=3)]
        M1, f1, M2, f2 = _evaluate([twice.M, twice.f, once.M, once.f], [q, qdot], values)
        np.testing.assert_allclose(M1, M2, atol=1e-10)
        np.testing.assert_allclose(f1, f2, atol=1e-10)


def test_summation_adds_metrics_and_forces() -> None:
    x, xdot = _symbols(2, "x")
    a = _task_lagrangian(x, xdot).spec()
    b = Spec(ca.SX.eye(2) * 2, x * 3 + xdot, x, xdot)
    total = a + b
    values = [RNG.normal(size=2), RNG.normal(size=2)]
    Ma, fa, Mb, fb, M, f = _evaluate([a.M, a.f, b.M, b.f, total.M, total.f], [x, xdot], values)
    np.testing.assert_allclose(M, Ma + Mb, atol=1e-12)
    np.testing.assert_allclose(f, fa + fb, atol=1e-12)


def test_summation_rejects_different_spaces() -> None:
    x, xdot = _symbols(2, "x")
    y, ydot = _symbols(2, "y")
    with pytest.raises(ValueError, match="different spaces"):
        _ = Spec(ca.SX.eye(2), x, x, xdot) + Spec(ca.SX.eye(2), y, y, ydot)


def test_energization_commutes_with_pullback() -> None:
    """energize_{L∘φ}(pull_φ S_h) has the same trajectories as pull_φ energize_L(S_h):
    both accelerations agree after the pullback (static maps, paper eq. (pulled_energized))."""
    q, qdot = _symbols(2, "q")
    x, xdot = _symbols(2, "x")
    phi = ca.vertcat(q[0] + 0.3 * ca.sin(q[1]), q[1] + 0.2 * q[0] ** 2)  # invertible near 0
    dmap = DifferentialMap.from_expression(phi, q, qdot)
    geometry = Spec(ca.SX.eye(2), ca.dot(xdot, xdot) * ca.vertcat(x[1], -x[0]), x, xdot)
    lagrangian = finsler_energy(ca.sqrt(ca.mtimes([xdot.T, ca.DM([[2, 0.5], [0.5, 1]]), xdot])) * (1 + 0.1 * x[0] ** 2), x, xdot)
    energized_then_pulled = energize(geometry, lagrangian).pull(dmap)
    pulled_geometry = geometry.pull(dmap)
    pulled_h = Spec(ca.SX.eye(2), -pulled_geometry.acceleration(), q, qdot)
    pulled_then_energized = energize(pulled_h, lagrangian.pull(dmap))
    for _ in range(20):
        values = [0.3 * RNG.normal(size=2), RNG.normal(size=2)]
        a1, a2 = _evaluate([energized_then_pulled.acceleration(), pulled_then_energized.acceleration()],
                           [q, qdot], values)
        np.testing.assert_allclose(a1, a2, atol=1e-9)


def _rk4(acceleration: ca.Function, x0: np.ndarray, v0: np.ndarray, dt: float, steps: int) -> tuple[np.ndarray, np.ndarray]:
    xs, vs = [x0], [v0]
    x, v = x0, v0
    for _ in range(steps):
        def deriv(state):
            return np.concatenate([state[len(x0):], np.array(acceleration(state[:len(x0)], state[len(x0):])).ravel()])
        s = np.concatenate([x, v])
        k1 = deriv(s); k2 = deriv(s + dt / 2 * k1); k3 = deriv(s + dt / 2 * k2); k4 = deriv(s + dt * k3)
        s = s + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        x, v = s[:len(x0)], s[len(x0):]
        xs.append(x); vs.append(v)
    return np.array(xs), np.array(vs)


def _curving_geometry(x: ca.SX, xdot: ca.SX) -> Spec:
    """A path-consistent geometry: h(x, α ẋ) = α² h(x, ẋ)."""
    return Spec(ca.SX.eye(2), ca.dot(xdot, xdot) * ca.vertcat(0.5 * x[1], -0.3 * x[0]) + 0.4 * xdot * ca.norm_2(xdot) * x[0], x, xdot)


def _finsler(x: ca.SX, xdot: ca.SX) -> Lagrangian:
    metric = ca.DM([[1.5, 0.3], [0.3, 1.0]]) * (1 + 0.5 * x[0] ** 2)
    return finsler_energy(ca.sqrt(ca.mtimes([xdot.T, metric, xdot])), x, xdot)


def test_energization_conserves_energy_along_trajectory() -> None:
    x, xdot = _symbols(2, "x")
    lagrangian = _finsler(x, xdot)
    energized = energize(_curving_geometry(x, xdot), lagrangian)
    acceleration = ca.Function("a", [x, xdot], [energized.acceleration()])
    energy = ca.Function("H", [x, xdot], [lagrangian.energy()])
    for _ in range(3):
        xs, vs = _rk4(acceleration, RNG.normal(size=2) * 0.5, RNG.normal(size=2), 1e-3, 2000)
        values = np.array([float(energy(a, b)) for a, b in zip(xs, vs)])
        assert np.max(np.abs(values - values[0])) < 1e-9 * max(1.0, abs(values[0]))


def test_energized_path_consistent_geometry_traces_same_path() -> None:
    x, xdot = _symbols(2, "x")
    geometry = _curving_geometry(x, xdot)
    energized = energize(geometry, _finsler(x, xdot))
    geometry_acc = ca.Function("g", [x, xdot], [geometry.acceleration()])
    energized_acc = ca.Function("e", [x, xdot], [energized.acceleration()])
    x0, v0 = np.array([0.3, -0.2]), np.array([0.8, 0.5])
    path_geometry, _ = _rk4(geometry_acc, x0, v0, 1e-3, 3000)
    path_energized, _ = _rk4(energized_acc, x0, v0, 1e-3, 1500)
    # every point of the energized path lies on the geometry's path (speed differs, path not)
    for point in path_energized[::50]:
        assert np.min(np.linalg.norm(path_geometry - point, axis=1)) < 2e-3
    assert np.linalg.norm(path_energized[-1] - x0) > 0.3  # it really moved


def test_damped_forced_fabric_converges_to_potential_minimum() -> None:
    x, xdot = _symbols(2, "x")
    minimum = np.array([0.4, -0.3])
    potential = 2.0 * ca.sumsqr(x - minimum) + 0.5 * ca.sin(x[0] - minimum[0]) ** 2
    energized = energize(_curving_geometry(x, xdot), _finsler(x, xdot), regularization=1e-9)
    forced = energized.forced(potential)
    damped = Spec(forced.M, forced.f + ca.mtimes(forced.M, 1.5 * xdot), x, xdot)
    acceleration = ca.Function("a", [x, xdot], [damped.acceleration()])
    for _ in range(3):
        xs, vs = _rk4(acceleration, RNG.normal(size=2), RNG.normal(size=2), 5e-3, 4000)
        np.testing.assert_allclose(xs[-1], minimum, atol=1e-4)
        assert np.linalg.norm(vs[-1]) < 1e-4


def test_weighted_geometry_pullback_matches_spec_pullback() -> None:
    q, qdot = _symbols(3, "q")
    x, xdot = _symbols(2, "x")
    dmap = _arm_map(q, qdot)
    h = ca.dot(xdot, xdot) * ca.vertcat(x[1], -x[0])
    weighted = WeightedGeometry.from_parts(h, _finsler(x, xdot))
    pulled = weighted.pull(dmap)
    reference_geometry = weighted.geometry_spec().pull(dmap)
    reference_energy = weighted.energy_spec().pull(dmap)
    values = [RNG.normal(size=3), RNG.normal(size=3)]
    got = _evaluate([pulled.M, pulled.f_geometry, pulled.f_energy], [q, qdot], values)
    want = _evaluate([reference_geometry.M, reference_geometry.f, reference_energy.f], [q, qdot], values)
    for a, b in zip(got, want):
        np.testing.assert_allclose(a, b, atol=1e-12)


def test_congruence_and_cholesky_solve_match_dense_algebra() -> None:
    J = ca.SX.sym("J", 3, 5)
    A = ca.SX.sym("A", 5, 5)
    b = ca.SX.sym("b", 5)
    M_values = RNG.normal(size=(3, 3)); M_values = M_values @ M_values.T
    J_values = RNG.normal(size=(3, 5))
    result = ca.Function("c", [J], [congruence(J, ca.DM(M_values))])(J_values)
    np.testing.assert_allclose(np.array(result), J_values.T @ M_values @ J_values, atol=1e-12)
    A_values = RNG.normal(size=(5, 5)); A_values = A_values @ A_values.T + 0.1 * np.eye(5)
    b_values = RNG.normal(size=5)
    solution = ca.Function("s", [A, b], [cholesky_solve(A, b)])(A_values, b_values)
    np.testing.assert_allclose(np.array(solution).ravel(), np.linalg.solve(A_values, b_values), atol=1e-10)
