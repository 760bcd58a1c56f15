"""The ``goal:`` entries of a scenario: position, joint, path, pose and axis goals."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, cast


from dynfab.geometry.orientation import unit_vector
from dynfab.geometry.shapes import ShapeError, quaternion_from_rpy, unit_quaternion
from dynfab.scenario import fields
from dynfab.scenario.fields import ScenarioError


GoalType = Literal["position", "joint", "path", "pose", "axis"]


_GOAL_TYPES: tuple[str, ...] = ("position", "joint", "path", "pose", "axis")


_WORKSPACE_KEYS = ("link", "parent_link", "axes", "tolerance", "weight", "offset")


_POSE_KEYS = ("link", "offset", "orientation", "rpy", "tolerance", "angle_tolerance", "weight")


_AXIS_KEYS = ("link", "angle_tolerance", "weight", "angular_velocity")


#: default ``angle_tolerance`` of pose and axis goals [rad]
DEFAULT_ANGLE_TOLERANCE = 0.1


@dataclass(frozen=True)
class GoalSpec:
    """One weighted sub-goal; the first goal of a scenario is the primary one.

    Attributes:
        type: ``position`` (a workspace point for ``link``), ``joint`` (a configuration),
            ``path`` (``link`` follows the reference ``trajectory``), ``pose`` (a point
            and an orientation for ``link``) or ``axis`` (a link axis along a world
            direction).
        link: Goal link; None means the robot's goal link (see :func:`validate_for_robot`).
            Always None for joint goals.
        position: Target point [m] in the ``parent_link`` frame (one number per axis of
            ``axes`` if given, else x, y for planar robots and x, y, z otherwise), or the
            target configuration for joint goals. None for path goals.
        tolerance: Reached when ||x_link - x_goal|| < tolerance [m] (joint goals: [rad];
            unused by axis goals).
        weight: Relative weight of this goal (> 0).
        parent_link: Frame in which the target is expressed; None is the robot root.
        axes: The workspace axes constrained by the goal, a subset of ``"xyz"``; None: all.
        trajectory: Reference of a path goal, a read-only mapping with a ``type`` among
            :data:`fields.TRAJECTORY_TYPES`; None for the other goal types.
        offset: The goal point on ``link``, in the link frame [m] (a tool centre point);
            position, path and pose goals.
        orientation: Target rotation of ``link`` in the world as a unit quaternion
            ``(w, x, y, z)`` (pose goals; ``rpy`` in the file is converted); else None.
        angle_tolerance: Pose and axis goals: reached when the orientation error is
            below this [rad].
        axis: Axis goals: the unit axis in the link frame; else None.
        direction: Axis goals: the unit world direction the axis should point along at
            t = 0; else None.
        angular_velocity: Axis goals: the direction turns at this angular velocity
            [rad/s] (world frame); None: at rest.
    """

    type: GoalType
    link: str | None = None
    position: tuple[float, ...] | None = None
    tolerance: float = 0.05
    weight: float = 1.0
    parent_link: str | None = None
    axes: str | None = None
    trajectory: Mapping[str, Any] | None = None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    orientation: tuple[float, float, float, float] | None = None
    angle_tolerance: float = DEFAULT_ANGLE_TOLERANCE
    axis: tuple[float, float, float] | None = None
    direction: tuple[float, float, float] | None = None
    angular_velocity: tuple[float, float, float] | None = None


def parse_goal(value: object, field: str) -> GoalSpec:
    """Parse one entry of ``goal``; the allowed keys depend on its ``type``."""
    data = fields.mapping(value, field)
    if "type" not in data:
        raise ScenarioError(f"{field}.type", "missing required key")
    goal_type = cast(GoalType, fields.choice(data["type"], f"{field}.type", _GOAL_TYPES))
    if goal_type == "joint":
        fields.check_keys(data, field, ("type", "position"), ("tolerance", "weight"))
    elif goal_type == "pose":
        return _pose_goal(data, field)
    elif goal_type == "axis":
        return _axis_goal(data, field)
    else:
        target = "position" if goal_type == "position" else "trajectory"
        fields.check_keys(data, field, ("type", target), _WORKSPACE_KEYS)
    axes = _axes(data["axes"], f"{field}.axes") if "axes" in data else None
    position: tuple[float, ...] | None = None
    trajectory: Mapping[str, Any] | None = None
    if goal_type == "joint":
        position = fields.vector(data["position"], f"{field}.position")
    elif goal_type == "position":
        position = _goal_position(data["position"], f"{field}.position", axes)
    else:
        trajectory = fields.trajectory_mapping(data["trajectory"], f"{field}.trajectory")
    return GoalSpec(
        type=goal_type,
        link=fields.optional_text(data, "link", field),
        position=position,
        tolerance=fields.positive(data.get("tolerance", 0.05), f"{field}.tolerance"),
        weight=fields.positive(data.get("weight", 1.0), f"{field}.weight"),
        parent_link=fields.optional_text(data, "parent_link", field),
        axes=axes,
        trajectory=trajectory,
        offset=_offset(data, field),
    )


def _pose_goal(data: Mapping[str, Any], field: str) -> GoalSpec:
    """Parse a ``pose`` goal: a point on the link and a rotation (quaternion or rpy)."""
    fields.check_keys(data, field, ("type", "position"), _POSE_KEYS)
    if ("orientation" in data) == ("rpy" in data):
        raise ScenarioError(field, "expected exactly one of 'orientation' [w, x, y, z] or 'rpy' [roll, pitch, yaw]")
    try:
        if "orientation" in data:
            orientation = unit_quaternion(fields.vector(data["orientation"], f"{field}.orientation", (4,)))
        else:
            orientation = quaternion_from_rpy(fields.vector(data["rpy"], f"{field}.rpy", (3,)))
    except ShapeError as error:
        key = "orientation" if "orientation" in data else "rpy"
        raise ScenarioError(f"{field}.{key}", str(error)) from None
    return GoalSpec(
        type="pose",
        link=fields.optional_text(data, "link", field),
        position=fields.vector(data["position"], f"{field}.position", (3,)),
        tolerance=fields.positive(data.get("tolerance", 0.05), f"{field}.tolerance"),
        weight=fields.positive(data.get("weight", 1.0), f"{field}.weight"),
        offset=_offset(data, field),
        orientation=orientation,
        angle_tolerance=_angle_tolerance(data, field),
    )


def _axis_goal(data: Mapping[str, Any], field: str) -> GoalSpec:
    """Parse an ``axis`` goal: a link axis that should point along a world direction."""
    fields.check_keys(data, field, ("type", "axis", "direction"), _AXIS_KEYS)
    angular_velocity = None
    if "angular_velocity" in data:
        x, y, z = fields.vector(data["angular_velocity"], f"{field}.angular_velocity", (3,))
        angular_velocity = (x, y, z)
    return GoalSpec(
        type="axis",
        link=fields.optional_text(data, "link", field),
        weight=fields.positive(data.get("weight", 1.0), f"{field}.weight"),
        axis=_unit(data["axis"], f"{field}.axis"),
        direction=_unit(data["direction"], f"{field}.direction"),
        angle_tolerance=_angle_tolerance(data, field),
        angular_velocity=angular_velocity,
    )


def _offset(data: Mapping[str, Any], field: str) -> tuple[float, float, float]:
    """``offset``: a point in the link frame [m], the origin if absent."""
    if "offset" not in data:
        return (0.0, 0.0, 0.0)
    x, y, z = fields.vector(data["offset"], f"{field}.offset", (3,))
    return (x, y, z)


def _unit(value: object, field: str) -> tuple[float, float, float]:
    """A non-zero 3-vector, normalised."""
    vector = fields.vector(value, field, (3,))
    try:
        return unit_vector(vector)
    except ValueError:
        raise ScenarioError(field, "expected a non-zero direction, got [0, 0, 0]") from None


def _angle_tolerance(data: Mapping[str, Any], field: str) -> float:
    """``angle_tolerance`` in (0, π] [rad]."""
    tolerance = fields.positive(data.get("angle_tolerance", DEFAULT_ANGLE_TOLERANCE), f"{field}.angle_tolerance")
    if tolerance > math.pi:
        raise ScenarioError(f"{field}.angle_tolerance", f"expected at most pi rad, got {tolerance:g}")
    return tolerance


def _goal_position(value: object, field: str, axes: str | None) -> tuple[float, ...]:
    """Parse a goal point: one number per axis of ``axes``, else 2 or 3 numbers."""
    if axes is None:
        return fields.vector(value, field, (2, 3))
    position = fields.vector(value, field)
    if len(position) != len(axes):
        raise ScenarioError(
            field, f"expected {len(axes)} numbers (one per axis of {axes!r}), got {len(position)}"
        )
    return position


def _axes(value: object, field: str) -> str:
    """Parse ``axes``: distinct letters of ``xyz`` in that order, e.g. ``xy``."""
    axes = fields.text(value, field)
    if axes not in ("x", "y", "z", "xy", "xz", "yz", "xyz"):
        raise ScenarioError(
            field, f"expected distinct axes among x, y, z in that order (e.g. 'xy'), got {axes!r}"
        )
    return axes
