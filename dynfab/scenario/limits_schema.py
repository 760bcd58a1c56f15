"""The ``limits:`` block of a scenario: velocity, acceleration and jerk limits that
override the robot's (URDF or built-in) ones, one value per velocity coordinate.

    limits: {velocity: [...], acceleration: [...], jerk: [...]}   # any subset

Lengths are checked against the robot when it is built (``robot.limits.names`` gives
the order: joints, or ``v``, ``omega``, arm joints on a differential-drive base).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from dynfab.scenario.model_types import Items, Range, ScenarioModel
from dynfab.scenario.ranges import MAX_ACCELERATION, MAX_JERK, MAX_SPEED

@dataclass(frozen=True)
class LimitsSpec:
    """Overrides of the robot's limits; ``None`` keeps the robot's.

    Attributes:
        velocity: [rad/s or m/s] per velocity coordinate.
        acceleration: [rad/s² or m/s²].
        jerk: [rad/s³ or m/s³]; giving it turns the jerk bound on.
    """

    velocity: tuple[float, ...] | None = None
    acceleration: tuple[float, ...] | None = None
    jerk: tuple[float, ...] | None = None


class LimitsMapping(ScenarioModel):
    """``limits: {velocity: [...], acceleration: [...], jerk: [...]}``, each a list of
    positive numbers, one per velocity coordinate."""

    velocity: Annotated[tuple[Annotated[float, Range(0.0, MAX_SPEED, open_lower=True)], ...],
                        Items(max_items=64)] | None = None
    acceleration: Annotated[tuple[Annotated[float, Range(0.0, MAX_ACCELERATION, open_lower=True)], ...],
                            Items(max_items=64)] | None = None
    jerk: Annotated[tuple[Annotated[float, Range(0.0, MAX_JERK, open_lower=True)], ...],
                    Items(max_items=64)] | None = None

    def spec(self) -> LimitsSpec:
        """The limits value."""
        return LimitsSpec(self.velocity, self.acceleration, self.jerk)
