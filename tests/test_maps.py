"""Finite-difference checks of every differential map's J and J̇ q̇."""

from __future__ import annotations

import casadi as ca
import numpy as np

from dynfab.fabric.maps import DifferentialMap, difference, linear_map, selected, sphere_distance_map

RNG = np.random.default_rng(3)


def check_map_against_finite_differences(dmap: DifferentialMap, extra: list[ca.SX] = (),
                                         extra_values: list[np.ndarray] = (), trials: int = 10,
                                         scale: float = 1.0) -> None:
    """J by central differences of φ; J̇ q̇ as d/dt (J q̇) along q(t) = q + t q̇ (q̈ = 0)."""
    n = dmap.q.shape[0]
    inputs = [dmap.q, dmap.qdot, *extra]
    phi = ca.Function("phi", inputs, [dmap.phi])
    jac = ca.Function("J", inputs, [dmap.jacobian])
    jdq = ca.Function("Jdq", inputs, [dmap.jdot_qdot])
    h = 1e-6
    for _ in range(trials):
        q = RNG.normal(size=n) * scale
        qdot = RNG.normal(size=n)
        args = [q, qdot, *extra_values]
        J = np.array(jac(*args))
        for i in range(n):
            dq = np.zeros(n); dq[i] = h
            column = (np.array(phi(q + dq, qdot, *extra_values)) - np.array(phi(q - dq, qdot, *extra_values))) / (2 * h)
            np.testing.assert_allclose(J[:, i], column.ravel(), atol=1e-6, rtol=1e-6)
        velocity_plus = np.array(jac(q + h * qdot, qdot, *extra_values)) @ qdot
        velocity_minus = np.array(jac(q - h * qdot, qdot, *extra_values)) @ qdot
        np.testing.assert_allclose(np.array(jdq(*args)).ravel(), (velocity_plus - velocity_minus) / (2 * h),
                                   atol=1e-6, rtol=1e-5)


def test_sphere_distance_map_closed_form_matches_finite_differences() -> None:
    for dims in (2, 3):
        p, pdot = ca.SX.sym("p", dims), ca.SX.sym("pdot", dims)
        center, radius = ca.SX.sym("c", dims), ca.SX.sym("r")
        dmap = sphere_distance_map(p, pdot, center, radius)
        check_map_against_finite_differences(dmap, [center, radius], [RNG.normal(size=dims), np.array(0.2)])


def test_sphere_distance_is_clearance() -> None:
    p, pdot = ca.SX.sym("p", 3), ca.SX.sym("pdot", 3)
    dmap = sphere_distance_map(p, pdot, ca.DM([1.0, 0.0, 0.0]), ca.DM(0.3))
    value = ca.Function("x", [p], [dmap.phi])(np.array([3.0, 0.0, 0.0]))
    assert abs(float(value) - 1.7) < 1e-3**2 / (2 * 2.0) + 1e-12  # smoothing bias ε²/2d


def test_sphere_distance_map_finite_at_coincident_centres() -> None:
    p, pdot = ca.SX.sym("p", 3), ca.SX.sym("pdot", 3)
    dmap = sphere_distance_map(p, pdot, ca.DM.zeros(3), ca.DM(0.1))
    outputs = ca.Function("m", [p, pdot], [dmap.phi, dmap.jacobian, dmap.jdot_qdot])(np.zeros(3), np.ones(3))
    assert all(np.isfinite(np.array(o)).all() for o in outputs)


def test_derived_map_composition_and_helpers_match_finite_differences() -> None:
    q, qdot = ca.SX.sym("q", 3), ca.SX.sym("qdot", 3)
    arm = DifferentialMap.from_expression(ca.vertcat(ca.cos(q[0]) + ca.cos(q[0] + q[1]), ca.sin(q[0]) * q[2], q[1] * q[2] ** 2), q, qdot)
    check_map_against_finite_differences(arm)
    y, ydot = ca.SX.sym("y", 3), ca.SX.sym("ydot", 3)
    outer = sphere_distance_map(y, ydot, ca.DM([0.1, 0.2, 0.3]), ca.DM(0.1))
    check_map_against_finite_differences(outer.after(arm))
    check_map_against_finite_differences(selected(arm, [0, 2], ca.DM([1.0, 2.0])))
    other = DifferentialMap.from_expression(ca.vertcat(q[0] * q[1], ca.sin(q[2]), q[0]), q, qdot)
    check_map_against_finite_differences(difference(arm, other))
    check_map_against_finite_differences(linear_map(np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]), ca.DM([0.5, 0.1]), q, qdot))
