"""Differential maps ``x = φ(q)`` between task spaces, with ``J`` and ``J̇ q̇``.

A map carries its domain's position and velocity symbols so that anything expressed in
the codomain's variables can be pulled back by substitution (``x → φ(q)``,
``ẋ → J q̇``). Maps are usually derived symbolically from ``φ``; a map may also supply a
closed form of ``J`` and ``J̇ q̇`` (the sphere distance below), which tests check against
finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca


@dataclass(frozen=True)
class DifferentialMap:
    """``x = φ(q)`` with ``ẋ = J q̇`` and ``ẍ = J q̈ + J̇ q̇``.

    Attributes:
        phi: ``φ(q)`` of shape (m, 1), an expression in ``q``.
        jacobian: ``J = ∂φ/∂q`` of shape (m, n).
        jdot_qdot: ``J̇ q̇`` of shape (m, 1), an expression in ``q`` and ``q̇``.
        q: domain position symbols (n, 1).
        qdot: domain velocity symbols (n, 1).
    """

    phi: ca.SX
    jacobian: ca.SX
    jdot_qdot: ca.SX
    q: ca.SX
    qdot: ca.SX

    @classmethod
    def from_expression(cls, phi: ca.SX, q: ca.SX, qdot: ca.SX) -> DifferentialMap:
        """Derive ``J = ∂φ/∂q`` and ``J̇ q̇ = ∂(J q̇)/∂q · q̇`` by automatic differentiation."""
        phi = ca.SX(phi)
        jacobian = ca.jacobian(phi, q)
        jdot_qdot = ca.jtimes(ca.mtimes(jacobian, qdot), q, qdot)
        return cls(phi, jacobian, jdot_qdot, q, qdot)

    @property
    def velocity(self) -> ca.SX:
        """``ẋ = J q̇``."""
        return ca.mtimes(self.jacobian, self.qdot)

    def substitute(self, expressions: list[ca.SX], x: ca.SX, xdot: ca.SX) -> list[ca.SX]:
        """Express codomain functions ``g(x, ẋ)`` in the domain: ``g(φ(q), J q̇)``."""
        return ca.substitute(expressions, [x, xdot], [ca.densify(self.phi), ca.densify(self.velocity)])

    def after(self, inner: DifferentialMap) -> DifferentialMap:
        """Composition ``self ∘ inner``: ``q → inner → self``.

        ``J = J_o J_i`` and ``J̇ q̇ = J_o J̇_i q̇ + (J̇_o ẏ)|_{y = φ_i, ẏ = J_i q̇}``.
        """
        outer_phi, outer_jacobian, outer_jdot = inner.substitute(
            [self.phi, self.jacobian, self.jdot_qdot], self.q, self.qdot
        )
        return DifferentialMap(
            phi=outer_phi,
            jacobian=ca.mtimes(outer_jacobian, inner.jacobian),
            jdot_qdot=ca.mtimes(outer_jacobian, inner.jdot_qdot) + outer_jdot,
            q=inner.q,
            qdot=inner.qdot,
        )


@dataclass(frozen=True)
class Reference:
    """A reference trajectory's state at the current time (paper Definition 1):
    ``x̃(t)``, ``ẋ̃(t)`` and ``ẍ̃(t)``, as CasADi symbols (runtime parameters) or expressions.
    """

    position: ca.SX
    velocity: ca.SX
    acceleration: ca.SX

    @classmethod
    def symbols(cls, name: str, dimension: int) -> Reference:
        """Fresh symbols ``name``, ``name_dot``, ``name_ddot`` of the given dimension."""
        return cls(ca.SX.sym(name, dimension), ca.SX.sym(name + "_dot", dimension),
                   ca.SX.sym(name + "_ddot", dimension))


def sphere_distance_map(
    p: ca.SX, pdot: ca.SX, center: ca.SX, radius: ca.SX, smoothing: float = 1e-3
) -> DifferentialMap:
    """Signed clearance of a point sphere to a sphere: ``x = ‖p − c‖ − r``.

    ``‖p − c‖`` is smoothed as ``d = √(‖p − c‖² + ε²)`` so that ``J = nᵀ`` and the curvature
    term stay finite when the centres coincide. With ``n = (p − c)/d``: ``J = nᵀ`` and
    ``J̇ ṗ = (‖ṗ‖² − (nᵀ ṗ)²)/d`` (the obstacle is at rest in this frame), at most
    ``‖ṗ‖²/ε``. ε = 1 mm bounds that term (an obstacle centre inside a robot sphere gave
    10⁶‖ṗ‖² at ε = 1e-6 m) while overstating a clearance at centre distance ``d`` by only
    ``ε²/2d`` (5 µm at 0.1 m).

    Args:
        p: point position symbols (d, 1), d = 2 or 3 [m].
        pdot: point velocity symbols (d, 1) [m/s].
        center: obstacle centre (d, 1) [m], a parameter.
        radius: sum of both radii [m], a parameter.
        smoothing: ε [m].
    """
    offset = p - center
    distance = ca.sqrt(ca.dot(offset, offset) + smoothing**2)
    normal = offset / distance
    normal_speed = ca.dot(normal, pdot)
    jdot_pdot = (ca.dot(pdot, pdot) - normal_speed**2) / distance
    return DifferentialMap(distance - radius, normal.T, jdot_pdot, p, pdot)


def linear_map(matrix: ca.DM, offset: ca.SX, q: ca.SX, qdot: ca.SX) -> DifferentialMap:
    """``x = A q − b`` with constant ``A``: ``J = A`` and ``J̇ q̇ = 0``.

    Used for joint-space tasks (joint limits, joint goals) where ``A`` selects joints.
    """
    jacobian = ca.SX(ca.DM(matrix))
    return DifferentialMap(ca.mtimes(jacobian, q) - offset, jacobian,
                           ca.SX(jacobian.shape[0], 1), q, qdot)


def selected(dmap: DifferentialMap, rows: list[int], offset: ca.SX) -> DifferentialMap:
    """Rows of a map shifted by a constant: ``x = S φ(q) − b`` (e.g. a goal on axes x, y)."""
    return DifferentialMap(dmap.phi[rows, :] - offset, dmap.jacobian[rows, :],
                           dmap.jdot_qdot[rows, :], dmap.q, dmap.qdot)


def difference(a: DifferentialMap, b: DifferentialMap) -> DifferentialMap:
    """``x = φ_a(q) − φ_b(q)``: ``J = J_a − J_b``, ``J̇ q̇ = J̇_a q̇ − J̇_b q̇``."""
    return DifferentialMap(a.phi - b.phi, a.jacobian - b.jacobian,
                           a.jdot_qdot - b.jdot_qdot, a.q, a.qdot)
