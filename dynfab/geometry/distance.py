"""Exact signed distance from points to obstacle shapes (numpy, vectorised).

Every function takes points ``x`` of shape (..., 3) [m] in the shape's own frame (see
:mod:`dynfab.geometry.shapes`) and returns the signed Euclidean distance (...,) [m] to the
shape's surface: positive outside, zero on the surface, negative inside (minus the depth
to the nearest surface point). Used by the metrics and as the reference of the smoothed
CasADi distances of :mod:`dynfab.geometry.smooth_distance`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.mesh_distance import mesh_signed_distance
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Mesh, Placement, Plane, PointCloud, Shape, Sphere

__all__ = ["box_distance", "capsule_distance", "cylinder_distance", "placed_distance", "plane_distance",
           "shape_distance", "sphere_distance"]


def sphere_distance(points: ArrayLike, radius: float) -> NDArray[np.float64]:
    """``d = ‖x‖ − r`` [m]."""
    return np.linalg.norm(np.asarray(points, dtype=float), axis=-1) - radius


def box_distance(points: ArrayLike, size: Sequence[float]) -> NDArray[np.float64]:
    """Box of full edge lengths ``size`` centred at the origin [m].

    With ``q = |x| − size/2`` (per axis): ``d = ‖max(q, 0)‖ + min(maxᵢ qᵢ, 0)``.
    """
    q = np.abs(np.asarray(points, dtype=float)) - 0.5 * np.asarray(size, dtype=float)
    return np.linalg.norm(np.maximum(q, 0.0), axis=-1) + np.minimum(q.max(axis=-1), 0.0)


def cylinder_distance(points: ArrayLike, radius: float, length: float) -> NDArray[np.float64]:
    """Solid cylinder along z, centred, of ``radius`` and full ``length`` [m].

    With ``ρ = √(x² + y²)`` and ``q = (ρ − r, |z| − l/2)``:
    ``d = ‖max(q, 0)‖ + min(max(q₁, q₂), 0)``.
    """
    x = np.asarray(points, dtype=float)
    q = np.stack([np.hypot(x[..., 0], x[..., 1]) - radius, np.abs(x[..., 2]) - 0.5 * length], axis=-1)
    return np.linalg.norm(np.maximum(q, 0.0), axis=-1) + np.minimum(q.max(axis=-1), 0.0)


def capsule_distance(points: ArrayLike, radius: float, length: float) -> NDArray[np.float64]:
    """Points within ``radius`` of the z segment ``[−l/2, l/2]`` [m]:
    ``d = ‖x − (0, 0, clamp(z, −l/2, l/2))‖ − r``."""
    x = np.array(points, dtype=float)
    x[..., 2] -= np.clip(x[..., 2], -0.5 * length, 0.5 * length)
    return np.linalg.norm(x, axis=-1) - radius


def plane_distance(points: ArrayLike) -> NDArray[np.float64]:
    """The half-space ``z ≤ 0``: ``d = z`` [m]."""
    return np.asarray(points, dtype=float)[..., 2].copy()


def shape_distance(shape: Shape, points: ArrayLike) -> NDArray[np.float64]:
    """Signed distance (...,) [m] of points (..., 3) given in the shape's frame (a mesh:
    :func:`~dynfab.geometry.mesh_distance.mesh_signed_distance`, signed within 0.1 m of a
    closed mesh's surface; a point cloud: the distance to its nearest kept point less its
    voxel half-diagonal, unsigned, :meth:`~dynfab.geometry.point_cloud.PointCloud.distance`)."""
    if isinstance(shape, Sphere):
        return sphere_distance(points, shape.radius)
    if isinstance(shape, Box):
        return box_distance(points, shape.size)
    if isinstance(shape, Cylinder):
        return cylinder_distance(points, shape.radius, shape.length)
    if isinstance(shape, Capsule):
        return capsule_distance(points, shape.radius, shape.length)
    if isinstance(shape, Plane):
        return plane_distance(points)
    if isinstance(shape, Mesh):
        return mesh_signed_distance(shape, points)
    if isinstance(shape, PointCloud):
        return shape.distance(points)
    raise TypeError(f"unknown shape {shape!r}")


def placed_distance(shape: Shape, placement: Placement, points: ArrayLike) -> NDArray[np.float64]:
    """Signed distance (...,) [m] of world points (..., 3) to ``shape`` placed at ``placement``:
    ``d(Rᵀ (x − p))``."""
    return shape_distance(shape, placement.to_local(points))
