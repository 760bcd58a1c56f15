"""Wireframe outlines of obstacle shapes, as polylines in world coordinates, for plots."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.shapes import Box, Capsule, Cylinder, Plane, Shape, Sphere, quaternion_matrix

#: Half the side of the square drawn for a (boundless) plane [m].
PLANE_HALF_SIDE = 0.5
_SEGMENTS = 32


def shape_outline(shape: Shape, orientation: Sequence[float], center: ArrayLike) -> list[NDArray[np.float64]]:
    """Polylines (each (N, 3) [m]) tracing ``shape`` placed at ``center`` with ``orientation``:
    a box's 12 edges; a cylinder's or capsule's end circles and 4 side lines (a capsule also
    its caps' meridians); a sphere's 3 great circles; a plane's square of side
    ``2 PLANE_HALF_SIDE`` around its point and a 0.1 m normal."""
    rotation = quaternion_matrix(orientation)
    origin = np.asarray(center, dtype=float)
    return [line @ rotation.T + origin for line in _local_outline(shape)]


def _circle(radius: float, z: float) -> NDArray[np.float64]:
    angle = np.linspace(0.0, 2.0 * np.pi, _SEGMENTS + 1)
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.full_like(angle, z)])


def _local_outline(shape: Shape) -> list[NDArray[np.float64]]:
    if isinstance(shape, Box):
        half = np.array(shape.size) / 2
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
        return [corners[[a, b]] for a in range(8) for b in range(a + 1, 8)
                if np.count_nonzero(corners[a] != corners[b]) == 1]
    if isinstance(shape, Sphere):
        circle = _circle(shape.radius, 0.0)
        return [circle, circle[:, [0, 2, 1]], circle[:, [2, 0, 1]]]
    if isinstance(shape, (Cylinder, Capsule)):
        half = shape.length / 2
        lines = [_circle(shape.radius, -half), _circle(shape.radius, half)]
        for angle in np.linspace(0.0, 2.0 * np.pi, 4, endpoint=False):
            x, y = shape.radius * np.cos(angle), shape.radius * np.sin(angle)
            lines.append(np.array([[x, y, -half], [x, y, half]]))
        if isinstance(shape, Capsule):
            arc = np.linspace(0.0, np.pi, _SEGMENTS // 2 + 1)
            for sign in (-1.0, 1.0):
                meridian = np.column_stack([shape.radius * np.cos(arc), np.zeros_like(arc),
                                            sign * (half + shape.radius * np.sin(arc))])
                lines += [meridian, meridian[:, [1, 0, 2]]]
        return lines
    if isinstance(shape, Plane):
        s = PLANE_HALF_SIDE
        square = np.array([[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0], [-s, -s, 0.0]])
        return [square, np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.1]])]
    raise TypeError(f"unknown shape {shape!r}")
