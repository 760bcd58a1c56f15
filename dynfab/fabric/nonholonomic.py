"""Non-holonomic robots (paper section V): the least-squares root solve.

A robot on a differential-drive base has configuration ``q = (x, y, θ, arm...)`` but only
``n − 1`` actuated velocities ``q̇_u = (v, ω, arm rates...)``: forward speed [m/s], yaw
rate [rad/s] and the arm's joint rates. They map to the configuration velocity by

    q̇ = J_nh(q) q̇_u,   J_nh = blockdiag([[cos θ, 0], [sin θ, 0], [0, 1]], I),

and ``q̈ = J_nh q̈_u + J̇_nh q̇_u``. The fabric is built on ``q`` as for any robot; its root
asks for ``q̈*``, i.e. ``M q̈ + f = 0`` with ``f = −M q̈*`` (``M`` the root metric). With
``M_nh = M J_nh`` and ``f_nh = M J̇_nh q̇_u + f`` the actuated acceleration solves

    min ‖M_nh q̈_u + f_nh‖²   ⇒   (M_nhᵀ M_nh + λ I) q̈_u = −M_nhᵀ f_nh,

``M_nh`` has full column rank (``M ⪰ c I`` with the planner's base metric ``c > 0`` and
``J_nh`` has orthonormal columns), so ``M_nhᵀ M_nh ⪰ c² I`` and the Cholesky solve is
always defined; the Tikhonov term ``λ = 10⁻¹²`` only guards rounding. For ``J_nh = I``
the solution is ``q̈*`` (to a relative ``λ/c²``): the standard fabric.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from dynfab.fabric.linalg import cholesky_solve

TIKHONOV = 1e-12


def velocity_map(q: ca.SX) -> ca.SX:
    """``J_nh(q)`` of a differential-drive base carrying ``len(q) − 3`` arm joints."""
    n = q.shape[0]
    jacobian = ca.SX(n, n - 1)
    jacobian[0, 0] = ca.cos(q[2])
    jacobian[1, 0] = ca.sin(q[2])
    jacobian[2, 1] = 1
    for i in range(3, n):
        jacobian[i, i - 1] = 1
    return jacobian


def velocity_map_derivative(q: ca.SX, actuated_velocity: ca.SX) -> ca.SX:
    """``J̇_nh q̇_u``: the configuration acceleration at ``q̈_u = 0``."""
    jacobian = velocity_map(q)
    velocity = ca.mtimes(jacobian, actuated_velocity)
    return ca.jtimes(velocity, q, velocity)


def least_squares_acceleration(metric: ca.SX, desired: ca.SX, jacobian: ca.SX, jdot_u: ca.SX,
                               steering: Steering | None = None, q: ca.SX | None = None) -> ca.SX:
    """``q̈_u`` minimizing ``‖M (J_nh q̈_u + J̇_nh q̇_u) − M q̈*‖²`` (module docstring),
    plus ``w² ‖C (J_nh q̈_u + J̇_nh q̇_u − q̈*)‖²`` with a look-ahead :class:`Steering`.

    Args:
        metric: the root metric ``M`` (n, n), positive definite.
        desired: the fabric's acceleration ``q̈*`` (n, 1).
        jacobian: ``J_nh`` (n, n_u).
        jdot_u: ``J̇_nh q̇_u`` (n, 1).
        steering: optional look-ahead term; ``None`` is the paper's plain least squares.
        q: the configuration (needed with ``steering``).
    """
    offset = jdot_u - desired
    rows, residual = [ca.mtimes(metric, jacobian)], [ca.mtimes(metric, offset)]
    if steering is not None:
        selector = steering.weight * lookahead_rows(q, steering.lookahead)
        rows.append(ca.mtimes(selector, jacobian))
        residual.append(ca.mtimes(selector, offset))
    weighted, force = ca.vertcat(*rows), ca.vertcat(*residual)
    normal = ca.mtimes(weighted.T, weighted)
    n_u = jacobian.shape[1]
    return -cholesky_solve(normal + TIKHONOV * ca.SX.eye(n_u), ca.mtimes(weighted.T, force))


@dataclass(frozen=True)
class Steering:
    """A look-ahead term of the non-holonomic solve.

    The base cannot accelerate sideways, so the plain least squares drops the lateral
    part of ``q̈*``; a point ``L`` ahead of the axle can move sideways by turning
    (``P̈ = (ẍ, ÿ) + L θ̈ (−sin θ, cos θ) + centripetal terms``). Adding
    ``w² ‖C r‖²`` (``C`` of :func:`lookahead_rows`, ``r`` the residual) asks the base to
    realize that point's desired acceleration too, i.e. to turn toward where the fabric
    wants it to slide: the look-ahead point of unicycle control. A moderate weight ``w``
    leaves the metric-weighted term in charge where the leaves have a strong opinion
    (near obstacles) and breaks the tie where they have none.

    Attributes:
        lookahead: ``L`` [m] ahead of the axle.
        weight: ``w`` [-], compared with the root metric's entries.
    """

    lookahead: float = 0.5
    weight: float = 3.0


def lookahead_rows(q: ca.SX, lookahead: float) -> ca.SX:
    """``C`` (2, n): the look-ahead point's acceleration as rows acting on ``q̈`` (the
    centripetal terms are the same for desired and realized motion and cancel in ``r``)."""
    n = q.shape[0]
    rows = ca.SX(2, n)
    rows[0, 0] = 1
    rows[1, 1] = 1
    rows[0, 2] = -lookahead * ca.sin(q[2])
    rows[1, 2] = lookahead * ca.cos(q[2])
    return rows
