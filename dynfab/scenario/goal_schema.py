"""The ``goal:`` entries of a scenario: position, joint, path, pose and axis goals."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any, Literal

from pydantic import model_validator

from dynfab.geometry.orientation import unit_vector
from dynfab.geometry.shapes import ShapeError, quaternion_from_rpy, unit_quaternion
from dynfab.scenario.model_errors import tagged_union
from dynfab.scenario.model_types import Choice, Flag, Items, Range, ScenarioModel, Text, fail
from dynfab.scenario.ranges import (
    MAX_JOINT_VALUE,
    MAX_LENGTH,
    AngularVelocity,
    Coordinate,
    Point3,
    Tolerance,
    Weight,
)
from dynfab.scenario.trajectory_schema import TrajectoryMapping, frozen_trajectory

__all__ = ["DEFAULT_ANGLE_TOLERANCE", "ENDING_PATHS", "GoalMapping", "GoalSpec", "GoalType", "goal_spec"]

GoalType = Literal["position", "joint", "path", "pose", "axis"]


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
        guided_end: Path goals: whether guidance plans to the path's end once its time is
            over (scenario/path_end.py); None: wherever it can (a path of a type in
            :data:`ENDING_PATHS`, guidance on); True: required (refused where it cannot);
            False: the fabric alone ends the path.
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
    guided_end: bool | None = None


#: The ``trajectory:`` types of a path goal that come to rest at a known time and point:
#: the ends that guidance can plan to (scenario/path_end.py).
ENDING_PATHS = ("spline", "rrt")


Link = Annotated[str, Text()]
Axes = Annotated[str, Choice(("x", "y", "z", "xy", "xz", "yz", "xyz"),
                             "expected distinct axes among x, y, z in that order (e.g. 'xy')")]
#: A point on the goal link, in the link frame [m].
Offset = Annotated[tuple[Annotated[float, Range(-MAX_LENGTH, MAX_LENGTH, unit=" m")], ...], Items((3,))]
AngleTolerance = Annotated[float, Range(0.0, math.pi, open_lower=True, unit=" rad")]
Angles = Annotated[float, Range(-1e3, 1e3)]


class PositionGoalMapping(ScenarioModel):
    """``{type: position, position: P [m], link, parent_link, axes, tolerance [m], weight, offset [m]}``."""

    type: Literal["position"]
    position: Annotated[tuple[Coordinate, ...], Items()]
    link: Link | None = None
    parent_link: Link | None = None
    axes: Axes | None = None
    tolerance: Tolerance = 0.05
    weight: Weight = 1.0
    offset: Offset = (0.0, 0.0, 0.0)

    @model_validator(mode="after")
    def _one_number_per_axis(self) -> PositionGoalMapping:
        if self.axes is None and len(self.position) not in (2, 3):
            raise fail(f"expected 2 or 3 numbers, got {len(self.position)}", "position")
        if self.axes is not None and len(self.position) != len(self.axes):
            raise fail(f"expected {len(self.axes)} numbers (one per axis of {self.axes!r}), "
                       f"got {len(self.position)}", "position")
        return self


class JointGoalMapping(ScenarioModel):
    """``{type: joint, position: q [rad or m], tolerance [rad or m], weight}``."""

    type: Literal["joint"]
    position: Annotated[tuple[Annotated[float, Range(-MAX_JOINT_VALUE, MAX_JOINT_VALUE)], ...], Items(max_items=64)]
    tolerance: Tolerance = 0.05
    weight: Weight = 1.0


class PathGoalMapping(ScenarioModel):
    """``{type: path, trajectory: {...}, link, parent_link, axes, tolerance [m], weight, offset [m],
    guided_end}``."""

    type: Literal["path"]
    trajectory: TrajectoryMapping
    link: Link | None = None
    parent_link: Link | None = None
    axes: Axes | None = None
    tolerance: Tolerance = 0.05
    weight: Weight = 1.0
    offset: Offset = (0.0, 0.0, 0.0)
    guided_end: Annotated[bool, Flag()] | None = None

    @model_validator(mode="after")
    def _an_end_to_guide(self) -> PathGoalMapping:
        kind = self.trajectory.type  # type: ignore[attr-defined]
        if self.guided_end and kind not in ENDING_PATHS:
            raise fail(f"a {kind} path has no end at rest to plan to (only {' and '.join(ENDING_PATHS)} paths "
                       "end); remove guided_end", "guided_end")
        return self


class PoseGoalMapping(ScenarioModel):
    """``{type: pose, position: P [m], orientation: [w, x, y, z] | rpy: [r, p, y] [rad], link,
    offset, tolerance [m], angle_tolerance [rad], weight}``."""

    type: Literal["pose"]
    position: Point3
    link: Link | None = None
    offset: Offset = (0.0, 0.0, 0.0)
    orientation: Annotated[tuple[Angles, ...], Items((4,))] | None = None
    rpy: Annotated[tuple[Angles, ...], Items((3,))] | None = None
    tolerance: Tolerance = 0.05
    angle_tolerance: AngleTolerance = DEFAULT_ANGLE_TOLERANCE
    weight: Weight = 1.0

    @model_validator(mode="after")
    def _one_rotation(self) -> PoseGoalMapping:
        if (self.orientation is None) == (self.rpy is None):
            raise fail("expected exactly one of 'orientation' [w, x, y, z] or 'rpy' [roll, pitch, yaw]")
        try:
            self.quaternion()
        except ShapeError as error:
            raise fail(str(error), "orientation" if self.orientation is not None else "rpy") from None
        return self

    def quaternion(self) -> tuple[float, float, float, float]:
        """The target rotation as a unit quaternion (w, x, y, z)."""
        if self.orientation is not None:
            return unit_quaternion(self.orientation)
        return quaternion_from_rpy(self.rpy)


class AxisGoalMapping(ScenarioModel):
    """``{type: axis, axis: a, direction: d, link, angle_tolerance [rad], weight,
    angular_velocity: ω [rad/s]}``."""

    type: Literal["axis"]
    axis: Point3
    direction: Point3
    link: Link | None = None
    angle_tolerance: AngleTolerance = DEFAULT_ANGLE_TOLERANCE
    weight: Weight = 1.0
    angular_velocity: Annotated[tuple[AngularVelocity, ...], Items((3,))] | None = None

    @model_validator(mode="after")
    def _directions_not_zero(self) -> AxisGoalMapping:
        for key in ("axis", "direction"):
            if math.hypot(*getattr(self, key)) < 1e-9:
                raise fail("expected a non-zero direction, got [0, 0, 0]", key)
        return self


GoalMapping = tagged_union({"position": PositionGoalMapping, "joint": JointGoalMapping, "path": PathGoalMapping,
                            "pose": PoseGoalMapping, "axis": AxisGoalMapping}, "type")


def goal_spec(goal: ScenarioModel) -> GoalSpec:
    """The goal value of a validated ``goal:`` entry."""
    if isinstance(goal, JointGoalMapping):
        return GoalSpec(type="joint", position=goal.position, tolerance=goal.tolerance, weight=goal.weight)
    if isinstance(goal, PoseGoalMapping):
        return GoalSpec(type="pose", link=goal.link, position=goal.position, tolerance=goal.tolerance,
                        weight=goal.weight, offset=goal.offset, orientation=goal.quaternion(),
                        angle_tolerance=goal.angle_tolerance)
    if isinstance(goal, AxisGoalMapping):
        return GoalSpec(type="axis", link=goal.link, weight=goal.weight, axis=unit_vector(goal.axis),
                        direction=unit_vector(goal.direction), angle_tolerance=goal.angle_tolerance,
                        angular_velocity=goal.angular_velocity)
    assert isinstance(goal, PositionGoalMapping | PathGoalMapping)
    return GoalSpec(
        type=goal.type, link=goal.link, position=goal.position if isinstance(goal, PositionGoalMapping) else None,
        tolerance=goal.tolerance, weight=goal.weight, parent_link=goal.parent_link, axes=goal.axes,
        trajectory=frozen_trajectory(goal.trajectory) if isinstance(goal, PathGoalMapping) else None,
        offset=goal.offset, guided_end=goal.guided_end if isinstance(goal, PathGoalMapping) else None)
