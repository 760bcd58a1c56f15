"""Numerical checks of the paper's dynamic-fabric theory (section IV) on random inputs."""

from __future__ import annotations

import casadi as ca
import numpy as np

from dynfab.fabric.energy import Lagrangian, dynamic_energize, finsler_energy
from dynfab.fabric.maps import DifferentialMap, Reference
from dynfab.fabric.spec import Spec

RNG = np.random.default_rng(11)
T = ca.SX.sym("t")
#: an analytic reference x̃(t) in the plane with its derivatives
REFERENCE_POSITION = ca.vertcat(0.5 * ca.sin(0.8 * T) + 0.2 * T, 0.3 * ca.cos(1.3 * T) - 0.1)
REFERENCE = Reference(REFERENCE_POSITION, ca.jacobian(REFERENCE_POSITION, T),
                      ca.jacobian(ca.jacobian(REFERENCE_POSITION, T), T))


def _relative_lagrangian() -> Lagrangian:
    """A dynamic Lagrangian L_d(x_r, ẋ_r) with a position-dependent metric."""
    x, xdot = ca.SX.sym("xr", 2), ca.SX.sym("xrdot", 2)
    metric = ca.SX.eye(2) * (1 + 0.4 * ca.dot(x, x)) + 0.3 * ca.mtimes(x, x.T)
    return Lagrangian(0.5 * ca.mtimes([xdot.T, metric, xdot]) + 0.2 * ca.sin(x[0]) * x[1] * ca.norm_2(xdot), x, xdot)


def _relative_finsler() -> Lagrangian:
    x, xdot = ca.SX.sym("xr", 2), ca.SX.sym("xrdot", 2)
    metric = ca.DM([[1.5, 0.3], [0.3, 1.0]]) * (1 + 0.5 * x[0] ** 2)
    return finsler_energy(ca.sqrt(ca.mtimes([xdot.T, metric, xdot])), x, xdot)


def _relative_geometry() -> Spec:
    """ẍ_r + h_r(x_r, ẋ_r) = 0 with h_r homogeneous of degree 2 in ẋ_r."""
    x, xdot = ca.SX.sym("xr", 2), ca.SX.sym("xrdot", 2)
    return Spec(ca.SX.eye(2), ca.dot(xdot, xdot) * ca.vertcat(0.5 * x[1], -0.3 * x[0]), x, xdot)


def test_euler_lagrange_commutes_with_dynamic_pullback() -> None:
    """Dynamic pull of the spec of L_d equals the generalized Euler-Lagrange equations of
    L_d(x − x̃(t), ẋ − ẋ̃(t)) in the fixed frame, where x̃ depends on time explicitly."""
    x, xdot, xddot = ca.SX.sym("x", 2), ca.SX.sym("xdot", 2), ca.SX.sym("xddot", 2)
    lagrangian = _relative_lagrangian()
    pulled_spec = lagrangian.spec().dynamic_pull(x, xdot, REFERENCE)
    fixed = lagrangian.dynamic_pull(x, xdot, REFERENCE).L
    momentum = ca.gradient(fixed, xdot)
    # d/dt ∂L/∂ẋ along (x(t), ẋ(t)) with the explicit time dependence through x̃(t)
    total_derivative = (ca.mtimes(ca.jacobian(momentum, xdot), xddot) + ca.mtimes(ca.jacobian(momentum, x), xdot)
                        + ca.jacobian(momentum, T))
    euler_lagrange = total_derivative - ca.gradient(fixed, x)
    residual_pulled = ca.mtimes(pulled_spec.M, xddot) + pulled_spec.f
    via_lagrangian = lagrangian.dynamic_pull(x, xdot, REFERENCE).spec()   # the API cannot drop ẍ̃
    residual_via_lagrangian = ca.mtimes(via_lagrangian.M, xddot) + via_lagrangian.f
    check = ca.Function("c", [x, xdot, xddot, T], [euler_lagrange, residual_pulled, residual_via_lagrangian])
    for _ in range(25):
        a, b, c = check(RNG.normal(size=2), RNG.normal(size=2), RNG.normal(size=2), RNG.uniform(0, 10))
        np.testing.assert_allclose(np.array(a), np.array(b), atol=1e-10)
        np.testing.assert_allclose(np.array(a), np.array(c), atol=1e-10)


