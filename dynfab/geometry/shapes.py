"""Obstacle shapes as values: geometry in the shape's own frame, placed by a pose.

Every shape is described in a frame of its own and placed in the world by a
:class:`Placement` ``(p, R)``: a point ``x_s`` of the shape frame is ``x = R x_s + p`` in
the world [m]. The shape frames are:

- :class:`Sphere`: centred at the origin.
- :class:`Box`: centred at the origin, edges along the axes, full edge lengths ``size``.
- :class:`Cylinder`: centred at the origin, axis along z, full ``length`` along z.
- :class:`Capsule`: the points within ``radius`` of the segment from ``(0, 0, -length/2)``
  to ``(0, 0, length/2)``.
- :class:`Plane`: the solid half-space ``z_s <= 0`` (the plane through the origin with
  normal +z; what lies below it is solid: a floor, a table top, a wall).
- :class:`~dynfab.geometry.mesh_shape.Mesh`: triangles given in the shape frame.
- :class:`~dynfab.geometry.point_cloud.PointCloud`: measured points given in the shape frame
  (a scenario's clouds: the world frame, placed at the origin).

Orientations are unit quaternions ``(w, x, y, z)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Union

import numpy as np

from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.point_cloud import PointCloud

__all__ = [
    "Box", "Capsule", "Cylinder", "IDENTITY_QUATERNION", "Mesh", "Placement", "Plane", "PointCloud", "Shape",
    "ShapeError", "Sphere", "quaternion_from_normal", "quaternion_from_rpy", "quaternion_matrix",
    "unit_quaternion",
]

#: The identity rotation as a quaternion (w, x, y, z).
IDENTITY_QUATERNION: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)

#: A quaternion whose norm is within this of 1 is normalised silently; further off, it is
#: still normalised (any non-zero quaternion is a rotation) unless its norm is below
#: :data:`_MIN_QUATERNION_NORM`.
_MIN_QUATERNION_NORM = 1e-6


class ShapeError(ValueError):
    """A degenerate shape: a size that is not positive and finite, a zero quaternion."""


def _positive(value: float, what: str) -> float:
    number = float(value)
    if not (math.isfinite(number) and number > 0.0):
        raise ShapeError(f"{what} must be a positive finite number, got {value!r}")
    return number


def _vector(values: Sequence[float], size: int, what: str) -> tuple[float, ...]:
    array = np.asarray(values, dtype=float).reshape(-1)
    if array.size != size or not np.isfinite(array).all():
        raise ShapeError(f"{what} must be {size} finite numbers, got {list(np.asarray(values).reshape(-1))}")
    return tuple(float(x) for x in array)


def unit_quaternion(values: Sequence[float], what: str = "orientation") -> tuple[float, float, float, float]:
    """``values / ‖values‖`` as a quaternion ``(w, x, y, z)``.

    Raises:
        ShapeError: not four finite numbers, or a norm below 1e-6 (no rotation).
    """
    q = np.array(_vector(values, 4, what))
    norm = float(np.linalg.norm(q))
    if norm < _MIN_QUATERNION_NORM:
        raise ShapeError(f"{what} must be a unit quaternion [w, x, y, z], got a zero quaternion {list(q)}")
    w, x, y, z = (float(v) for v in q / norm)
    return (w, x, y, z)


def quaternion_matrix(quaternion: Sequence[float]) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = quaternion
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def quaternion_from_rpy(rpy: Sequence[float]) -> tuple[float, float, float, float]:
    """Quaternion of ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (URDF's fixed-axis convention) [rad]."""
    roll, pitch, yaw = _vector(rpy, 3, "rpy")
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return unit_quaternion((cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy))


def quaternion_from_normal(normal: Sequence[float]) -> tuple[float, float, float, float]:
    """The shortest rotation taking +z onto the unit vector along ``normal``.

    Raises:
        ShapeError: ``normal`` is zero or not finite.
    """
    n = np.array(_vector(normal, 3, "normal"))
    length = float(np.linalg.norm(n))
    if length < 1e-9:
        raise ShapeError(f"normal must be a non-zero vector, got {list(n)}")
    n = n / length
    if n[2] < -1.0 + 1e-12:  # opposite of +z: half a turn about x
        return (0.0, 1.0, 0.0, 0.0)
    # q = (1 + z·n, z × n) normalised
    return unit_quaternion((1.0 + n[2], -n[1], n[0], 0.0))


@dataclass(frozen=True)
class Placement:
    """Where a shape frame is: ``x_world = R(orientation) x_shape + position`` [m].

    Attributes:
        position: Origin of the shape frame in the world [m].
        orientation: Unit quaternion (w, x, y, z); normalised on construction.
    """

    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float] = IDENTITY_QUATERNION

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _vector(self.position, 3, "position"))
        object.__setattr__(self, "orientation", unit_quaternion(self.orientation))

    @property
    def rotation(self) -> np.ndarray:
        """``R`` (3, 3): columns are the shape axes in world coordinates."""
        return quaternion_matrix(self.orientation)

    def to_local(self, points: np.ndarray) -> np.ndarray:
        """World points (..., 3) in shape coordinates, ``R^T (x - p)`` [m]."""
        return (np.asarray(points, dtype=float) - np.array(self.position)) @ self.rotation


@dataclass(frozen=True)
class Sphere:
    """A ball of ``radius`` [m] about the shape origin."""

    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive(self.radius, "sphere radius"))

    @property
    def dimensions(self) -> tuple[float, ...]:
        """The numbers that size the shape: ``(radius,)`` [m]."""
        return (self.radius,)


@dataclass(frozen=True)
class Box:
    """An axis-aligned box (in its frame) of full edge lengths ``size`` [m], centred."""

    size: tuple[float, float, float]

    def __post_init__(self) -> None:
        size = _vector(self.size, 3, "box size")
        for value in size:
            _positive(value, f"box size {list(size)}: every edge")
        object.__setattr__(self, "size", size)

    @property
    def dimensions(self) -> tuple[float, ...]:
        """``(lx, ly, lz)`` [m]."""
        return self.size


@dataclass(frozen=True)
class Cylinder:
    """A solid cylinder along the frame's z axis: ``radius`` and full ``length`` [m]."""

    radius: float
    length: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive(self.radius, "cylinder radius"))
        object.__setattr__(self, "length", _positive(self.length, "cylinder length"))

    @property
    def dimensions(self) -> tuple[float, ...]:
        """``(radius, length)`` [m]."""
        return (self.radius, self.length)


@dataclass(frozen=True)
class Capsule:
    """Points within ``radius`` of the z-axis segment of ``length`` [m] (cap centres)."""

    radius: float
    length: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive(self.radius, "capsule radius"))
        object.__setattr__(self, "length", _positive(self.length, "capsule length"))

    @property
    def dimensions(self) -> tuple[float, ...]:
        """``(radius, length)`` [m]."""
        return (self.radius, self.length)


@dataclass(frozen=True)
class Plane:
    """The solid half-space ``z <= 0`` of its frame (a floor, table top or wall)."""

    @property
    def dimensions(self) -> tuple[float, ...]:
        """No sizes."""
        return ()


#: Any obstacle shape.
Shape = Union[Sphere, Box, Cylinder, Capsule, Plane, Mesh, PointCloud]
