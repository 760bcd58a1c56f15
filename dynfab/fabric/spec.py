"""Spectral semi-sprays (specs) and their algebra: summation and pullback.

A spec ``(M, f)_X`` on a task space ``X`` is the differential equation
``M(x, ẋ) ẍ + f(x, ẋ) = 0`` (paper section III-C/D). ``M`` is symmetric; ``f`` has units
of ``M`` times acceleration.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from dynfab.fabric.linalg import congruence
from dynfab.fabric.maps import DifferentialMap, Reference


@dataclass(frozen=True)
class Spec:
    """``M(x, ẋ) ẍ + f(x, ẋ) = 0`` expressed in the symbols ``x`` and ``ẋ``.

    Attributes:
        M: symmetric metric (m, m).
        f: force (m, 1).
        x: task position symbols (m, 1).
        xdot: task velocity symbols (m, 1).
    """

    M: ca.SX
    f: ca.SX
    x: ca.SX
    xdot: ca.SX

    def __add__(self, other: Spec) -> Spec:
        """``(M₁, f₁) + (M₂, f₂) = (M₁ + M₂, f₁ + f₂)`` on the same space."""
        _require_same_space(self, other)
        return Spec(self.M + other.M, self.f + other.f, self.x, self.xdot)

    def pull(self, dmap: DifferentialMap) -> Spec:
        """Pullback through ``x = φ(q)``: ``(Jᵀ M J, Jᵀ (f + M J̇ q̇))`` on the domain."""
        M, f = dmap.substitute([self.M, self.f], self.x, self.xdot)
        return Spec(
            congruence(dmap.jacobian, M),
            ca.mtimes(dmap.jacobian.T, f + ca.mtimes(M, dmap.jdot_qdot)),
            dmap.q,
            dmap.qdot,
        )

    def dynamic_pull(self, x: ca.SX, xdot: ca.SX, reference: Reference) -> Spec:
        """Dynamic pullback (paper eq. (dynamic_pull)) of a spec written in relative
        coordinates ``x_rel = x − x̃(t)`` (its symbols ``self.x``, ``self.xdot``) to the fixed
        coordinates ``x``: ``(M, f − M ẍ̃)`` with ``x_rel → x − x̃``, ``ẋ_rel → ẋ − ẋ̃``.
        """
        M, f = ca.substitute([self.M, self.f], [self.x, self.xdot],
                             [x - reference.position, xdot - reference.velocity])
        return Spec(M, f - ca.mtimes(M, reference.acceleration), x, xdot)

    def acceleration(self) -> ca.SX:
        """The motion the spec describes, ``ẍ = −M⁻¹ f``."""
        return -ca.solve(self.M, self.f)

    def forced(self, potential: ca.SX) -> Spec:
        """Forced variant ``(M, f + ∂ψ/∂x)`` by a potential ``ψ(x)``."""
        return Spec(self.M, self.f + ca.gradient(potential, self.x), self.x, self.xdot)


def _require_same_space(a: Spec, b: Spec) -> None:
    if a.x.shape != b.x.shape or not ca.is_equal(a.x, b.x) or not ca.is_equal(a.xdot, b.xdot):
        raise ValueError("specs live on different spaces; pull them to a common space first")
