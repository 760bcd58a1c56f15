"""Exact distances between triangle meshes and obstacle shapes (coal).

A robot link's collision geometry is a :class:`MeshSet`: one or more triangle meshes in
the link frame. Each mesh is kept twice, as

- its convex hull (``coal.Convex``): GJK/EPA give a *signed* distance [m], negative
  inside (the penetration depth), in a few microseconds; since a mesh lies inside its
  hull, the hull distance is a lower bound of the mesh distance;
- the mesh itself (``coal.BVHModelOBBRSS``): exact but about 10-50 times slower, and it
  only knows surfaces: no penetration depth, and a solid wholly inside a mesh does not
  cross its surface.

:func:`exact_distance` combines them: the true mesh distance when the hulls are apart
or the meshes do not touch although their hulls overlap, and the hulls' (non-positive)
signed distance when the meshes do touch — their surfaces intersect, or one lies wholly
inside the other (then no surfaces cross; one point of the inner solid is tested against
the outer mesh by ray parity, which needs closed meshes, as collision meshes are; an open
obstacle mesh, a surface, has no inside and is touched only when surfaces meet). Obstacle shapes (:mod:`dynfab.geometry.shapes`)
are coal primitives, exact; a :class:`~dynfab.geometry.shapes.Plane` is the solid
half-space ``z <= 0`` of its frame; a point cloud's kept points are measured as points, a
point inside a link as deep as its distance to the link's surface
(:mod:`dynfab.geometry.cloud_collision`).

Poses are 4x4 homogeneous transforms ``x_world = R x_local + p`` [m].
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import coal
import numpy as np
import trimesh
from numpy.typing import NDArray

from dynfab.geometry.cloud_collision import (CloudSolid, LinkSolid, closed_solid, cloud_distance, cloud_lower_bound,
                                             cloud_solid, hull_planes)
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Mesh, Placement, Plane, PointCloud, Shape, Sphere

__all__ = [
    "MeshSet", "Solid", "exact_distance", "hull_distance", "mesh_set", "placement_matrix",
    "shape_bounding_radius", "shape_geometry",
]


@dataclass(frozen=True, eq=False)
class _MeshPart(LinkSolid):
    """One triangle mesh as its convex hull (coal's, and its face planes), as a BVH of its
    triangles, as is and merged (:class:`~dynfab.geometry.cloud_collision.LinkSolid`), and
    whether it is closed as is (watertight: it has an inside), decided once."""

    hull: coal.Convex
    triangles: trimesh.Trimesh
    closed: bool


@dataclass(frozen=True, eq=False)
class MeshSet:
    """The collision meshes of one body, in its frame.

    Attributes:
        parts: One entry per mesh.
        center: Centre of the bounding sphere of every vertex, body frame [m].
        radius: Its radius [m]: every vertex is within ``radius`` of ``center``.
    """

    parts: tuple[_MeshPart, ...]
    center: NDArray[np.float64]
    radius: float


#: What a :class:`MeshSet` can be measured against: another mesh set, a coal primitive or a cloud's points.
Solid = MeshSet | coal.CollisionGeometry | CloudSolid


def mesh_set(meshes: Sequence[trimesh.Trimesh]) -> MeshSet:
    """The mesh set of some triangle meshes (at least one, each with triangles).

    Raises:
        ValueError: No mesh, or a mesh without triangles.
    """
    if not meshes:
        raise ValueError("a mesh set needs at least one mesh")
    parts = []
    for mesh in meshes:
        if len(mesh.faces) == 0:
            raise ValueError("a collision mesh has no triangles")
        parts.append(_MeshPart(mesh=_bvh(mesh), planes=hull_planes(mesh), solid=closed_solid(mesh),
                               hull=_convex(mesh.convex_hull), triangles=mesh, closed=bool(mesh.is_watertight)))
    vertices = np.concatenate([np.asarray(mesh.vertices, dtype=float) for mesh in meshes])
    center = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    radius = float(np.max(np.linalg.norm(vertices - center, axis=1)))
    return MeshSet(tuple(parts), center, radius)


def shape_geometry(shape: Shape) -> Solid:
    """The coal primitive of an obstacle shape, in the shape's frame (see shapes.py); a mesh
    obstacle's :class:`MeshSet` (built once per mesh); a non-empty point cloud's
    :class:`~dynfab.geometry.cloud_collision.CloudSolid` (built once per cloud)."""
    if isinstance(shape, PointCloud):
        cached = shape.__dict__.get("_cloud_solid")
        if cached is None:
            cached = shape.__dict__["_cloud_solid"] = cloud_solid(shape, _bvh(shape.specks.triangles))
        return cached
    if isinstance(shape, Mesh):
        cached = shape.__dict__.get("_mesh_set")
        if cached is None:
            cached = shape.__dict__["_mesh_set"] = mesh_set([shape.triangles])
        return cached
    if isinstance(shape, Sphere):
        return coal.Sphere(shape.radius)
    if isinstance(shape, Box):
        return coal.Box(*shape.size)
    if isinstance(shape, Cylinder):
        return coal.Cylinder(shape.radius, shape.length)
    if isinstance(shape, Capsule):
        return coal.Capsule(shape.radius, shape.length)
    if isinstance(shape, Plane):
        return coal.Halfspace(np.array([0.0, 0.0, 1.0]), 0.0)
    raise TypeError(f"unsupported obstacle shape {type(shape).__name__}")


def shape_bounding_radius(shape: Shape) -> float:
    """Radius [m] of the smallest sphere about the shape origin that holds the shape;
    ``inf`` for a plane (a half-space is unbounded)."""
    if isinstance(shape, Sphere):
        return shape.radius
    if isinstance(shape, Box):
        return 0.5 * float(np.linalg.norm(shape.size))
    if isinstance(shape, Cylinder):
        return float(np.hypot(shape.radius, 0.5 * shape.length))
    if isinstance(shape, Capsule):
        return shape.radius + 0.5 * shape.length
    if isinstance(shape, Plane):
        return float("inf")
    if isinstance(shape, Mesh | PointCloud):
        return shape.bounding_radius
    raise TypeError(f"unsupported obstacle shape {type(shape).__name__}")


def placement_matrix(placement: Placement) -> NDArray[np.float64]:
    """The 4x4 transform ``[[R, p], [0, 1]]`` of a placement."""
    matrix = np.eye(4)
    matrix[:3, :3] = placement.rotation
    matrix[:3, 3] = placement.position
    return matrix


def hull_distance(a: MeshSet, pose_a: NDArray[np.float64], b: Solid, pose_b: NDArray[np.float64]) -> float:
    """Signed distance [m] between the convex hulls of ``a``'s meshes and ``b``.

    ``min_{i,j} d(hull(A_i), B_j)``, negative when two hulls overlap (minus the
    penetration depth). A lower bound of the meshes' own distance. Against a cloud, the
    bound of its bounding spheres (:func:`~dynfab.geometry.cloud_collision.cloud_lower_bound`).
    """
    if isinstance(b, CloudSolid):
        return cloud_lower_bound(a.center, a.radius, pose_a, b, pose_b)
    transform_a, transform_b = _transform(pose_a), _transform(pose_b)
    return min(_distance(part.hull, transform_a, other, transform_b)
               for part in a.parts for other in _hulls(b))


def exact_distance(a: MeshSet, pose_a: NDArray[np.float64], b: Solid, pose_b: NDArray[np.float64]) -> float:
    """Distance [m] between ``a``'s meshes and ``b``; <= 0 when they touch.

    For each pair of parts: if the hulls are apart, or the solids do not touch, the
    exact distance between the meshes (>= 0); if they touch (surfaces intersect or one
    is inside the other), the hulls' signed distance (<= 0: its magnitude is the hulls'
    penetration depth). The result is the minimum over the pairs. Against a half-space the
    hulls are exact: the lowest point of a hull is one of the mesh's vertices. Against a
    cloud, the signed distance to its points
    (:func:`~dynfab.geometry.cloud_collision.cloud_distance`).
    """
    if isinstance(b, CloudSolid):
        return cloud_distance(a.parts, a.center, a.radius, pose_a, b, pose_b)
    if isinstance(b, coal.Halfspace):
        return hull_distance(a, pose_a, b, pose_b)
    transform_a, transform_b = _transform(pose_a), _transform(pose_b)
    best = float("inf")
    for part in a.parts:
        for hull, mesh, triangles, closed in _parts_of(b):
            hull_gap = _distance(part.hull, transform_a, hull, transform_b)
            touching = hull_gap <= 0.0 and (
                _collide(part.mesh, transform_a, mesh, transform_b)
                or _inside(part, pose_a, triangles, closed, pose_b))
            if touching:
                gap = min(hull_gap, 0.0)
            else:
                gap = max(_distance(part.mesh, transform_a, mesh, transform_b), hull_gap, 0.0)
            best = min(best, gap)
    return best


def _inside(part: _MeshPart, pose_a: NDArray[np.float64], triangles: trimesh.Trimesh | None, closed: bool,
            pose_b: NDArray[np.float64]) -> bool:
    """Whether ``b`` lies inside the part, or (a mesh) the part inside ``b``, given that
    their surfaces do not cross: then one point of the inner one decides."""
    to_a = np.linalg.inv(np.asarray(pose_a, dtype=float)) @ np.asarray(pose_b, dtype=float)
    if triangles is None:  # a bounded primitive: its origin is inside it
        return bool(part.triangles.contains(to_a[None, :3, 3])[0])
    b_vertex = to_a[:3, :3] @ triangles.vertices[0] + to_a[:3, 3]
    to_b = np.linalg.inv(to_a)
    a_vertex = to_b[:3, :3] @ part.triangles.vertices[0] + to_b[:3, 3]
    if bool(part.triangles.contains(b_vertex[None])[0]):
        return True
    return closed and bool(triangles.contains(a_vertex[None])[0])  # an open surface has no inside


def _hulls(b: Solid) -> list[coal.CollisionGeometry]:
    return [part.hull for part in b.parts] if isinstance(b, MeshSet) else [b]


def _parts_of(b: Solid) -> list[tuple[coal.CollisionGeometry, coal.CollisionGeometry, trimesh.Trimesh | None, bool]]:
    """(hull, BVH, triangles, closed) of each part of a mesh set; (shape, shape, None, True)
    for a primitive."""
    if isinstance(b, MeshSet):
        return [(part.hull, part.mesh, part.triangles, part.closed) for part in b.parts]
    return [(b, b, None, True)]


def _distance(a: coal.CollisionGeometry, transform_a: coal.Transform3s,
              b: coal.CollisionGeometry, transform_b: coal.Transform3s) -> float:
    return float(coal.distance(a, transform_a, b, transform_b, coal.DistanceRequest(), coal.DistanceResult()))


def _collide(a: coal.CollisionGeometry, transform_a: coal.Transform3s,
             b: coal.CollisionGeometry, transform_b: coal.Transform3s) -> bool:
    return coal.collide(a, transform_a, b, transform_b, coal.CollisionRequest(), coal.CollisionResult()) > 0


def _transform(pose: NDArray[np.float64]) -> coal.Transform3s:
    matrix = np.asarray(pose, dtype=float)
    return coal.Transform3s(np.ascontiguousarray(matrix[:3, :3]), np.ascontiguousarray(matrix[:3, 3]))


def _convex(hull: trimesh.Trimesh) -> coal.Convex:
    points = coal.StdVec_Vec3s()
    for vertex in np.asarray(hull.vertices, dtype=float):
        points.append(vertex)
    triangles = coal.StdVec_Triangle()
    for a, b, c in np.asarray(hull.faces, dtype=int):
        triangles.append(coal.Triangle(int(a), int(b), int(c)))
    return coal.Convex(points, triangles)


def _bvh(mesh: trimesh.Trimesh) -> coal.BVHModelOBBRSS:
    model = coal.BVHModelOBBRSS()
    model.beginModel(len(mesh.faces), len(mesh.vertices))
    model.addVertices(np.ascontiguousarray(mesh.vertices, dtype=float))
    model.addTriangles(np.ascontiguousarray(mesh.faces, dtype=np.int64))
    model.endModel()
    return model
