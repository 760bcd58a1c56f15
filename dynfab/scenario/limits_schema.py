"""The ``limits:`` block of a scenario: velocity, acceleration and jerk limits that
override the robot's (URDF or built-in) ones, one value per velocity coordinate.

    limits: {velocity: [...], acceleration: [...], jerk: [...]}   # any subset

Lengths are checked against the robot when it is built (``robot.limits.names`` gives
the order: joints, or ``v``, ``omega``, arm joints on a differential-drive base).
"""

from __future__ import annotations

from dataclasses import dataclass

from dynfab.scenario import fields
from dynfab.scenario.fields import ScenarioError

LIMIT_KINDS: tuple[str, ...] = ("velocity", "acceleration", "jerk")


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


def parse_limits(value: object, field: str) -> LimitsSpec:
    """Validate a ``limits:`` mapping: every value a list of positive finite numbers."""
    block = fields.mapping(value, field)
    fields.check_keys(block, field, required=(), optional=LIMIT_KINDS)
    parsed = {}
    for kind in LIMIT_KINDS:
        if kind not in block:
            continue
        items = fields.sequence(block[kind], f"{field}.{kind}")
        if not items:
            raise ScenarioError(f"{field}.{kind}", "expected numbers, got an empty list")
        parsed[kind] = tuple(fields.positive(item, f"{field}.{kind}[{i}]") for i, item in enumerate(items))
    return LimitsSpec(**parsed)
