"""Joint values of a scenario (the start ``q``, joint goals) inside the robot's limits."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from dynfab.scenario.fields import ScenarioError

if TYPE_CHECKING:
    from dynfab.robots.robot import Robot

__all__ = ["JOINT_LIMIT_TOLERANCE", "check_within_limits", "clipped_to_limits"]

#: A value this far beyond a limit counts as at the limit (a value rounded when written,
#: such as MotionBenchMaker's joint values) [rad or m].
JOINT_LIMIT_TOLERANCE = 1e-6


def check_within_limits(values: Sequence[float], robot: Robot, field: str) -> None:
    """Raise unless ``lower_i - JOINT_LIMIT_TOLERANCE <= values[i] <= upper_i + ...`` for every joint.

    Raises:
        ScenarioError: ``initial_state.q[3] (elbow_joint): 3.5 is outside [-3.14159, 3.14159]``.
    """
    kinematics = robot.kinematics
    for i, value in enumerate(values):
        lower, upper = kinematics.lower[i], kinematics.upper[i]
        if not lower - JOINT_LIMIT_TOLERANCE <= value <= upper + JOINT_LIMIT_TOLERANCE:
            raise ScenarioError(f"{field}[{i}] ({kinematics.joint_names[i]})",
                                f"{value:.6g} is outside [{lower:.6g}, {upper:.6g}]")


def clipped_to_limits(values: Sequence[float], robot: Robot) -> tuple[float, ...]:
    """``values`` (checked by :func:`check_within_limits`) with those just beyond a limit set to it."""
    kinematics = robot.kinematics
    return tuple(min(max(float(value), float(kinematics.lower[i])), float(kinematics.upper[i]))
                 for i, value in enumerate(values))
