"""The non-holonomic root solve (paper section V)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from dynfab.fabric.nonholonomic import least_squares_acceleration, velocity_map, velocity_map_derivative

RNG = np.random.default_rng(21)


def _spd(n: int, condition: float = 1e3) -> np.ndarray:
    basis, _ = np.linalg.qr(RNG.normal(size=(n, n)))
    return basis @ np.diag(np.geomspace(1.0, condition, n)) @ basis.T


def test_least_squares_solution_satisfies_the_normal_equations() -> None:
    n = 6
    q, u = ca.SX.sym("q", n), ca.SX.sym("u", n - 1)
    M, desired = ca.SX.sym("M", n, n), ca.SX.sym("a", n)
    jacobian = velocity_map(q)
    solution = least_squares_acceleration(M, desired, jacobian, velocity_map_derivative(q, u))
    f = ca.Function("f", [M, desired, q, u], [solution, jacobian, velocity_map_derivative(q, u)])
    for _ in range(20):
        metric, target = _spd(n), RNG.normal(size=n)
        qv, uv = RNG.normal(size=n), RNG.normal(size=n - 1)
        qddot_u, J, jdot_u = (np.array(v) for v in f(metric, target, qv, uv))
        qddot_u, jdot_u = qddot_u.ravel(), jdot_u.ravel()
        M_nh, f_nh = metric @ J, metric @ (jdot_u - target)
        residual = M_nh.T @ (M_nh @ qddot_u + f_nh)  # gradient of ½‖M_nh q̈_u + f_nh‖²
        assert np.linalg.norm(residual) <= 1e-8 * np.linalg.norm(M_nh.T @ f_nh)
        # and it is the minimiser: no random direction does better
        best = np.linalg.norm(M_nh @ qddot_u + f_nh)
        for _ in range(5):
            assert np.linalg.norm(M_nh @ (qddot_u + 1e-3 * RNG.normal(size=n - 1)) + f_nh) >= best


def test_identity_map_reproduces_the_holonomic_acceleration() -> None:
    n = 7
    M, desired = ca.SX.sym("M", n, n), ca.SX.sym("a", n)
    solution = ca.Function("s", [M, desired], [least_squares_acceleration(M, desired, ca.SX.eye(n), ca.SX(n, 1))])
    for _ in range(20):
        target = RNG.normal(size=n)
        # normal equations square the condition number (1e3 here): agreement to ~1e-10
        np.testing.assert_allclose(np.array(solution(_spd(n, 1e3), target)).ravel(), target, rtol=1e-8, atol=1e-10)


def test_velocity_map_and_its_derivative_match_finite_differences() -> None:
    n = 5
    q, u = ca.SX.sym("q", n), ca.SX.sym("u", n - 1)
    f = ca.Function("f", [q, u], [ca.mtimes(velocity_map(q), u), velocity_map_derivative(q, u)])
    h = 1e-6
    for _ in range(20):
        qv, uv = RNG.normal(size=n), RNG.normal(size=n - 1)
        qdot, jdot_u = (np.array(v).ravel() for v in f(qv, uv))
        assert abs(-qdot[0] * np.sin(qv[2]) + qdot[1] * np.cos(qv[2])) < 1e-15  # no sideways velocity
        np.testing.assert_allclose(qdot[:3], [uv[0] * np.cos(qv[2]), uv[0] * np.sin(qv[2]), uv[1]], atol=1e-15)
        # J̇ q̇_u = d/dt (J(q(t)) q̇_u) along q̇ = J q̇_u with q̇_u held constant
        plus = np.array(f(qv + h * qdot, uv)[0]).ravel()
        minus = np.array(f(qv - h * qdot, uv)[0]).ravel()
        np.testing.assert_allclose(jdot_u, (plus - minus) / (2 * h), atol=1e-7)


def test_steering_term_turns_a_base_toward_a_lateral_goal_direction() -> None:
    """With the base at rest and the fabric asking for a purely lateral acceleration, the
    plain least squares cannot do anything (ω̇ = 0), while the look-ahead term turns the
    base toward that side (ω̇ > 0 for a leftward request)."""
    from dynfab.fabric.nonholonomic import Steering

    n = 3
    q, u = ca.SX.sym("q", n), ca.SX.sym("u", n - 1)
    jacobian, jdot_u = velocity_map(q), velocity_map_derivative(q, u)
    M = ca.SX.eye(n)
    left = ca.DM([0.0, 1.0, 0.0])  # heading along x: "left" is +y
    plain = ca.Function("p", [q, u], [least_squares_acceleration(M, left, jacobian, jdot_u)])
    steered = ca.Function("s", [q, u], [least_squares_acceleration(M, left, jacobian, jdot_u, Steering(0.5, 1.0), q)])
    at_rest = ([0.0, 0.0, 0.0], [0.0, 0.0])
    np.testing.assert_allclose(np.array(plain(*at_rest)).ravel(), 0.0, atol=1e-12)
    forward, turn = np.array(steered(*at_rest)).ravel()
    assert abs(forward) < 1e-12 and turn > 0.1
