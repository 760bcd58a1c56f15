"""Lagrangians, Finsler energies, energization and weighted geometries.

Conventions follow the paper (section III-F): a geometry is ``ẍ + h(x, ẋ) = 0``, i.e.
the spec ``(I, h)``; a Lagrangian ``L(x, ẋ)`` gives its spec ``(M_L, f_L)`` through the
Euler-Lagrange equation and conserves the energy ``H = ∂L/∂ẋ · ẋ − L``.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from dynfab.fabric.linalg import congruence
from dynfab.fabric.maps import DifferentialMap, Reference
from dynfab.fabric.spec import Spec


@dataclass(frozen=True)
class Lagrangian:
    """A scalar ``L(x, ẋ)`` in the symbols ``x`` and ``ẋ``."""

    L: ca.SX
    x: ca.SX
    xdot: ca.SX

    def spec(self) -> Spec:
        """Euler-Lagrange: ``M = ∂²L/∂ẋ²``, ``f = ∂²L/∂ẋ∂x · ẋ − ∂L/∂x``."""
        momentum = ca.gradient(self.L, self.xdot)
        M = ca.jacobian(momentum, self.xdot)
        f = ca.mtimes(ca.jacobian(momentum, self.x), self.xdot) - ca.gradient(self.L, self.x)
        return Spec(M, f, self.x, self.xdot)

    def energy(self) -> ca.SX:
        """Hamiltonian ``H = ∂L/∂ẋ · ẋ − L``."""
        return ca.dot(ca.gradient(self.L, self.xdot), self.xdot) - self.L

    def pull(self, dmap: DifferentialMap) -> Lagrangian:
        """``L(φ(q), J q̇)`` in the domain symbols."""
        (pulled,) = dmap.substitute([self.L], self.x, self.xdot)
        return Lagrangian(pulled, dmap.q, dmap.qdot)

    def __add__(self, other: Lagrangian) -> Lagrangian:
        return Lagrangian(self.L + other.L, self.x, self.xdot)

    def dynamic_pull(self, x: ca.SX, xdot: ca.SX, reference: Reference) -> DynamicLagrangian:
        """This Lagrangian, written in relative coordinates ``x_rel = x − x̃(t)``, seen from
        the fixed coordinates ``x`` (see :class:`DynamicLagrangian`)."""
        return DynamicLagrangian(self, x, xdot, reference)


@dataclass(frozen=True)
class DynamicLagrangian:
    """A Lagrangian ``L_d(x_rel, ẋ_rel)`` of relative coordinates ``x_rel = x − x̃(t)``,
    seen from the fixed coordinates ``x``.

    Its spec is NOT the Euler-Lagrange equation of ``L_d(x − x̃, ẋ − ẋ̃)`` with ``x̃``, ``ẋ̃``
    frozen (that misses the reference's acceleration): :meth:`spec` is the relative spec
    pulled dynamically, ``(M, f − M ẍ̃)``, which equals the Euler-Lagrange equation with
    the explicit time dependence of ``x̃(t)`` (paper, "Euler-Lagrange commutes with the
    dynamic pullback"). There is deliberately no ``Lagrangian`` view with frozen
    parameters to call ``spec()`` on.

    Attributes:
        relative: ``L_d`` in its own (relative) symbols.
        x: fixed-frame position symbols.
        xdot: fixed-frame velocity symbols.
        reference: ``x̃``, ``ẋ̃``, ``ẍ̃`` (parameters).
    """

    relative: Lagrangian
    x: ca.SX
    xdot: ca.SX
    reference: Reference

    @property
    def L(self) -> ca.SX:
        """The value ``L_d(x − x̃, ẋ − ẋ̃)`` in the fixed symbols."""
        return self._in_fixed_frame(self.relative.L)

    def energy(self) -> ca.SX:
        """The relative energy ``H_d(x − x̃, ẋ − ẋ̃)``, conserved by dynamic energization."""
        return self._in_fixed_frame(self.relative.energy())

    def spec(self) -> Spec:
        """``(M, f − M ẍ̃)`` of the relative spec, in the fixed symbols."""
        return self.relative.spec().dynamic_pull(self.x, self.xdot, self.reference)

    def _in_fixed_frame(self, expression: ca.SX) -> ca.SX:
        (value,) = ca.substitute([expression], [self.relative.x, self.relative.xdot],
                                 [self.x - self.reference.position, self.xdot - self.reference.velocity])
        return value


def finsler_energy(finsler_structure: ca.SX, x: ca.SX, xdot: ca.SX) -> Lagrangian:
    """Finsler energy ``L_e = ½ F²`` of a Finsler structure ``F`` (positively homogeneous
    of degree 1 in ``ẋ``)."""
    return Lagrangian(0.5 * finsler_structure**2, x, xdot)


def energization_coefficient(M: ca.SX, f_geometry: ca.SX, f_energy: ca.SX, xdot: ca.SX,
                             regularization: float = 1e-9) -> ca.SX:
    """``α`` such that ``ẍ = −M⁻¹ f_geometry + α ẋ`` conserves the energy of the
    Lagrangian whose spec is ``(M, f_energy)``:

    ``α = ẋᵀ (f_geometry − f_energy) / (ẋᵀ M ẋ + ε)``.

    The regularization ``ε`` keeps ``α`` finite at rest (where it multiplies ``ẋ = 0``).
    """
    return ca.dot(xdot, f_geometry - f_energy) / (ca.dot(xdot, ca.mtimes(M, xdot)) + regularization)


def energize(geometry: Spec, lagrangian: Lagrangian, regularization: float = 0.0) -> Spec:
    """Energize ``(I, h)`` with ``L_e``: ``(M_e, f_e + P_e [M_e h − f_e])`` with the projector
    ``P_e = M_e (M_e⁻¹ − ẋ ẋᵀ / (ẋᵀ M_e ẋ))``.

    Args:
        geometry: the spec ``(I, h)`` (its metric must be the identity).
        lagrangian: the energy ``L_e`` on the same space.
        regularization: ε added to ``ẋᵀ M_e ẋ`` (0 for exact theory checks).
    """
    energy_spec = lagrangian.spec()
    M, x, xdot = energy_spec.M, energy_spec.x, energy_spec.xdot
    (h,) = ca.substitute([geometry.f], [geometry.x, geometry.xdot], [x, xdot])
    residual = ca.mtimes(M, h) - energy_spec.f
    M_xdot = ca.mtimes(M, xdot)
    projected = residual - M_xdot * ca.dot(xdot, residual) / (ca.dot(xdot, M_xdot) + regularization)
    return Spec(M, energy_spec.f + projected, x, xdot)


def dynamic_energize(geometry: Spec, lagrangian_spec: Spec, relative_velocity: ca.SX,
                     regularization: float = 0.0) -> Spec:
    """Dynamic energization (paper Proposition "Dynamic Energization").

    Given the geometry ``ẍ + h = 0`` (``h = M_g⁻¹ f_g`` of ``geometry``), the spec
    ``(M, f)`` of a dynamic Lagrangian already pulled dynamically to these coordinates
    (``f = f_de − M ẍ̃``, so that ``M ẍ + f = 0`` conserves ``H_d``) and the relative
    velocity ``v_r`` (``ẋ − ẋ̃``, or ``q̇ − J⁺ ẋ̃`` after a pullback), the system
    ``ẍ + h + α v_r = 0`` with

        α = −(v_rᵀ M v_r)⁻¹ v_rᵀ (M h − f)  [= −(ẋ_rᵀ M ẋ_r)⁻¹ ẋ_rᵀ (M (h + ẍ̃) − f_de)]

    conserves the dynamic energy ``H_d``. Returned as the spec ``(M, M (h + α v_r))``.
    """
    M, f = lagrangian_spec.M, lagrangian_spec.f
    h = -geometry.acceleration()
    (h,) = ca.substitute([h], [geometry.x, geometry.xdot], [lagrangian_spec.x, lagrangian_spec.xdot])
    M_v = ca.mtimes(M, relative_velocity)
    alpha = -ca.dot(relative_velocity, ca.mtimes(M, h) - f) / (ca.dot(relative_velocity, M_v) + regularization)
    return Spec(M, ca.mtimes(M, h) + alpha * M_v, lagrangian_spec.x, lagrangian_spec.xdot)


@dataclass(frozen=True)
class WeightedGeometry:
    """A geometry ``ẍ + h = 0`` weighted by the metric of a Finsler energy ``L_e``
    (Van Wyk et al. 2022): the spec ``(M_e, M_e h)``, carried together with the energy's
    own force ``f_e`` so the root can energize the sum (α of :func:`energization_coefficient`).

    Attributes:
        M: ``M_e`` (m, m).
        f_geometry: ``M_e h`` (m, 1).
        f_energy: ``f_e`` (m, 1).
        x, xdot: task symbols.
    """

    M: ca.SX
    f_geometry: ca.SX
    f_energy: ca.SX
    x: ca.SX
    xdot: ca.SX

    @classmethod
    def from_parts(cls, h: ca.SX, lagrangian: Lagrangian) -> WeightedGeometry:
        """Weight ``h(x, ẋ)`` (in the Lagrangian's symbols) by ``L_e``."""
        spec = lagrangian.spec()
        return cls(spec.M, ca.mtimes(spec.M, h), spec.f, spec.x, spec.xdot)

    def geometry_spec(self) -> Spec:
        return Spec(self.M, self.f_geometry, self.x, self.xdot)

    def energy_spec(self) -> Spec:
        return Spec(self.M, self.f_energy, self.x, self.xdot)

    def pull(self, dmap: DifferentialMap) -> WeightedGeometry:
        """Pull both specs through ``φ``; they share ``M``, so ``Jᵀ M J`` is built once:
        ``(Jᵀ M J, Jᵀ (f_geometry + M J̇ q̇), Jᵀ (f_energy + M J̇ q̇))``."""
        M, f_geometry, f_energy = dmap.substitute(
            [self.M, self.f_geometry, self.f_energy], self.x, self.xdot
        )
        curvature = ca.mtimes(M, dmap.jdot_qdot)
        jacobian_t = dmap.jacobian.T
        return WeightedGeometry(
            congruence(dmap.jacobian, M),
            ca.mtimes(jacobian_t, f_geometry + curvature),
            ca.mtimes(jacobian_t, f_energy + curvature),
            dmap.q,
            dmap.qdot,
        )

    def dynamic_pull(self, x: ca.SX, xdot: ca.SX, reference: Reference) -> WeightedGeometry:
        """Dynamic pullback from relative coordinates ``x − x̃`` to ``x``: both forces lose
        ``M ẍ̃`` (see :meth:`dynfab.fabric.spec.Spec.dynamic_pull`)."""
        M, f_geometry, f_energy = ca.substitute(
            [self.M, self.f_geometry, self.f_energy], [self.x, self.xdot],
            [x - reference.position, xdot - reference.velocity])
        inertial = ca.mtimes(M, reference.acceleration)
        return WeightedGeometry(M, f_geometry - inertial, f_energy - inertial, x, xdot)

    def scaled(self, factor: ca.SX) -> WeightedGeometry:
        """Multiply metric and forces by a scalar (e.g. an activation flag of 0 or 1)."""
        return WeightedGeometry(self.M * factor, self.f_geometry * factor,
                                self.f_energy * factor, self.x, self.xdot)

    def __add__(self, other: WeightedGeometry) -> WeightedGeometry:
        return WeightedGeometry(self.M + other.M, self.f_geometry + other.f_geometry,
                                self.f_energy + other.f_energy, self.x, self.xdot)
