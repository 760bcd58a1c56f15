"""Boolean contact of a robot's collision meshes with obstacles, with a security margin: a
planner's state validity on the meshes, far cheaper than their distances.

    free(q) ⇔ for every link l some joint moves and every obstacle k: d(link_l(q), k) > margin,
              and for every checked link pair (i, j): d(link_i(q), link_j(q)) > 0

decided by coal's ``collide`` with ``security_margin = margin`` [m], in three tiers per
(link, obstacle): the link's bounding sphere (centre ``x``, radius ``r``) apart from the
obstacle's bounding box (centre ``c``, axes ``R``, half extents ``h``, in which it lies) by
more than the margin, ``‖max(|Rᵀ(x − c)| − h, 0)‖ − r > margin``, tested for every pair at once
(free); the link's convex hull (which holds its mesh) clear of the obstacle by the margin
(free); else the link's triangles (BVH) against the obstacle's. A link pair is tested only
where the links' bounding spheres meet. An obstacle mesh is its triangles (BVH), a
primitive coal's exact shape. Surfaces only: a link wholly inside a closed obstacle is not
seen by the triangles: where a hull is touched and no triangle, the exact distance decides
(:func:`~dynfab.geometry.exact_collision.exact_distance`, which sees it). Point clouds are
not handled (:class:`ValueError`).

Measured on MBM's kitchen around development kitchen/0005's start (seed 1), 200
configurations, 3 mm: 2.99 ms a configuration against 31.1 ms for the exact distances at
load 6.5 (0.41 against 4.4 ms at load 1.4), the same answer on all 200
(``bench/bench_mesh_contact.py``). The bounding boxes tested at once and the links' coal
transforms made once per configuration (session 25) against a bounding sphere per pair
tested in turn, on the same machine at load 2: that bench 1.61 → 0.62 ms a configuration;
around moving-sphere bookshelf_thin/0089's start (``--seed 17``; 2000 configurations,
σ = 0.3 rad, margins 0, 3 and 6 mm) 2.7-3.0 → 0.39-0.47 ms (6.3-7.0×), the same answers.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import coal
import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.exact_collision import (MeshSet, Solid, exact_distance, placement_matrix,
                                             shape_geometry)
from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Plane, PointCloud, Shape, Sphere

from .mesh_collision import MeshCollisionModel, moving_part

__all__ = ["MeshContactCheck", "PlacedSolid"]


@dataclass(frozen=True, eq=False)
class PlacedSolid:
    """An obstacle as the check sees it.

    Attributes:
        geometry: its coal geometry (a mesh's :class:`MeshSet`, or a primitive), in its frame.
        pose: its pose (4, 4) [m].
        transform: the same pose as coal's.
        center: the centre of its bounding box, world frame [m].
        half: the box's half extents along the columns of ``pose``'s rotation [m] (infinite
            for a plane).
    """

    geometry: Solid
    pose: NDArray[np.float64]
    transform: coal.Transform3s
    center: NDArray[np.float64]
    half: NDArray[np.float64]


class MeshContactCheck:
    """``q ↦ free(q)`` of the module docstring.

    Attributes:
        model: The robot's mesh model (its pairs are the self-collision pairs checked).
        margin: Security margin [m] every moving link keeps from every obstacle.
        checks: Configurations checked so far [-].
    """

    def __init__(self, model: MeshCollisionModel, margin: float) -> None:
        if not np.isfinite(margin) or margin < 0.0:
            raise ValueError(f"margin: must be finite and >= 0, got {margin}")
        self.model = model
        self.margin = margin
        self.checks = 0
        moving = set(moving_part(model).links)
        self._moving = np.array([i for i, link in enumerate(model.links) if link in moving], dtype=int)
        self._link_centers = np.array([mesh.center for mesh in model.meshes], dtype=float).reshape(-1, 3)
        self._link_radii = np.array([mesh.radius for mesh in model.meshes], dtype=float)
        self._pairs = np.array(model.pairs, dtype=int).reshape(-1, 2)
        q = ca.SX.sym("q", model.kinematics.dof)
        stacked = ca.vertcat(*[model.kinematics.transform(q, link) for link in model.links])
        self._poses = ca.Function("link_poses", [q], [ca.reshape(stacked.T, 16 * len(model.links), 1)])
        self._obstacles: tuple[PlacedSolid, ...] = ()
        self._axes = np.zeros((0, 3, 3))
        self._centers = np.zeros((0, 3))
        self._halves = np.zeros((0, 3))
        self._request = coal.CollisionRequest()
        self._request.security_margin = margin
        self._touch = coal.CollisionRequest()

    def set_obstacles(self, obstacles: Sequence[object]) -> None:
        """Check against ``obstacles`` (each with ``shape`` and ``placement``, as
        :class:`~dynfab.motion.configuration_checker.PlacedObstacle`) from now on.

        Raises:
            ValueError: A point cloud among them (named by its index).
        """
        solids = []
        for k, obstacle in enumerate(obstacles):
            shape = obstacle.shape   # type: ignore[attr-defined]
            if isinstance(shape, PointCloud):
                raise ValueError(f"obstacles[{k}]: the mesh contact check does not take point clouds")
            pose = placement_matrix(obstacle.placement)   # type: ignore[attr-defined]
            offset, half = _bounding_box(shape)
            solids.append(PlacedSolid(shape_geometry(shape), pose, _transform(pose),
                                      pose[:3, :3] @ offset + pose[:3, 3], half))
        self._obstacles = tuple(solids)
        self._axes = np.array([solid.pose[:3, :3] for solid in solids]).reshape(-1, 3, 3)
        self._centers = np.array([solid.center for solid in solids]).reshape(-1, 3)
        self._halves = np.array([solid.half for solid in solids]).reshape(-1, 3)

    def link_poses(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """The poses of the model's links at ``q``, shape (L, 4, 4)."""
        flat = np.asarray(self._poses(np.asarray(q, dtype=float))).ravel()
        return flat.reshape(len(self.model.links), 4, 4)

    def free(self, q: NDArray[np.float64]) -> bool:
        """Whether ``q`` (n,) is free (module docstring)."""
        self.checks += 1
        poses = self.link_poses(q)
        centers = np.einsum("lij,lj->li", poses[:, :3, :3], self._link_centers) + poses[:, :3, 3]
        meshes = self.model.meshes
        transforms: dict[int, coal.Transform3s] = {}

        def transform(i: int) -> coal.Transform3s:
            if i not in transforms:
                transforms[i] = _transform(poses[i])
            return transforms[i]

        if self._obstacles:
            moving = self._moving
            local = np.einsum("kji,lkj->lki", self._axes, centers[moving, None, :] - self._centers[None])
            outside = np.maximum(np.abs(local) - self._halves[None], 0.0)
            gaps = np.linalg.norm(outside, axis=2) - self._link_radii[moving, None]
            for a, k in zip(*np.nonzero(gaps <= self.margin)):
                i, solid = int(moving[a]), self._obstacles[k]
                if self._touches(meshes[i], poses[i], transform(i), solid.geometry, solid.pose, solid.transform,
                                 self._request):
                    return False
        first, second = self._pairs[:, 0], self._pairs[:, 1]
        near = (np.linalg.norm(centers[first] - centers[second], axis=1)
                <= self._link_radii[first] + self._link_radii[second])
        return not any(self._touches(meshes[i], poses[i], transform(i), meshes[j], poses[j], transform(j), self._touch)
                       for i, j in self._pairs[near].tolist())

    def motion_free(self, a: NDArray[np.float64], b: NDArray[np.float64], step: float) -> bool:
        """Whether every configuration of the straight motion from ``a`` to ``b``, at most
        ``step`` [rad] apart (``b`` included, ``a`` not), is free."""
        if not step > 0.0:
            raise ValueError(f"step: must be > 0, got {step}")
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        return all(self.free(a + (b - a) * k / count) for k in range(1, count + 1))

    @staticmethod
    def _touches(link: MeshSet, pose: NDArray[np.float64], transform: coal.Transform3s, solid: Solid,
                 other: NDArray[np.float64], placed: coal.Transform3s, request: coal.CollisionRequest) -> bool:
        """Whether ``link``'s meshes at ``pose`` (coal's ``transform``) come within the
        request's margin of ``solid`` at ``other`` (``placed``): clear if every hull is;
        touching if triangles are; where a hull is touched and no triangle, the exact
        distance decides (one may lie wholly inside the other:
        :func:`~dynfab.geometry.exact_collision.exact_distance`)."""
        parts = tuple(part.mesh for part in solid.parts) if isinstance(solid, MeshSet) else (solid,)
        hull_touched = False
        for part in link.parts:
            for geometry in parts:
                if coal.collide(part.hull, transform, geometry, placed, request, coal.CollisionResult()):
                    hull_touched = True
                    if coal.collide(part.mesh, transform, geometry, placed, request, coal.CollisionResult()):
                        return True
        return hull_touched and exact_distance(link, pose, solid, other) <= request.security_margin


def _transform(pose: NDArray[np.float64]) -> coal.Transform3s:
    return coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))


def _bounding_box(shape: Shape) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The centre (3,) and half extents (3,) [m] of a box in ``shape``'s frame, along its
    axes, that holds it (infinite for a plane, whose half-space no box holds)."""
    if isinstance(shape, Mesh):
        low, high = shape.vertices.min(axis=0), shape.vertices.max(axis=0)
        return (low + high) / 2.0, (high - low) / 2.0
    if isinstance(shape, Box):
        return np.zeros(3), np.asarray(shape.size, dtype=float) / 2.0
    if isinstance(shape, Sphere):
        return np.zeros(3), np.full(3, shape.radius)
    if isinstance(shape, Cylinder):
        return np.zeros(3), np.array([shape.radius, shape.radius, shape.length / 2.0])
    if isinstance(shape, Capsule):
        return np.zeros(3), np.array([shape.radius, shape.radius, shape.length / 2.0 + shape.radius])
    if isinstance(shape, Plane):
        return np.zeros(3), np.full(3, np.inf)
    raise TypeError(f"unsupported obstacle shape {type(shape).__name__}")
