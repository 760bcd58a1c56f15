"""Motion models of the embedded simulator: how a commanded acceleration moves the robot.

A model advances ``(q, u)`` over a sub-step of length ``h`` [s] with the commanded
acceleration ``u̇`` held constant, where ``u`` are the robot's velocity coordinates:
the joint velocities ``q̇`` of a holonomic robot, or ``(v, ω, arm rates)`` of a robot on a
differential-drive base.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

Vector = NDArray[np.float64]


class MotionModel(Protocol):
    """Integrates one sub-step."""

    def velocity_size(self, configuration_size: int) -> int:
        """Number of velocity coordinates for a configuration of the given size."""

    def step(self, q: Vector, velocity: Vector, acceleration: Vector, h: float) -> tuple[Vector, Vector]:
        """``(q, u)`` after ``h`` seconds of constant ``u̇``."""


@dataclass(frozen=True)
class DoubleIntegrator:
    """Holonomic joints, exact for a constant acceleration:
    ``q ← q + q̇ h + ½ q̈ h²``, ``q̇ ← q̇ + q̈ h``."""

    def velocity_size(self, configuration_size: int) -> int:
        return configuration_size

    def step(self, q: Vector, velocity: Vector, acceleration: Vector, h: float) -> tuple[Vector, Vector]:
        return q + velocity * h + 0.5 * acceleration * h * h, velocity + acceleration * h


@dataclass(frozen=True)
class DifferentialDrive:
    """A unicycle base ``q = (x, y, θ, arm...)``, ``u = (v, ω, arm rates...)``.

    The base moves along a circular arc with the sub-step's mid-point speeds
    ``v̄ = v + ½ v̇ h``, ``ω̄ = ω + ½ ω̇ h`` (exact unicycle motion for constant ``v̄``, ``ω̄``):

        Δ = ω̄ h,   θ' = θ + Δ,
        (x', y') = (x, y) + v̄ h · sinc(Δ/2) · (cos(θ + Δ/2), sin(θ + Δ/2)),

    (``sinc(a) = sin(a)/a``; this equals ``x + v̄ (sin θ' − sin θ)/ω̄`` without its
    cancellation at small ``ω̄``), so the displacement is the chord of an arc tangent to
    the heading: the base never slides sideways. The heading change ``ω̄ h`` is exact for constant ``ω̇``;
    arm joints are exact double integrators.
    """

    def velocity_size(self, configuration_size: int) -> int:
        return configuration_size - 1

    def step(self, q: Vector, velocity: Vector, acceleration: Vector, h: float) -> tuple[Vector, Vector]:
        v, omega = velocity[:2] + 0.5 * acceleration[:2] * h
        x, y, heading = q[:3]
        turn = omega * h
        middle = heading + 0.5 * turn
        chord = v * h * np.sinc(turn / (2 * np.pi))
        position = (x + chord * np.cos(middle), y + chord * np.sin(middle), heading + turn)
        arm = q[3:] + velocity[2:] * h + 0.5 * acceleration[2:] * h * h
        return np.concatenate([position, arm]), velocity + acceleration * h


def motion_model_for(on_base: bool) -> MotionModel:
    """The model of a robot: :class:`DifferentialDrive` if it stands on a
    differential-drive base, else :class:`DoubleIntegrator`."""
    return DifferentialDrive() if on_base else DoubleIntegrator()
