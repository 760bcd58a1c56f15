"""Nearest surface points and distances of query points to a triangle mesh (coal).

For a query point ``x`` (in the mesh frame) the nearest point ``c`` on the mesh's triangles
and the distance ``d = ‖x − c‖`` [m] are exact (coal's distance between a point and the
mesh's bounding-volume hierarchy). The *outward* unit normal is ``n = (x − c)/‖x − c‖``, so
that ``nᵀ (x − c) = d``. For a closed (watertight) mesh a query point inside the solid gets
``d < 0`` and ``n`` flipped (it still points out of the solid at ``c``); inside is decided
by ray parity (trimesh) and only for points within ``signed_within`` of the surface, since
that test costs about a millisecond: a point deeper inside reads as outside. A point
farther than ``max_distance`` from the mesh's bounding box is not queried (``found`` is
false): the broad phase.

This is the representation the fabric's nearest-point leaf
(:mod:`dynfab.fabric.leaves.surface_points`) reads: a mesh, and later a point cloud,
both become "the nearest surface point to each robot sphere".
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.mesh_shape import Mesh

__all__ = ["NearestPoints", "mesh_bvh", "mesh_signed_distance", "nearest_on_mesh"]

#: Radius of the coal sphere standing for a query point [m] (coal has no point shape).
_POINT_RADIUS = 1e-9
_IDENTITY = coal.Transform3s()


@dataclass(frozen=True)
class NearestPoints:
    """Per query point, its nearest surface point.

    Attributes:
        points: (N, 3) nearest points on the surface [m] (rows of points not found: NaN).
        normals: (N, 3) outward unit normals (from the surface toward the query point).
        distances: (N,) signed distances [m]; ``inf`` where not found.
        found: (N,) whether the point was within ``max_distance`` of the bounding box.
    """

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    distances: NDArray[np.float64]
    found: NDArray[np.bool_]


def mesh_bvh(mesh: Mesh) -> coal.BVHModelOBBRSS:
    """coal's bounding-volume hierarchy of the mesh, built once per mesh."""
    cached = mesh.__dict__.get("_bvh")
    if cached is None:
        cached = coal.BVHModelOBBRSS()
        cached.beginModel(len(mesh.faces), len(mesh.vertices))
        cached.addVertices(np.ascontiguousarray(mesh.vertices))
        cached.addTriangles(np.ascontiguousarray(mesh.faces))
        cached.endModel()
        mesh.__dict__["_bvh"] = cached
    return cached


def box_gap(mesh: Mesh, points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distance (N,) [m] of points (mesh frame) to the mesh's axis-aligned bounding box: a
    lower bound of their distance to the mesh."""
    low, high = mesh.bounds
    outside = np.maximum(low - points, 0.0) + np.maximum(points - high, 0.0)
    return np.linalg.norm(outside, axis=-1)


def nearest_on_mesh(mesh: Mesh, points: ArrayLike, max_distance: float = np.inf,
                    signed_within: float = 0.0) -> NearestPoints:
    """The nearest surface point of each query point (module docstring).

    Args:
        mesh: The mesh.
        points: (N, 3) query points in the mesh frame [m].
        max_distance: Points farther than this from the mesh's bounding box are not
            queried [m].
        signed_within: For a closed mesh, points closer than this to the surface are tested
            for being inside [m]; 0: never (unsigned distances).
    """
    x = np.asarray(points, dtype=float).reshape(-1, 3)
    count = len(x)
    nearest = np.full((count, 3), np.nan)
    normals = np.full((count, 3), np.nan)
    distances = np.full(count, np.inf)
    found = box_gap(mesh, x) <= max_distance
    bvh = mesh_bvh(mesh)
    point = coal.Sphere(_POINT_RADIUS)
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    rotation = np.eye(3)
    for i in np.flatnonzero(found):
        result.clear()
        distances[i] = coal.distance(point, coal.Transform3s(rotation, x[i]), bvh, _IDENTITY, request, result)
        nearest[i] = result.getNearestPoint2()
    if not found.any():
        return NearestPoints(nearest, normals, distances, found)
    rows = np.flatnonzero(found)
    distances[rows] = np.maximum(distances[rows] + _POINT_RADIUS, 0.0)
    offsets = x[rows] - nearest[rows]
    lengths = np.linalg.norm(offsets, axis=1)
    on_surface = lengths < 1e-9
    normals[rows] = offsets / np.where(on_surface, 1.0, lengths)[:, None]
    if on_surface.any():  # the point lies on a triangle: that triangle's normal
        normals[rows[on_surface]] = _face_normals(mesh, x[rows[on_surface]])
    solid = mesh.solid if signed_within > 0.0 else None
    if solid is not None:
        near = rows[distances[rows] < signed_within]
        if near.size:
            inside = near[solid.contains(x[near])]
            distances[inside] *= -1.0
            normals[inside] *= -1.0
    return NearestPoints(nearest, normals, distances, found)


def mesh_signed_distance(mesh: Mesh, points: ArrayLike, signed_within: float = 0.1) -> NDArray[np.float64]:
    """Distance (...,) [m] of points (..., 3) in the mesh frame to the mesh's surface,
    negative inside a closed mesh within ``signed_within`` of its surface."""
    x = np.asarray(points, dtype=float)
    result = nearest_on_mesh(mesh, x.reshape(-1, 3), signed_within=signed_within)
    return result.distances.reshape(x.shape[:-1])


def _face_normals(mesh: Mesh, points: NDArray[np.float64]) -> NDArray[np.float64]:
    """The unit normals of the triangles nearest to points lying on the surface."""
    _, _, triangle = mesh.triangles.nearest.on_surface(points)
    return np.asarray(mesh.triangles.face_normals[triangle], dtype=float)