def _rk4(acceleration: ca.Function, x0: np.ndarray, v0: np.ndarray, dt: float, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Integrate ẍ = a(x, ẋ, t)."""
    n = len(x0)

    def derivative(state: np.ndarray, t: float) -> np.ndarray:
        return np.concatenate([state[n:], np.array(acceleration(state[:n], state[n:], t)).ravel()])

    state = np.concatenate([x0, v0])
    states = [state]
    for k in range(steps):
        t = k * dt
        k1 = derivative(state, t)
        k2 = derivative(state + dt / 2 * k1, t + dt / 2)
        k3 = derivative(state + dt / 2 * k2, t + dt / 2)
        k4 = derivative(state + dt * k3, t + dt)
        state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        states.append(state)
    states = np.array(states)
    return states[:, :n], states[:, n:]


def _dynamically_energized(x: ca.SX, xdot: ca.SX, regularization: float = 0.0) -> tuple[Spec, Lagrangian]:
    """A geometry written in relative coordinates, pulled dynamically and energized with a
    dynamic Finsler energy: dynamically unbiased by construction."""
    lagrangian = _relative_finsler()
    geometry = _relative_geometry().dynamic_pull(x, xdot, REFERENCE)
    energy_spec = lagrangian.spec().dynamic_pull(x, xdot, REFERENCE)
    energized = dynamic_energize(geometry, energy_spec, xdot - REFERENCE.velocity, regularization)
    return energized, lagrangian


def test_dynamic_energization_conserves_dynamic_energy() -> None:
    x, xdot = ca.SX.sym("x", 2), ca.SX.sym("xdot", 2)
    # an arbitrary (biased) geometry in the fixed frame, energized dynamically
    geometry = Spec(ca.SX.eye(2), ca.dot(xdot, xdot) * ca.vertcat(x[1], -0.5 * x[0]) + ca.vertcat(0.3, -0.2), x, xdot)
    lagrangian = _relative_finsler()
    energized = dynamic_energize(geometry, lagrangian.spec().dynamic_pull(x, xdot, REFERENCE), xdot - REFERENCE.velocity)
    acceleration = ca.Function("a", [x, xdot, T], [energized.acceleration()])
    energy = ca.Function("H", [x, xdot, T], [lagrangian.dynamic_pull(x, xdot, REFERENCE).L])  # H_d = L_d (Finsler)
    for _ in range(3):
        dt, steps = 1e-3, 2000
        xs, vs = _rk4(acceleration, RNG.normal(size=2) * 0.5, RNG.normal(size=2), dt, steps)
        values = np.array([float(energy(a, b, k * dt)) for k, (a, b) in enumerate(zip(xs, vs))])
        assert values[0] > 1e-2
        assert np.max(np.abs(values - values[0])) < 1e-8 * values[0]


def test_dynamic_energization_commutes_with_pullback() -> None:
    """energize_{pull L_d}(pull S_h) = pull(energize_{L_d} S_h) with q̇̃ = J⁺ ẋ̃."""
    q, qdot = ca.SX.sym("q", 2), ca.SX.sym("qdot", 2)
    x, xdot = ca.SX.sym("x", 2), ca.SX.sym("xdot", 2)
    dmap = DifferentialMap.from_expression(ca.vertcat(q[0] + 0.3 * ca.sin(q[1]), q[1] + 0.2 * q[0] ** 2), q, qdot)
    geometry = Spec(ca.SX.eye(2), ca.dot(xdot, xdot) * ca.vertcat(x[1], -x[0]) + 0.1 * ca.norm_2(xdot) * xdot, x, xdot)
    energy_spec = _relative_finsler().spec().dynamic_pull(x, xdot, REFERENCE)
    energized_then_pulled = dynamic_energize(geometry, energy_spec, xdot - REFERENCE.velocity).pull(dmap)
    reference_joint_velocity = ca.mtimes(ca.pinv(dmap.jacobian), REFERENCE.velocity)
    pulled_then_energized = dynamic_energize(geometry.pull(dmap), energy_spec.pull(dmap), qdot - reference_joint_velocity)
    check = ca.Function("c", [q, qdot, T], [energized_then_pulled.acceleration(), pulled_then_energized.acceleration()])
    for _ in range(25):
        a, b = check(0.3 * RNG.normal(size=2), RNG.normal(size=2), RNG.uniform(0, 10))
        np.testing.assert_allclose(np.array(a), np.array(b), atol=1e-9)


def test_damped_dynamically_energized_fabric_converges_to_moving_reference() -> None:
    """Lemma "Dynamically energized fabrics": forced by ψ(x − x̃) (∂ψ/∂x = −∂ψ/∂x̃) and
    damped by B ẋ_r, the error x − x̃ goes to zero while x̃ keeps moving."""
    x, xdot = ca.SX.sym("x", 2), ca.SX.sym("xdot", 2)
    energized, _ = _dynamically_energized(x, xdot)
    error = x - REFERENCE.position
    potential = 3.0 * ca.sumsqr(error) + 0.5 * ca.sin(error[0]) ** 2
    damping = 2.0 * (xdot - REFERENCE.velocity)
    closed_loop = Spec(energized.M, energized.f + ca.gradient(potential, x) + damping, x, xdot)
    acceleration = ca.Function("a", [x, xdot, T], [closed_loop.acceleration()])
    reference = ca.Function("r", [T], [REFERENCE.position, REFERENCE.velocity])
    dt, steps = 2e-3, 10000
    for _ in range(3):
        xs, vs = _rk4(acceleration, RNG.normal(size=2), RNG.normal(size=2), dt, steps)
        target, target_velocity = (np.array(v).ravel() for v in reference(steps * dt))
        initial_error = np.linalg.norm(xs[0] - np.array(reference(0)[0]).ravel())
        assert initial_error > 0.1
        assert np.linalg.norm(xs[-1] - target) < 1e-4
        assert np.linalg.norm(vs[-1] - target_velocity) < 1e-3


def test_dynamically_unbiased_spec_started_on_reference_stays_on_it() -> None:
    x, xdot = ca.SX.sym("x", 2), ca.SX.sym("xdot", 2)
    energized, _ = _dynamically_energized(x, xdot, regularization=1e-12)  # α finite at ẋ_r = 0
    damped = Spec(energized.M, energized.f + 1.5 * (xdot - REFERENCE.velocity), x, xdot)
    acceleration = ca.Function("a", [x, xdot, T], [damped.acceleration()])
    reference = ca.Function("r", [T], [REFERENCE.position, REFERENCE.velocity])
    x0, v0 = (np.array(v).ravel() for v in reference(0.0))
    dt, steps = 1e-3, 3000
    xs, _ = _rk4(acceleration, x0, v0, dt, steps)
    expected = np.array([np.array(reference(k * dt)[0]).ravel() for k in range(steps + 1)])
    assert np.max(np.linalg.norm(xs - expected, axis=1)) < 1e-9
