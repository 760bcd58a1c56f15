"""Motion limits of a robot's velocity coordinates: velocity, acceleration, jerk, effort.

The velocity coordinates are the ones a command acts on: the joints of a holonomic robot,
or ``(v, ω, arm joints...)`` for a robot on a differential-drive base. Position limits
stay with the kinematics (``Kinematics.lower`` / ``upper``), which live in configuration
space.

Where the numbers come from:

- a URDF's ``<limit velocity=... effort=...>`` (a velocity of 0, as some shipped URDFs
  write for "unspecified", counts as not given);
- URDF has no acceleration or jerk limits: a joint without published data gets
  :data:`DEFAULT_ACCELERATION` and no jerk limit, and a velocity without data gets
  :data:`DEFAULT_VELOCITY`; a scenario's ``limits:`` block overrides all of them;
- the built-in Panda carries Franka's published limits (:data:`FRANKA_ACCELERATION`,
  :data:`FRANKA_JERK`, the velocities and efforts of its URDF), the built-in Boxer base
  Clearpath's speeds (``BOXER_BASE``) and acceleration limits from its traction
  (:data:`BOXER_ACCELERATION`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

#: velocity limit for a joint whose description gives none [rad/s or m/s]
DEFAULT_VELOCITY = 2.0
#: acceleration limit for a joint without published data (URDF has no such tag)
#: [rad/s² or m/s²]: below what industrial arms reach, above what the fabric needs
DEFAULT_ACCELERATION = 10.0

#: Franka Emika Panda, "Robot and interface specifications" (Franka Control Interface
#: documentation): joint acceleration limits [rad/s²] ...
FRANKA_ACCELERATION = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)
#: ... and jerk limits [rad/s³] (not applied unless a scenario asks: see MotionLimits.jerk)
FRANKA_JERK = (7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0)
#: Clearpath Boxer, acceleration limits ``(v̇ [m/s²], ω̇ [rad/s²])`` from traction: the
#: drive wheels carry 627 of the base's 981 N (the rest rests on the casters), so at
#: friction 1 they push at most 6.3 m/s²; 5 keeps 20 % margin, and 5 rad/s² is where the
#: base stops skidding in yaw under MuJoCo (Experiment 4, seed 33: 1.007x its yaw-rate
#: limit at 10 rad/s², 0.98x at 5). Clearpath's drive controller ships with 2 and 2
#: (boxer_control/config/control.yaml), a conservative setting: with it, the static
#: fabric's bounded command brakes too late in Experiment 4 (seed 3 hits a disc), since
#: the barriers do not know the limit (docs/guides/limits.md). Chosen on Experiment 4 seeds 33
#: (MuJoCo) and 3 (kinematic) of seeds 0-49, the series docs/results.md reports (static
#: fabric under MuJoCo there: 48/50, no contact, worst velocity ratio 0.997); held out,
#: seeds 1000-1049 under MuJoCo: 47/50, no contact, worst velocity ratio 0.976, by ``dynfab
#: experiment exp4 --runs 50 --seed 1000 --planners static-fabric --simulator mujoco``
#: (docs/results.md, "Tuned constants on held-out seeds").
BOXER_ACCELERATION = (5.0, 5.0)


class LimitsError(ValueError):
    """Limits that are not positive and finite, or of the wrong length."""


@dataclass(frozen=True)
class MotionLimits:
    """Symmetric bounds on the velocity coordinates ``u`` of a robot: ``|u̇_i| ≤ velocity_i``,
    ``|ü_i| ≤ acceleration_i``, ``|dü_i/dt| ≤ jerk_i``, ``|τ_i| ≤ effort_i``.

    Attributes:
        names: the velocity coordinates in order (joint names; ``"v"``, ``"omega"`` for a base).
        velocity: maximum speed (m,) [rad/s or m/s].
        acceleration: maximum acceleration (m,) [rad/s² or m/s²].
        jerk: maximum jerk (m,) [rad/s³ or m/s³], or ``None``: not limited.
        effort: maximum torque or force (m,) [N m or N], or ``None`` if unknown (used by
            physics simulation, not by the planner).
    """

    names: tuple[str, ...]
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray | None = None
    effort: np.ndarray | None = None

    def __post_init__(self) -> None:
        m = len(self.names)
        object.__setattr__(self, "names", tuple(self.names))
        for field in ("velocity", "acceleration", "jerk", "effort"):
            value = getattr(self, field)
            if value is None:
                if field in ("velocity", "acceleration"):
                    raise LimitsError(f"limits.{field}: required")
                continue
            array = _positive_finite(field, value, m)
            object.__setattr__(self, field, array)

    @property
    def size(self) -> int:
        """Number of velocity coordinates."""
        return len(self.names)

    def overridden(self, velocity: object = None, acceleration: object = None,
                   jerk: object = None) -> MotionLimits:
        """A copy with the given limits replaced (``None`` keeps the current one)."""
        changes = {name: value for name, value in
                   (("velocity", velocity), ("acceleration", acceleration), ("jerk", jerk)) if value is not None}
        return replace(self, **changes)

    def with_headroom(self, fraction: float) -> MotionLimits:
        """The limits a planner plans with when it keeps ``fraction`` (in [0, 1)) of every
        velocity limit free for tracking error: velocity ``(1 - fraction) × limit``."""
        if not 0.0 <= fraction < 1.0:
            raise LimitsError(f"limits.headroom: must be in [0, 1), got {fraction}")
        return replace(self, velocity=(1.0 - fraction) * self.velocity)

    def velocity_ratio(self, velocities: np.ndarray) -> float:
        """``max_t,i |u̇_i(t)| / velocity_i`` over rows of ``velocities`` (T, m); 0 if empty."""
        return _max_ratio(velocities, self.velocity)

    def acceleration_ratio(self, accelerations: np.ndarray) -> float:
        """``max_t,i |ü_i(t)| / acceleration_i`` over rows of ``accelerations`` (T, m)."""
        return _max_ratio(accelerations, self.acceleration)


def limits_from_joints(names: tuple[str, ...], velocity: np.ndarray, effort: np.ndarray | None = None,
                       acceleration: np.ndarray | None = None) -> MotionLimits:
    """Limits from a description's per-joint data: velocities that are missing (inf) or 0
    become :data:`DEFAULT_VELOCITY`, a missing acceleration :data:`DEFAULT_ACCELERATION`,
    and efforts that are missing or 0 make the effort unknown (``None``)."""
    velocity = np.array(velocity, dtype=float)
    velocity = np.where(np.isfinite(velocity) & (velocity > 0), velocity, DEFAULT_VELOCITY)
    if acceleration is None:
        acceleration = np.full(len(names), DEFAULT_ACCELERATION)
    if effort is not None:
        effort = np.array(effort, dtype=float)
        if not (np.isfinite(effort) & (effort > 0)).all():
            effort = None
    return MotionLimits(tuple(names), velocity, np.array(acceleration, dtype=float), effort=effort)


def _positive_finite(field: str, value: object, size: int) -> np.ndarray:
    try:
        array = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise LimitsError(f"limits.{field}: must be a list of {size} numbers, got {value!r}") from None
    if array.size != size:
        raise LimitsError(f"limits.{field}: must have {size} values (one per velocity coordinate), "
                          f"got {array.size}")
    bad = [i for i, x in enumerate(array) if not (math.isfinite(x) and x > 0)]
    if bad:
        raise LimitsError(f"limits.{field}[{bad[0]}]: must be a positive finite number, got {array[bad[0]]}")
    array.setflags(write=False)
    return array


def _max_ratio(values: np.ndarray, limit: np.ndarray) -> float:
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return 0.0
    return float(np.max(np.abs(values) / limit))
