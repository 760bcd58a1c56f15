"""The reference a guided fabric follows while its plan is made: a straight joint-space
motion from where the robot was to the goal configuration, at rest at both ends, with the
fastest trapezoidal (or triangular) speed profile within per-joint limits.

With ``L = ‖g − q₀‖``, ``u = (g − q₀)/L`` and the path limits ``v = minᵢ vᵢ/|uᵢ|``,
``a = minᵢ aᵢ/|uᵢ|`` (so every joint keeps ``|q̇ᵢ| ≤ vᵢ``, ``|q̈ᵢ| ≤ aᵢ``), the path
coordinate ``s(t)`` accelerates at ``a`` to ``v_p = min(v, √(a L))``, cruises, and brakes
at ``a`` to rest at ``s = L``:

    q(t) = q₀ + s(t) u,   q̇(t) = ṡ(t) u,   q̈(t) = s̈(t) u.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.trajectories import Samples, Trajectory, derived_field

__all__ = ["StraightMotion"]


@dataclass(frozen=True)
class StraightMotion(Trajectory):
    """A straight joint-space motion from rest to rest (module docstring).

    Attributes:
        start: ``q₀`` (n,) [rad].
        goal: ``g`` (n,) [rad].
        velocity: per-joint speed limits ``vᵢ`` (n,) [rad/s], > 0.
        acceleration: per-joint acceleration limits ``aᵢ`` (n,) [rad/s²], > 0.
        duration: time from ``q₀`` to rest at ``g`` [s].
    """

    start: NDArray[np.float64]
    goal: NDArray[np.float64]
    velocity: NDArray[np.float64]
    acceleration: NDArray[np.float64]
    duration: float = derived_field()
    _direction: NDArray[np.float64] = derived_field()
    _profile: tuple[float, float, float, float] = derived_field()

    def __post_init__(self) -> None:
        for name in ("velocity", "acceleration"):
            values = np.asarray(getattr(self, name), dtype=float)
            if values.shape != np.shape(self.start) or not np.all(values > 0.0):
                raise ValueError(f"StraightMotion.{name} must hold one limit > 0 per joint")
        offset = np.asarray(self.goal, dtype=float) - np.asarray(self.start, dtype=float)
        length = float(np.linalg.norm(offset))
        direction = offset / length if length > 0.0 else np.zeros_like(offset)
        moving = np.abs(direction) > 0.0
        speed = float(np.min(np.asarray(self.velocity)[moving] / np.abs(direction[moving]))) if length else 1.0
        push = float(np.min(np.asarray(self.acceleration)[moving] / np.abs(direction[moving]))) if length else 1.0
        peak = min(speed, float(np.sqrt(push * length)))
        ramp = peak / push
        cruise = (length - peak * ramp) / peak if peak > 0.0 else 0.0
        object.__setattr__(self, "_direction", direction)
        object.__setattr__(self, "_profile", (peak, push, ramp, max(0.0, cruise)))
        object.__setattr__(self, "duration", 2.0 * ramp + max(0.0, cruise))

    @property
    def dimension(self) -> int:
        return int(np.size(self.start))

    def _sample(self, times: np.ndarray) -> Samples:
        peak, push, ramp, cruise = self._profile
        t = np.clip(times, 0.0, self.duration)
        braking = np.maximum(0.0, t - ramp - cruise)
        rising = np.minimum(t, ramp)
        s = 0.5 * push * rising**2 + peak * np.clip(t - ramp, 0.0, cruise) + peak * braking - 0.5 * push * braking**2
        s_dot = push * rising - push * braking
        s_ddot = np.where(t < ramp, push, np.where(t > ramp + cruise, -push, 0.0))
        s_ddot = np.where((times < 0.0) | (times >= self.duration), 0.0, s_ddot)
        u = self._direction
        return (np.asarray(self.start, dtype=float) + s[:, None] * u, s_dot[:, None] * u, s_ddot[:, None] * u)
