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

import casadi as ca

from dynfab.linalg import cholesky_solve

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


def least_squares_acceleration(metric: ca.SX, desired: ca.SX, jacobian: ca.SX, jdot_u: ca.SX) -> ca.SX:
    """``q̈_u`` minimizing ``‖M (J_nh q̈_u + J̇_nh q̇_u) − M q̈*‖²`` (module docstring).

    Args:
        metric: the root metric ``M`` (n, n), positive definite.
        desired: the fabric's acceleration ``q̈*`` (n, 1).
        jacobian: ``J_nh`` (n, n_u).
        jdot_u: ``J̇_nh q̇_u`` (n, 1).
    """
    weighted = ca.mtimes(metric, jacobian)
    force = ca.mtimes(metric, jdot_u - desired)
    normal = ca.mtimes(weighted.T, weighted)
    n_u = jacobian.shape[1]
    return -cholesky_solve(normal + TIKHONOV * ca.SX.eye(n_u), ca.mtimes(weighted.T, force))
