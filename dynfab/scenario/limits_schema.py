"""The ``limits:`` block of a scenario: velocity, acceleration and jerk limits that
override the robot's (URDF or built-in) ones, one value per velocity coordinate.

    limits: {velocity: [...], acceleration: [...], jerk: [...], headroom: 0.05}   # any subset

``headroom`` is the fraction of every velocity limit the planner keeps free for tracking
error: it bounds its velocities to ``(1 - headroom) × limit``, while the metrics
(``max_velocity_ratio``) compare with the full limit. A robot that follows its commands
exactly needs none (the default of the kinematic simulator, 0); under physics a controller
tracks with some error (a base skids when the arm swings), so ``simulator: mujoco``
defaults to :data:`PHYSICS_HEADROOM`.

Lengths are checked against the robot when it is built (``robot.limits.names`` gives
the order: joints, or ``v``, ``omega``, arm joints on a differential-drive base).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from dynfab.scenario.model_types import Items, Range, ScenarioModel
from dynfab.scenario.ranges import MAX_ACCELERATION, MAX_JERK, MAX_SPEED

#: Default ``headroom`` under ``simulator: mujoco`` (the kinematic simulator's is 0).
PHYSICS_HEADROOM = 0.05
#: Largest ``headroom``: the planner keeps at least half of every velocity limit.
MAX_HEADROOM = 0.5

@dataclass(frozen=True)
class LimitsSpec:
    """Overrides of the robot's limits; ``None`` keeps the robot's.

    Attributes:
        velocity: [rad/s or m/s] per velocity coordinate.
        acceleration: [rad/s² or m/s²].
        jerk: [rad/s³ or m/s³]; giving it turns the jerk bound on.
        headroom: fraction of the velocity limits the planner leaves free (module doc);
            ``None``: 0, or :data:`PHYSICS_HEADROOM` under MuJoCo.
    """

    velocity: tuple[float, ...] | None = None
    acceleration: tuple[float, ...] | None = None
    jerk: tuple[float, ...] | None = None
    headroom: float | None = None

    def headroom_for(self, simulator: str) -> float:
        """The headroom in use under ``simulator`` (``kinematic`` or ``mujoco``)."""
        if self.headroom is not None:
            return self.headroom
        return PHYSICS_HEADROOM if simulator == "mujoco" else 0.0


class LimitsMapping(ScenarioModel):
    """``limits: {velocity: [...], acceleration: [...], jerk: [...]}``, each a list of
    positive numbers, one per velocity coordinate."""

    velocity: Annotated[tuple[Annotated[float, Range(0.0, MAX_SPEED, open_lower=True)], ...],
                        Items(max_items=64)] | None = None
    acceleration: Annotated[tuple[Annotated[float, Range(0.0, MAX_ACCELERATION, open_lower=True)], ...],
                            Items(max_items=64)] | None = None
    jerk: Annotated[tuple[Annotated[float, Range(0.0, MAX_JERK, open_lower=True)], ...],
                    Items(max_items=64)] | None = None
    headroom: Annotated[float, Range(0.0, MAX_HEADROOM)] | None = None

    def spec(self) -> LimitsSpec:
        """The limits value."""
        return LimitsSpec(self.velocity, self.acceleration, self.jerk, self.headroom)
