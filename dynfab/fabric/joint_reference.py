"""The primary goal's moving reference seen from joint space (dynamic fabrics).

A task reference ``x̃(t)`` with velocity ``ẋ̃`` and acceleration ``ẍ̃`` is brought to joint
space through the task map ``x = φ(q)`` (Jacobian ``J``, curvature term ``J̇ q̇``):

    q̇̃ = J⁺ ẋ̃,        q̈̃ = J⁺ (ẍ̃ − J̇ q̇),        J⁺ = Jᵀ (J Jᵀ + λ² I)⁻¹.

On the reference (``x = x̃``, ``q̇ = q̇̃``) with ``J J⁺ = I`` these are exact: ``J q̇̃ = ẋ̃`` and
``J q̈̃ + J̇ q̇ = ẍ̃``, so a joint-space energy pulled dynamically with ``(q̇̃, q̈̃)`` asks for
exactly the motion the task reference asks for, and the fabric follows the reference
without bias (``q̈̃`` differs from ``d/dt q̇̃`` only in the null space of ``J``).

The damping ``λ²`` keeps ``J⁺`` finite at singularities, but any ``λ > 0`` breaks
``J J⁺ = I``. So it is switched on only near a singularity (variable damping, as in
Nakamura & Hanafusa 1986): with ``g = det(J Jᵀ)^{1/m}`` (the geometric mean of the squared
singular values [m²]),

    λ² = λ₀² · max(0, 1 − g / (4 λ₀²))²,

zero (an exact pseudo-inverse) while ``g ≥ 4 λ₀²``, rising smoothly to ``λ₀²`` at ``g = 0``.
Tasks of more than 3 rows (orientation goals: stacked unit directions, whose ``J Jᵀ`` is
singular by construction) keep the constant ``λ₀²``.
"""

from __future__ import annotations

import casadi as ca

from dynfab.fabric.linalg import cholesky_solve
from dynfab.fabric.maps import DifferentialMap, Reference


def reference_damping(jacobian: ca.SX, damping: float) -> ca.SX:
    """``λ²`` of the module docstring for ``J`` (m × n) and ``λ₀ = damping`` [m²]."""
    m = jacobian.shape[0]
    if m > 3:
        return ca.SX(damping**2)
    gram = ca.mtimes(jacobian, jacobian.T)
    mean_squared_singular_value = ca.fmax(ca.det(gram), 0) ** (1.0 / m)
    closeness = ca.fmax(0, 1 - mean_squared_singular_value / (4 * damping**2))
    return damping**2 * closeness**2


def joint_reference(task: DifferentialMap, reference: Reference, damping: float) -> tuple[ca.SX, ca.SX]:
    """``(q̇̃, q̈̃)`` of the module docstring [rad/s, rad/s²].

    Args:
        task: the primary goal's task map (its ``phi``, ``jacobian``, ``jdot_qdot``).
        reference: the task reference (``velocity``, ``acceleration`` used).
        damping: ``λ₀`` [m] (or the task's unit).
    """
    jacobian = task.jacobian
    m = jacobian.shape[0]
    gram = ca.mtimes(jacobian, jacobian.T) + reference_damping(jacobian, damping) * ca.SX.eye(m)
    velocity = ca.mtimes(jacobian.T, cholesky_solve(gram, reference.velocity))
    acceleration = ca.mtimes(jacobian.T, cholesky_solve(gram, reference.acceleration - task.jdot_qdot))
    return velocity, acceleration
