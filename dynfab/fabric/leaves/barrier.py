"""The 1-D barrier shared by every avoidance leaf (obstacles, joint limits, self-collision).

The task variable is a clearance ``x`` [m or rad] that must stay positive. Following
Ratliff et al. 2020 and Van Wyk et al. 2022 the leaf is a geometry weighted by a Finsler
energy:

- geometry ``ẍ + h = 0`` with ``h = −k ẋ² / x`` (homogeneous of degree 2 in ``ẋ``): an
  approaching motion decelerates like ``ẋ ∝ x^k`` and never reaches ``x = 0``;
- energy ``L_e = λ (1 − H(ẋ)) ẋ² (1/x − 1/r)₊²`` with the Heaviside gate ``H`` and a range
  ``r``: the leaf has metric ``M_e = 2λ (1 − H(ẋ)) (1/x − 1/r)₊²`` only while the clearance
  shrinks and is below ``r``; it grows like ``2λ/x²`` near contact and vanishes (with its
  derivative) at ``x = r``, so far-away obstacles do not dilute the other leaves' metrics.

``x`` is clamped below at ``min_clearance`` so metric and forces stay finite when a sphere
overlaps the robot (the leaf then pushes as hard as its clamp allows).

With an ``offset`` ``δ`` the leaf acts on ``x − δ`` in place of ``x``: it keeps ``δ`` of the
clearance as a buffer (collision spheres that leave up to ``δ`` of a robot's meshes outside
them then keep the meshes clear).

**Braking** (optional, off by default): with a deceleration ``a_b`` the leaf's energy acts on
the clearance left once the robot has braked, ``x_b = x − δ − min(ẋ, 0)² / (2 a_b)`` (the
stopping distance at ``a_b`` taken off while the clearance shrinks):
``L_e = λ (1 − H(ẋ)) ẋ² (1/x_b − 1/r)₊²``. The default barrier's metric outweighs the
other leaves only within a few cm of contact, where the deceleration it then asks exceeds
the joints' acceleration limits; the planner's last stage
(:mod:`dynfab.fabric.command_bounds`) scales the command into them and a fast approach
brakes too late. On ``x_b`` the metric grows as soon as a stop at ``a_b`` barely fits,
``x_b`` stays constant along a stop at exactly ``a_b`` (``ẋ_b = ẋ (1 − ẍ/a_b)``), and the
clamp at ``min_clearance`` (the leaf's largest weight) is reached when it no longer fits.
What it keeps and gives up:

- the geometry ``h = −k ẋ²/(x − δ)`` is the paper's, homogeneous of degree 2 in ``ẋ``: the
  paths the leaf asks for do not depend on the speed, only how strongly it asks;
- the energy is no longer homogeneous of degree 2 in ``ẋ`` (``x_b`` depends on the speed),
  so it is not a Finsler energy: its spec is the Euler-Lagrange one with the stopping
  distance held fixed, then evaluated at the current ``ẋ`` (the metric stays positive
  semi-definite and the root energizes with it, ``α_le``, but the sum of the leaves'
  energies is conserved only while the stopping distance does not change). Moving away
  (``ẋ ≥ 0``) the leaf is the paper's.

Tried and not kept (docs/results.md, "kitchen and table_bars (issue 20)"): ``x_b`` in the
geometry as well, where the saturated leaf throws the motion sideways (energization keeps
the joint speed and turns it), and in the geometry alone, whose head-on stop the
energization undoes.

Without braking the leaf is the paper's.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca

from dynfab.fabric.energy import Lagrangian, WeightedGeometry

#: ``h(x, ẋ)`` of a geometry ``ẍ + h = 0`` on a 1-D clearance.
GeometryFunction = Callable[[ca.SX, ca.SX], ca.SX]
#: A Lagrangian ``L_e(x, ẋ)`` on a 1-D clearance.
EnergyFunction = Callable[[ca.SX, ca.SX], ca.SX]


@dataclass(frozen=True)
class Barrier:
    """Geometry and energy of a clearance leaf (a Finsler energy unless it brakes).

    Attributes:
        geometry_gain: ``k`` in ``h = −k ẋ²/x`` [-].
        energy_gain: ``λ`` in ``L_e = λ (1 − H(ẋ)) ẋ² (1/x − 1/r)₊²`` [m²].
        horizon: the range ``r`` beyond which the leaf is inactive [m or rad].
        min_clearance: clamp of ``x`` used inside ``h`` and ``L_e`` [m or rad].
        offset: ``δ``, the clearance kept as a buffer: the leaf acts on ``x − δ`` [m or rad].
        geometry: optional replacement ``h(x, ẋ)``; receives the clamped ``x``.
        energy: optional replacement ``L_e(x, ẋ)``; receives the clamped ``x`` (``x_b``
            with braking, its stopping distance held fixed).
        braking: ``a_b`` [m/s² or rad/s²], the deceleration whose stopping distance the
            leaf's energy takes off an approaching clearance (module docstring); None: none.
    """

    geometry_gain: float = 0.5
    energy_gain: float = 0.1
    horizon: float = 0.3
    min_clearance: float = 1e-3
    offset: float = 0.0
    geometry: GeometryFunction | None = None
    energy: EnergyFunction | None = None
    braking: float | None = None

    def __post_init__(self) -> None:
        if self.min_clearance <= 0:
            raise ValueError(f"Barrier.min_clearance must be > 0, got {self.min_clearance}")
        if self.energy_gain < 0 or self.geometry_gain < 0:
            raise ValueError("Barrier gains must be >= 0")
        if self.horizon <= self.min_clearance:
            raise ValueError(f"Barrier.horizon must exceed min_clearance, got {self.horizon}")
        if self.braking is not None and not (math.isfinite(self.braking) and self.braking > 0):
            raise ValueError(f"Barrier.braking must be a positive finite deceleration or None, got {self.braking}")

    def stopping_distance(self, xdot: ca.SX) -> ca.SX:
        """``min(ẋ, 0)² / (2 a_b)`` [m or rad], the distance a stop at ``a_b`` takes (0
        without braking or while the clearance grows)."""
        if self.braking is None:
            return ca.SX(0)
        return ca.fmin(xdot, 0) ** 2 / (2 * self.braking)

    def weighted_geometry(self) -> WeightedGeometry:
        """The leaf ``(M_e, M_e h)`` with ``f_e`` in fresh 1-D symbols ``x``, ``ẋ``.

        A user energy goes through the Euler-Lagrange equation (:class:`Lagrangian`);
        the default energy's spec is written out in closed form (the same result, checked
        in the tests, in half the instructions: this leaf is evaluated for every robot
        sphere and obstacle slot): with ``u = (1/x − 1/r)₊`` and ``s = 1 − H(ẋ)``,
        ``M_e = 2λ u² s`` and ``f_e = ∂L_e/∂x``-terms ``= −2λ u s ẋ² / x²``; with braking ``M_e``
        and ``f_e`` take ``x_b`` for ``x`` (the stopping distance held fixed in the
        derivatives), ``h`` keeps ``x``.
        """
        x = ca.SX.sym("x", 1)
        xdot = ca.SX.sym("xdot", 1)
        stopping = self.stopping_distance(xdot)
        geometry = self.geometry or _default_geometry(self.geometry_gain)
        h = geometry(ca.fmax(x - self.offset, self.min_clearance), xdot)
        if self.energy is not None:
            held = ca.SX.sym("stopping", 1)
            spec = self.lagrangian(held).spec()
            M, f_energy = ca.substitute([spec.M, spec.f], [spec.x, spec.xdot, held], [x, xdot, stopping])
            return WeightedGeometry(M, ca.mtimes(M, h), f_energy, x, xdot)
        clearance = ca.fmax(x - self.offset - stopping, self.min_clearance)
        inverse = 1 / clearance
        reach = ca.fmax(0, inverse - 1 / self.horizon)
        gate = 1 - ca.heaviside(xdot)
        metric = 2 * self.energy_gain * reach**2 * gate
        unclamped = x - self.offset - stopping > self.min_clearance
        f_energy = -2 * self.energy_gain * reach * gate * xdot**2 * inverse**2 * unclamped
        return WeightedGeometry(metric, metric * h, f_energy, x, xdot)

    def lagrangian(self, stopping: ca.SX | float = 0.0) -> Lagrangian:
        """The energy ``L_e(x, ẋ)`` (default or user-given) in fresh 1-D symbols, on the
        clearance ``x − δ − stopping``: ``stopping`` is a stopping distance held fixed (a
        number, or a symbol other than ``x``, ``ẋ``) [m or rad]."""
        x = ca.SX.sym("x", 1)
        xdot = ca.SX.sym("xdot", 1)
        energy = self.energy or _default_energy(self.energy_gain, self.horizon)
        return Lagrangian(energy(ca.fmax(x - self.offset - stopping, self.min_clearance), xdot), x, xdot)


def _default_geometry(gain: float) -> GeometryFunction:
    return lambda x, xdot: -gain / x * xdot**2


def _default_energy(gain: float, horizon: float) -> EnergyFunction:
    return lambda x, xdot: gain * ca.fmax(0, 1 / x - 1 / horizon) ** 2 * (1 - ca.heaviside(xdot)) * xdot**2
