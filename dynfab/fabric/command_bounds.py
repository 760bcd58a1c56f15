"""The last stage of the planner: the fabric's acceleration made executable.

The fabric keeps the robot inside its joint limits with a barrier leaf and its speed near
the speed-control target, but neither bounds the commanded acceleration, and a leaf's
acceleration grows without bound as a clearance closes. This stage takes the fabric's
command ``a`` for the velocity coordinates ``u`` (joints; ``(v, ω, arm...)`` on a base)
and returns a command inside the box ``B = [lo, hi]`` that makes the next state
executable, for a command held over one control period ``Δt``:

- acceleration: ``|ü_i| ≤ A_i``;
- velocity: ``u_i + ü_i Δt ∈ [v_lo,i, v_hi,i]`` with ``v_hi = min(V, v_brake(D_up))``,
  ``v_lo = max(−V, −v_brake(D_low))``;
- position (hard, viable): the next state can still stop before the limit at the maximum
  deceleration ``A``. With ``D_up = q_up − q − u Δt/2`` the room left after this period's
  share of the motion, ``v_brake(D) = −AΔt + √((AΔt)² + 2A max(D, 0))`` is the largest
  next velocity ``v`` whose own half period ``vΔt/2`` plus a stop held period by period
  (at most ``v²/2A + vΔt/2``) fits in ``D``;
- jerk (only where the limits give one): ``|ü_i − ü_prev,i| ≤ J_i Δt``, kept where it
  does not conflict with the bounds above.

``B`` always lies in ``[−A, A]``. It contains 0 for every coordinate whose state is
executable (``v_lo ≤ u ≤ v_hi``), which is every reachable state of a robot started
inside its limits. The command is brought into ``B`` in three steps, each as gentle on the
fabric's behaviour as the bounds allow:

1. **Brake along the path**: ``a₁ = a + γ u`` with the smallest braking ``γ ∈ [−1/Δt, 0]``
   [1/s] that keeps each coordinate's velocity and position bound. Adding a multiple of
   ``u`` changes the speed along the current path, not its direction, so a joint at its
   velocity limit, or running into a position limit, slows the whole motion instead of
   bending it.
2. **Scale uniformly** into the acceleration limits: ``a₂ = s a₁`` with
   ``s = min(1, min_i A_i / |a₁,i|)``. This keeps the command's direction, so the fabric's
   geometry (the path it would trace at a lower speed) is kept; only its magnitude
   shrinks. What is lost is the time-optimality of the leaves: a barrier that wanted to
   stop the robot faster than ``A`` allows stops it as fast as ``A`` allows, so the
   fabric's avoidance guarantees hold only as far as the hard limits let them (the
   position bound above is the hard one for joint limits).
3. **Clip per coordinate** into ``B`` (the only step that changes the direction): it
   acts on a coordinate whose velocity or position bound step 1 could not meet within
   its braking cap, on a joint resting at a position limit that the fabric pushes into
   (that joint stays, the others move on: scaling the whole command to zero would freeze
   the robot), on a coordinate already beyond what can be held (faster than its limit,
   or too fast to stop before a position limit: it brakes as hard as ``A`` allows), and
   on the jerk bound.

A non-finite fabric command stays non-finite here, so that the planner's fallback
catches it.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from dynfab.robots.limits import MotionLimits


@dataclass(frozen=True)
class CommandBounds:
    """Limits of the velocity coordinates and the period the command is held.

    Attributes:
        limits: velocity, acceleration and (optional) jerk limits, per velocity coordinate.
        lower: lower position limit of the configuration variable each velocity coordinate
            moves (m,) [rad or m]; ``-inf`` where there is none (a base's ``v``, ``ω``).
        upper: upper position limit (m,); ``+inf`` where there is none.
        time_step: ``Δt``, the control period over which a command is held [s].
    """

    limits: MotionLimits
    lower: np.ndarray
    upper: np.ndarray
    time_step: float = 0.01

    def __post_init__(self) -> None:
        m = self.limits.size
        for name in ("lower", "upper"):
            array = np.array(getattr(self, name), dtype=float).reshape(-1)
            if array.shape != (m,) or np.isnan(array).any():
                raise ValueError(f"CommandBounds.{name} must be {m} numbers (±inf for none)")
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        if not (np.isfinite(self.time_step) and self.time_step > 0):
            raise ValueError(f"CommandBounds.time_step must be a positive finite number, got {self.time_step}")

    def bounded(self, position: ca.SX, velocity: ca.SX, acceleration: ca.SX,
                previous: ca.SX | None = None) -> ca.SX:
        """The executable command (module docstring), symbolically.

        Args:
            position: the configuration variable of each velocity coordinate (m, 1) (any
                value where there is no position limit) [rad or m].
            velocity: ``u`` (m, 1) [rad/s or m/s].
            acceleration: the fabric's ``a`` (m, 1) [rad/s² or m/s²].
            previous: the previous command (m, 1), needed when the limits give a jerk.
        """
        dt = self.time_step
        limits = self.limits
        jerk = limits.jerk
        if jerk is not None and previous is None:
            raise ValueError("CommandBounds.bounded: a jerk limit needs the previous command")
        lows, highs, motion_lows, motion_highs = [], [], [], []
        for i in range(limits.size):
            v, peak = velocity[i], float(limits.acceleration[i])
            v_high, v_low = ca.SX(float(limits.velocity[i])), ca.SX(-float(limits.velocity[i]))
            if np.isfinite(self.upper[i]):
                v_high = ca.fmin(v_high, _braking_speed(self.upper[i] - position[i] - 0.5 * dt * v, peak, dt))
            if np.isfinite(self.lower[i]):
                v_low = ca.fmax(v_low, -_braking_speed(position[i] - self.lower[i] + 0.5 * dt * v, peak, dt))
            motion_high, motion_low = (v_high - v) / dt, (v_low - v) / dt
            high, low = _clamp(motion_high, -peak, peak), _clamp(motion_low, -peak, peak)
            if jerk is not None:
                step = float(jerk[i]) * dt
                low, high = (ca.fmax(low, ca.fmin(previous[i] - step, high)),
                             ca.fmin(high, ca.fmax(previous[i] + step, low)))
            lows.append(low)
            highs.append(high)
            motion_lows.append(motion_low)
            motion_highs.append(motion_high)
        braking = ca.SX(0)
        for i in range(limits.size):
            a, v = acceleration[i], velocity[i]
            needed = ca.if_else(ca.logic_and(v > 0, a > motion_highs[i]), (motion_highs[i] - a) / v,
                                ca.if_else(ca.logic_and(v < 0, a < motion_lows[i]), (motion_lows[i] - a) / v, 0))
            braking = ca.fmin(braking, needed)
        braking = ca.fmax(braking, -1.0 / dt)
        braked = [acceleration[i] + braking * velocity[i] for i in range(limits.size)]
        scale = ca.SX(1)
        for a, peak in zip(braked, limits.acceleration):
            scale = ca.if_else(ca.fabs(a) > peak, ca.fmin(scale, float(peak) / ca.fabs(a)), scale)
        return ca.vertcat(*[_clamp(scale * a, low, high) for a, low, high in zip(braked, lows, highs)])


def _braking_speed(room: ca.SX, peak: float, dt: float) -> ca.SX:
    """``v_brake(D) = −AΔt + √((AΔt)² + 2A max(D, 0))`` [rad/s or m/s]: the root of
    ``v²/2A + vΔt = D``."""
    step = peak * dt
    return -step + ca.sqrt(step**2 + 2 * peak * ca.fmax(room, 0))


def _clamp(value: ca.SX, low: ca.SX | float, high: ca.SX | float) -> ca.SX:
    """``value`` clipped into ``[low, high]``; a NaN stays NaN (comparisons with it fail)."""
    return ca.if_else(value > high, high, ca.if_else(value < low, low, value))
