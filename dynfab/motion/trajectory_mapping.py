"""Trajectories from a scenario's ``trajectory:`` mapping (docs/design.md section 5.2)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from dynfab.describe import describe
from dynfab.motion.spline_trajectory import SplineTrajectory
from dynfab.motion.trajectories import (
    CircleTrajectory,
    ExpressionTrajectory,
    LinearTrajectory,
    PolynomialTrajectory,
    Trajectory,
)
from dynfab.motion.trajectory_values import TrajectoryError

__all__ = ["trajectory_from_mapping"]


_KINDS: dict[str, tuple[type[Trajectory], tuple[str, ...], tuple[str, ...]]] = {
    "linear": (LinearTrajectory, ("start", "velocity"), ()),
    "circle": (CircleTrajectory, ("center", "radius", "angular_velocity"), ("normal", "phase")),
    "polynomial": (PolynomialTrajectory, ("coefficients",), ()),
    "expression": (ExpressionTrajectory, ("x",), ()),
    "spline": (SplineTrajectory, ("waypoints", "duration"), ()),
}
"""Per ``type``: the class, its required and its optional mapping keys."""

_ARGUMENTS: dict[str, str] = {"x": "expressions"}
"""Mapping keys whose constructor argument has another name."""


def trajectory_from_mapping(data: Mapping[str, Any], field: str) -> Trajectory:
    """Build a trajectory from a scenario's ``trajectory:`` mapping (docs/design.md section 5.2).

    - ``{type: linear, start: P, velocity: V}``: :class:`LinearTrajectory`;
    - ``{type: circle, center: C, radius: R, angular_velocity: W, normal: N, phase: A}``
      (``normal`` and ``phase`` optional): :class:`CircleTrajectory`;
    - ``{type: polynomial, coefficients: [[cx0, cx1, ...], [cy0, ...], ...]}``, one list
      per axis, lowest order first: :class:`PolynomialTrajectory`;
    - ``{type: expression, x: ["0.5 + 0.1*sin(0.5*t)", "...", "..."]}``:
      :class:`ExpressionTrajectory`;
    - ``{type: spline, waypoints: [P0, P1, ...], duration: T}``: :class:`SplineTrajectory`.

    ``rrt`` needs the scenario's obstacles and is rejected here: the caller plans the path
    and builds a spline.

    Args:
        data: The mapping, as read from YAML (lists or tuples for sequences).
        field: Field path of the mapping, prefixed to error messages, e.g.
            ``obstacles[1].trajectory``.

    Raises:
        TrajectoryError: Not a mapping, unknown or missing keys, unknown ``type``, or any
            invalid value; the message starts with the full field path, e.g.
            ``obstacles[1].trajectory.velocity: expected 3 numbers, got 2``.
    """
    if not isinstance(data, Mapping):
        raise TrajectoryError(field, f"expected a mapping, got {describe(data)}")
    kind = data.get("type")
    if kind == "rrt":
        problem = "rrt must be resolved by the caller (it plans around the scenario's obstacles)"
        raise TrajectoryError(_join(field, "type"), problem)
    if "type" not in data:
        raise TrajectoryError(_join(field, "type"), "missing required key")
    if not isinstance(kind, str) or kind not in _KINDS:
        problem = f"expected one of {', '.join(_KINDS)}, rrt; got {describe(kind)}"
        raise TrajectoryError(_join(field, "type"), problem)
    cls, required, optional = _KINDS[kind]
    allowed = ("type", *required, *optional)
    for key in data:
        if key not in allowed:
            problem = f"unknown key (allowed: {', '.join(allowed)})"
            raise TrajectoryError(_join(field, str(key)), problem)
    for key in required:
        if key not in data:
            raise TrajectoryError(_join(field, key), "missing required key")
    arguments = {_ARGUMENTS.get(key, key): value for key, value in data.items() if key != "type"}
    try:
        return cls(**arguments)
    except TrajectoryError as error:
        raise TrajectoryError(_join(field, _mapping_path(error.field)), error.problem) from None


def _mapping_path(argument_path: str) -> str:
    """Rename the constructor argument at the root of a field path to its mapping key."""
    keys = {argument: key for key, argument in _ARGUMENTS.items()}
    root = argument_path.split("[", 1)[0]
    return keys.get(root, root) + argument_path[len(root) :]


def _join(field: str, key: str) -> str:
    """Field path of ``key`` inside ``field`` (an empty ``field`` is the top level)."""
    return f"{field}.{key}" if field else key
