"""An obstacle at one instant, as guidance and its checkers see it."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from dynfab.geometry.shapes import Placement, PointCloud, Shape

__all__ = ["PlacedObstacle", "any_cloud", "any_moving"]


@dataclass(frozen=True)
class PlacedObstacle:
    """An obstacle at one instant.

    Attributes:
        shape: its shape.
        placement: where its frame is (a plane: its point, and its normal as the frame's z).
        velocity: its frame's velocity then [m/s] (zero for what does not move; plans see
            a moving sphere as what it sweeps soon, :mod:`dynfab.motion.swept_obstacles`).
    """

    shape: Shape
    placement: Placement
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)


def any_moving(obstacles: Sequence[PlacedObstacle]) -> bool:
    """Whether any of ``obstacles`` moves (a velocity other than zero)."""
    return any(any(v != 0.0 for v in o.velocity) for o in obstacles)


def any_cloud(obstacles: Sequence[PlacedObstacle]) -> bool:
    """Whether any of ``obstacles`` is a point cloud."""
    return any(isinstance(o.shape, PointCloud) for o in obstacles)
