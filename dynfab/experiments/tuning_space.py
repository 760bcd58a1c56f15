"""What ``dynfab tune`` searches: parameters of the scenario's ``fabric:`` block
(:mod:`dynfab.scenario.fabric_schema`), each within an interval that contains the
planner's default for every built-in robot.

Values are rounded to :data:`SIGNIFICANT_DIGITS` significant digits before a trial runs,
so the block a trial ran is exactly the block written to the output file.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from dynfab.fabric.planner_config import GoalConfig, PlannerConfig
from dynfab.scenario.fabric_schema import fabric_block
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import scenario_from_dict

SIGNIFICANT_DIGITS = 3


@dataclass(frozen=True)
class Dimension:
    """One searched parameter.

    Attributes:
        key: ``part.name`` in the ``fabric:`` block, e.g. ``obstacle.range``.
        low, high: the interval searched, in the parameter's unit.
        log: sample uniformly in ``log`` (for gains spanning decades).
    """

    key: str
    low: float
    high: float
    log: bool = True

    def __post_init__(self) -> None:
        if not 0 < self.low < self.high:
            raise ValueError(f"Dimension {self.key}: expected 0 < low < high, got {self.low}, {self.high}")


#: The parameters that shape a reaching motion among obstacles: the obstacle barrier
#: (k [-], λ [m²], range [m]), the goal's pull k [m/s²], the speed-control target
#: L_ex* [(rad/s)²], its damping b [1/s] and the extra damping near the goal b_goal [1/s].
SEARCH_SPACE: tuple[Dimension, ...] = (
    Dimension("obstacle.gain", 0.5, 20.0),
    Dimension("obstacle.energy_gain", 0.05, 5.0),
    Dimension("obstacle.range", 0.05, 0.8),
    Dimension("goal.gain", 1.0, 20.0),
    Dimension("speed_control.execution_energy", 0.1, 3.0),
    Dimension("speed_control.damping", 0.1, 3.0),
    Dimension("speed_control.goal_damping", 1.0, 20.0),
)


def rounded(value: float) -> float:
    """``value`` to :data:`SIGNIFICANT_DIGITS` significant digits."""
    return float(f"{value:.{SIGNIFICANT_DIGITS}g}")


def block_of(values: Mapping[str, float]) -> dict[str, dict[str, float]]:
    """The ``fabric:`` block of flat ``{part.name: value}`` values, each rounded."""
    block: dict[str, dict[str, float]] = {}
    for key, value in values.items():
        part, name = key.split(".")
        block.setdefault(part, {})[name] = rounded(value)
    return block


def default_values(scenario: Mapping[str, Any], space: tuple[Dimension, ...] = SEARCH_SPACE) -> dict[str, float]:
    """The planner's defaults of the searched parameters for the robot of ``scenario`` (a
    scenario-file mapping), flat as ``{part.name: value}``.

    Raises:
        ValueError: a default lies outside its interval.
    """
    robot = robot_for(scenario_from_dict(dict(scenario)))
    block = fabric_block(PlannerConfig.for_robot(robot, (GoalConfig(link=robot.goal_link),)))
    values = {}
    for dimension in space:
        part, name = dimension.key.split(".")
        value = block[part][name]
        if not dimension.low <= value <= dimension.high:
            raise ValueError(f"Dimension {dimension.key}: the default {value} lies outside "
                             f"[{dimension.low}, {dimension.high}]")
        values[dimension.key] = value
    return values


def space_description(space: tuple[Dimension, ...] = SEARCH_SPACE) -> list[list[Any]]:
    """The space as plain values (stored with a study, so that a changed space is noticed)."""
    return [[d.key, d.low, d.high, d.log] for d in space]
