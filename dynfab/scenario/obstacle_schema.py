"""The ``obstacles:`` entries of a scenario: spheres, boxes, cylinders, capsules and
half-space planes, each static or moving along a trajectory of its centre."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, cast

from dynfab.geometry.shapes import (
    IDENTITY_QUATERNION,
    Box,
    Capsule,
    Cylinder,
    Plane,
    Shape,
    ShapeError,
    Sphere,
    quaternion_from_normal,
    unit_quaternion,
)
from dynfab.scenario import fields
from dynfab.scenario.fields import ScenarioError


OBSTACLE_TYPES: tuple[str, ...] = ("sphere", "box", "cylinder", "capsule", "plane")


ObstacleType = Literal["sphere", "box", "cylinder", "capsule", "plane"]


#: Keys of each obstacle type besides ``type``: (required, optional); every type also
#: takes exactly one of its placement key (``position``, a plane's ``point``) or ``trajectory``.
_OBSTACLE_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "sphere": (("radius",), ()),
    "box": (("size",), ("orientation",)),
    "cylinder": (("radius", "length"), ("orientation",)),
    "capsule": (("radius", "length"), ("orientation",)),
    "plane": (("normal",), ()),
}


@dataclass(frozen=True)
class ObstacleSpec:
    """An obstacle shape, static (``position``) or moving (``trajectory`` of its centre;
    its orientation stays).

    Attributes:
        type: One of :data:`OBSTACLE_TYPES`.
        radius: Radius of a sphere, cylinder or capsule [m] (> 0); 0 for a box or plane.
        position: Centre [m] (a plane: its ``point``), 2 numbers (planar robots only) or 3;
            None if moving.
        trajectory: Read-only mapping of the centre's motion, with a ``type`` among
            :data:`fields.TRAJECTORY_TYPES`; None if static.
        size: A box's full edge lengths (lx, ly, lz) [m]; None for other shapes.
        length: A cylinder's full length or a capsule's segment length, along the shape's z
            axis [m]; None for other shapes.
        orientation: Unit quaternion (w, x, y, z) of the shape frame (normalised from the
            file); a plane's takes +z onto its ``normal``.
        normal: A plane's unit normal, pointing out of the solid half-space; None otherwise.
    """

    type: ObstacleType
    radius: float = 0.0
    position: tuple[float, ...] | None = None
    trajectory: Mapping[str, Any] | None = None
    size: tuple[float, float, float] | None = None
    length: float | None = None
    orientation: tuple[float, float, float, float] = IDENTITY_QUATERNION
    normal: tuple[float, float, float] | None = None

    @property
    def shape(self) -> Shape:
        """The obstacle's geometry in its own frame."""
        if self.type == "sphere":
            return Sphere(self.radius)
        if self.type == "box":
            return Box(self.size)
        if self.type == "cylinder":
            return Cylinder(self.radius, self.length)
        if self.type == "capsule":
            return Capsule(self.radius, self.length)
        return Plane()


def parse_obstacle(value: object, field: str) -> ObstacleSpec:
    """Parse one entry of ``obstacles``; the allowed keys depend on its ``type``."""
    data = fields.mapping(value, field)
    if "type" not in data:
        raise ScenarioError(f"{field}.type", "missing required key")
    kind = cast(ObstacleType, fields.choice(data["type"], f"{field}.type", OBSTACLE_TYPES))
    placement = "point" if kind == "plane" else "position"
    required, optional = _OBSTACLE_KEYS[kind]
    fields.check_keys(data, field, ("type",) + required, optional + (placement, "trajectory"))
    if (placement in data) == ("trajectory" in data):
        raise ScenarioError(
            field, f"expected exactly one of '{placement}' (static) or 'trajectory' (moving)"
        )
    moving = "trajectory" in data
    normal = _normal(data["normal"], f"{field}.normal") if kind == "plane" else None
    orientation = _orientation(data["orientation"], f"{field}.orientation") if "orientation" in data \
        else IDENTITY_QUATERNION
    return ObstacleSpec(
        type=kind,
        radius=fields.positive(data["radius"], f"{field}.radius") if "radius" in data else 0.0,
        position=None if moving else fields.vector(data[placement], f"{field}.{placement}", (2, 3)),
        trajectory=fields.trajectory_mapping(data["trajectory"], f"{field}.trajectory") if moving else None,
        size=_size(data["size"], f"{field}.size") if kind == "box" else None,
        length=fields.positive(data["length"], f"{field}.length") if "length" in data else None,
        orientation=quaternion_from_normal(normal) if normal is not None else orientation,
        normal=normal,
    )


def _size(value: object, field: str) -> tuple[float, float, float]:
    """Parse a box's edge lengths: 3 positive numbers [m]."""
    numbers = fields.vector(value, field, (3,))
    lx, ly, lz = (fields.positive(number, f"{field}[{i}]") for i, number in enumerate(numbers))
    return lx, ly, lz


def _orientation(value: object, field: str) -> tuple[float, float, float, float]:
    """Parse a quaternion [w, x, y, z]; a non-unit one is normalised, a zero one rejected."""
    numbers = fields.vector(value, field, (4,))
    try:
        return unit_quaternion(numbers)
    except ShapeError:
        raise ScenarioError(field, f"expected a non-zero quaternion [w, x, y, z], got {list(numbers)}") from None


def _normal(value: object, field: str) -> tuple[float, float, float]:
    """Parse a plane's normal: 3 numbers, not all zero; returned unit length."""
    numbers = fields.vector(value, field, (3,))
    length = math.hypot(*numbers)
    if length < 1e-9:
        raise ScenarioError(field, f"expected a non-zero vector, got {list(numbers)}")
    x, y, z = (number / length for number in numbers)
    return x, y, z
