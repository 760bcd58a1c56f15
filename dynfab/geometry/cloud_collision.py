"""Exact distance between a robot link's meshes and a point cloud's kept points (the run's
collision metrics against a cloud, issue 20).

A cloud's kept points ``C`` (:mod:`dynfab.geometry.point_cloud`) are points, not a solid: the
distance of a link ``L`` (closed triangle meshes) to them is signed,

    d(L, C) = min_{c ∈ C} s(c),   s(c) = dist(c, ∂L) outside L,  −dist(c, ∂L) inside L   [m],

so a contact is a point inside the link, as deep as its distance to the link's surface.
(Measuring the points as one mesh of tiny triangles, as before, gave the convex hull of the
whole cloud as the penetration depth once a triangle touched a link: "13.5 cm" where the run
was 7.5 mm clear of the true shapes.)

How it is computed, with ``(c_L, R_L)`` the link's bounding sphere (every vertex within
``R_L`` of ``c_L``) and ``d_0 = min_c ‖c − c_L‖`` (the cloud's KD-tree):

- ``d_0 − R_L`` is a lower bound of ``d(L, C)``: a point outside the ball is farther than
  ``d_0 − R_L`` from every point of the link, and a point inside the link lies inside the
  ball, at most ``R_L − ‖c − c_L‖ ≤ R_L − d_0`` from the link's surface (the ray from ``c``
  away from ``c_L`` leaves the link before the ball);
- only points within ``R_L`` of ``c_L`` can be inside: those inside the link's convex hull
  (its face planes, numpy) are tested against the mesh by their winding number (the mesh
  with coincident vertices merged, which makes Franka's collision meshes watertight; a mesh
  that is not has no inside and is touched only at its surface) and the inside ones
  measured to its surface (coal);
- with none inside, the unsigned distance is coal's between the link's mesh and a 0.1 mm
  triangle at each point (:attr:`~dynfab.geometry.point_cloud.PointCloud.specks`; at most
  0.1 mm below the distance to the points).

The metrics lower this by the cloud's ``δ`` (:attr:`~dynfab.robots.mesh_sweep.PlacedShape.lowering`):
raw points lie within ``δ`` of the kept ones.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import coal
import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from dynfab.geometry.point_cloud import PointCloud

if TYPE_CHECKING:
    from pykdtree.kdtree import KDTree

__all__ = [
    "CloudSolid", "LinkSolid", "closed_solid", "cloud_distance", "cloud_lower_bound", "cloud_solid", "hull_planes",
    "winding_numbers",
]


@dataclass(frozen=True, eq=False)
class CloudSolid:
    """A cloud's kept points for exact checks, in the cloud's frame.

    Attributes:
        points: (M, 3) kept points [m] (M > 0).
        tree: pykdtree KD-tree of them (nearest point).
        balls: scipy KD-tree of them (points within a radius).
        specks: coal BVH of a 0.1 mm triangle at each point (unsigned distance).
    """

    points: NDArray[np.float64]
    tree: KDTree
    balls: cKDTree
    specks: coal.BVHModelOBBRSS


@dataclass(frozen=True, eq=False)
class LinkSolid:
    """What :func:`cloud_distance` reads of one mesh of a link, in the link frame.

    Attributes:
        mesh: coal BVH of its triangles.
        planes: (4, F) its convex hull's faces, rows ``n_x, n_y, n_z, b``: ``nᵀx ≤ b``
            inside [-, m] (C order: ``points @ planes[:3]`` reads contiguous rows).
        solid: the mesh with coincident vertices merged, if that is watertight (it has an
            inside: Franka's collision meshes are, once merged), else None.
    """

    mesh: coal.BVHModelOBBRSS
    planes: NDArray[np.float64]
    solid: trimesh.Trimesh | None


def cloud_solid(cloud: PointCloud, specks: coal.BVHModelOBBRSS) -> CloudSolid:
    """The solid of a non-empty cloud, given the BVH of its specks."""
    return CloudSolid(cloud.points, cloud.tree, cKDTree(cloud.points), specks)


def cloud_lower_bound(center: NDArray[np.float64], radius: float, pose_a: NDArray[np.float64], cloud: CloudSolid,
                      pose_b: NDArray[np.float64]) -> float:
    """``d_0 − R_L`` [m] (module docstring): a lower bound of :func:`cloud_distance` of a
    link whose bounding sphere is ``(center, radius)`` in its frame at pose ``pose_a``, the
    cloud at ``pose_b`` (4x4 transforms)."""
    local = _to_cloud(pose_a, pose_b, center[None])
    gap, _ = cloud.tree.query(local)
    return float(gap[0]) - radius


def cloud_distance(parts: Sequence[LinkSolid], center: NDArray[np.float64], radius: float,
                   pose_a: NDArray[np.float64], cloud: CloudSolid, pose_b: NDArray[np.float64]) -> float:
    """``d(L, C)`` [m] (module docstring) of a link made of ``parts`` with bounding sphere
    ``(center, radius)`` (link frame) at ``pose_a``, the cloud at ``pose_b``; negative: the
    depth of the deepest point inside a part."""
    link_to_cloud = np.linalg.inv(np.asarray(pose_b, dtype=float)) @ np.asarray(pose_a, dtype=float)
    centre = link_to_cloud[:3, :3] @ center + link_to_cloud[:3, 3]
    near = cloud.balls.query_ball_point(centre, radius)
    depth = 0.0
    if near:
        rotation, offset = link_to_cloud[:3, :3], link_to_cloud[:3, 3]
        local = (cloud.points[np.asarray(near)] - offset) @ rotation  # Rᵀ (c − p): the link frame
        for part in parts:
            depth = max(depth, _depth_inside(part, local))
    if depth > 0.0:
        return -depth
    transform_a = _transform(np.asarray(pose_a, dtype=float))
    transform_b = _transform(np.asarray(pose_b, dtype=float))
    return min(float(coal.distance(part.mesh, transform_a, cloud.specks, transform_b, coal.DistanceRequest(),
                                   coal.DistanceResult())) for part in parts)


def _depth_inside(part: LinkSolid, points: NDArray[np.float64]) -> float:
    """The largest distance to the part's surface of the ``points`` (link frame) inside it;
    0 if none is (or the part has no inside)."""
    if part.solid is None:
        return 0.0
    in_hull = points[np.all(points @ part.planes[:3] <= part.planes[3], axis=1)]
    if len(in_hull) == 0:
        return 0.0
    inside = in_hull[np.abs(winding_numbers(part.solid, in_hull)) > 0.5]
    identity, dot = coal.Transform3s(), coal.Sphere(1e-9)
    return max((float(coal.distance(part.mesh, identity, dot, coal.Transform3s(np.eye(3), point),
                                    coal.DistanceRequest(), coal.DistanceResult())) for point in inside), default=0.0)


def winding_numbers(mesh: trimesh.Trimesh, points: NDArray[np.float64]) -> NDArray[np.float64]:
    """The winding number of a closed ``mesh`` about each of ``points`` (N, 3): ±1 inside, 0
    outside (the sign is the faces' orientation). The sum over the triangles ``(a, b, c)``,
    taken from the point, of their solid angles ``Ω = 2 atan2(a·(b×c), |a||b||c| + (a·b)|c|
    + (b·c)|a| + (c·a)|b|)`` over ``4π`` (Van Oosterom and Strackee, 1983)."""
    corners = np.asarray(mesh.triangles, dtype=float)[None] - points[:, None, None, :]  # (N, F, 3, 3)
    a, b, c = corners[:, :, 0], corners[:, :, 1], corners[:, :, 2]
    la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
    triple = np.einsum("nfi,nfi->nf", a, np.cross(b, c))
    below = (la * lb * lc + np.einsum("nfi,nfi->nf", a, b) * lc + np.einsum("nfi,nfi->nf", b, c) * la
             + np.einsum("nfi,nfi->nf", c, a) * lb)
    return np.sum(2.0 * np.arctan2(triple, below), axis=1) / (4.0 * np.pi)


def hull_planes(mesh: trimesh.Trimesh) -> NDArray[np.float64]:
    """(4, F) ``(n, b)`` of the faces of ``mesh``'s convex hull, one per column: ``nᵀx ≤ b``
    inside (1 µm slack)."""
    hull = mesh.convex_hull
    normals = np.asarray(hull.face_normals, dtype=float)
    offsets = np.einsum("ij,ij->i", normals, np.asarray(hull.triangles_center, dtype=float)) + 1e-6
    return np.ascontiguousarray(np.vstack([normals.T, offsets]))


def closed_solid(mesh: trimesh.Trimesh) -> trimesh.Trimesh | None:
    """``mesh`` with coincident vertices merged if that is watertight, else None."""
    merged = mesh.copy()
    merged.merge_vertices()
    return merged if merged.is_watertight else None


def _to_cloud(pose_a: NDArray[np.float64], pose_b: NDArray[np.float64],
              points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points (N, 3) of the link frame in the cloud frame."""
    world = points @ np.asarray(pose_a, dtype=float)[:3, :3].T + np.asarray(pose_a, dtype=float)[:3, 3]
    b = np.asarray(pose_b, dtype=float)
    return (world - b[:3, 3]) @ b[:3, :3]


def _transform(pose: NDArray[np.float64]) -> coal.Transform3s:
    return coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))
