"""The ``trajectory:`` mappings of path goals and moving obstacles (docs/design.md section 5.2):
their keys and the documented ranges of their numbers (:mod:`dynfab.scenario.ranges`).

The trajectory itself is built later, by
:func:`dynfab.motion.trajectory_mapping.trajectory_from_mapping` or, for ``rrt``, by an
RRT around the scenario's obstacles (scenario/references.py); a goal or obstacle keeps the
validated mapping, read-only.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Any, Literal, cast

from pydantic import model_validator

from dynfab.scenario.fields import TRAJECTORY_TYPES, freeze
from dynfab.scenario.model_errors import tagged_union
from dynfab.scenario.model_types import Items, Range, ScenarioModel, Text, Whole, fail
from dynfab.scenario.ranges import (
    MAX_COEFFICIENT,
    MAX_COEFFICIENTS,
    MAX_SEED,
    AngularVelocity,
    Coordinate,
    Length,
    PathDuration,
    Point,
    Point3,
    Speed,
)

__all__ = ["TrajectoryMapping", "frozen_trajectory"]

#: Longest expression of one axis [characters].
MAX_EXPRESSION_LENGTH = 500
#: Most waypoints of a spline.
MAX_WAYPOINTS = 1000


class LinearMapping(ScenarioModel):
    """``{type: linear, start: P [m], velocity: V [m/s]}``: ``x(t) = P + V t``."""

    type: Literal["linear"]
    start: Point
    velocity: Annotated[tuple[Speed, ...], Items((2, 3))]

    @model_validator(mode="after")
    def _same_length(self) -> LinearMapping:
        if len(self.velocity) != len(self.start):
            raise fail(f"expected {len(self.start)} numbers, got {len(self.velocity)}", "velocity")
        return self


class CircleMapping(ScenarioModel):
    """``{type: circle, center: C [m], radius: R [m], angular_velocity: ω [rad/s],
    normal: N, phase: φ [rad]}`` (``normal`` and ``phase`` optional)."""

    type: Literal["circle"]
    center: Point
    radius: Length
    angular_velocity: AngularVelocity
    normal: Point3 = (0.0, 0.0, 1.0)
    phase: Annotated[float, Range(-1e3, 1e3, unit=" rad")] = 0.0

    @model_validator(mode="after")
    def _normal_not_zero(self) -> CircleMapping:
        if not any(self.normal):
            raise fail("must not be the zero vector", "normal")
        return self


class PolynomialMapping(ScenarioModel):
    """``{type: polynomial, coefficients: [[cx0, cx1, ...], [cy0, ...], ...]}``, one list
    per axis, lowest order first [m/s^k]."""

    type: Literal["polynomial"]
    coefficients: Annotated[
        tuple[Annotated[tuple[Annotated[float, Range(-MAX_COEFFICIENT, MAX_COEFFICIENT)], ...],
                        Items(what="coefficients", max_items=MAX_COEFFICIENTS)], ...],
        Items((2, 3), what="lists (one per axis)")]


class ExpressionMapping(ScenarioModel):
    """``{type: expression, x: ["0.5 + 0.1*sin(0.5*t)", ...]}``: one expression of t per axis."""

    type: Literal["expression"]
    x: Annotated[tuple[Annotated[str, Text(MAX_EXPRESSION_LENGTH)], ...], Items((2, 3), what="expressions")]


class SplineMapping(ScenarioModel):
    """``{type: spline, waypoints: [P0, P1, ...], duration: T [s]}``."""

    type: Literal["spline"]
    waypoints: Annotated[tuple[Point, ...], Items(what="waypoints", max_items=MAX_WAYPOINTS)]
    duration: PathDuration

    @model_validator(mode="after")
    def _enough_waypoints(self) -> SplineMapping:
        if len(self.waypoints) < 2:
            raise fail(f"expected at least 2 waypoints, got {len(self.waypoints)}", "waypoints")
        for i, waypoint in enumerate(self.waypoints[1:], 1):
            if len(waypoint) != len(self.waypoints[0]):
                raise fail(f"expected {len(self.waypoints[0])} numbers, got {len(waypoint)}", f"waypoints[{i}]")
        return self


class RrtMapping(ScenarioModel):
    """``{type: rrt, goal: P [m], duration: T [s], seed: S}``: an RRT path to P around the
    static spheres, followed by a spline that reaches P at T."""

    type: Literal["rrt"]
    goal: Annotated[tuple[Coordinate, ...], Items(max_items=3)]
    duration: PathDuration
    seed: Annotated[int, Whole(0, MAX_SEED)] = 0


TrajectoryMapping = tagged_union(dict(zip(TRAJECTORY_TYPES, (
    LinearMapping, CircleMapping, PolynomialMapping, ExpressionMapping, SplineMapping, RrtMapping)))
    , "type")


def frozen_trajectory(model: ScenarioModel) -> Mapping[str, Any]:
    """The validated mapping, read-only (tuples for lists), with only the keys the file gave."""
    return cast(Mapping[str, Any], freeze(model.model_dump(exclude_unset=True)))
