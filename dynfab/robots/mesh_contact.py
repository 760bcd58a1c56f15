"""Boolean contact of a robot's collision meshes with obstacles, with a security margin: a
planner's state validity on the meshes, far cheaper than their distances.

    free(q) ⇔ for every link l some joint moves and every obstacle k: d(link_l(q), k) > margin,
              and for every checked link pair (i, j): d(link_i(q), link_j(q)) > 0

decided by coal's ``collide`` with ``security_margin = margin`` [m], in three tiers per
(link, obstacle): the bounding spheres apart by more than the margin (free); the link's
convex hull (which holds its mesh) clear of the obstacle by the margin (free); else the
link's triangles (BVH) against the obstacle's. An obstacle mesh is its triangles (BVH), a
primitive coal's exact shape. Surfaces only: a link wholly inside a closed obstacle is not
seen by the triangles: where a hull is touched and no triangle, the exact distance decides
(:func:`~dynfab.geometry.exact_collision.exact_distance`, which sees it). Point clouds are
not handled (:class:`ValueError`).

Measured on MBM's kitchen around development kitchen/0005's start (seed 1), 200
configurations, 3 mm: 2.99 ms a configuration against 31.1 ms for the exact distances at
load 6.5 (0.41 against 4.4 ms at load 1.4), the same answer on all 200
(``bench/bench_mesh_contact.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import coal
import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.exact_collision import (MeshSet, Solid, exact_distance, placement_matrix, shape_bounding_radius,
                                             shape_geometry)
from dynfab.geometry.shapes import PointCloud

from .mesh_collision import MeshCollisionModel, moving_part

__all__ = ["MeshContactCheck", "PlacedSolid"]


@dataclass(frozen=True, eq=False)
class PlacedSolid:
    """An obstacle as the check sees it.

    Attributes:
        geometry: its coal geometry (a mesh's :class:`MeshSet`, or a primitive), in its frame.
        pose: its pose (4, 4) [m].
        center: the centre of its bounding sphere, world frame [m].
        radius: its bounding sphere's radius [m].
    """

    geometry: Solid
    pose: NDArray[np.float64]
    center: NDArray[np.float64]
    radius: float


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
        self._moving = tuple(i for i, link in enumerate(model.links) if link in moving)
        q = ca.SX.sym("q", model.kinematics.dof)
        stacked = ca.vertcat(*[model.kinematics.transform(q, link) for link in model.links])
        self._poses = ca.Function("link_poses", [q], [ca.reshape(stacked.T, 16 * len(model.links), 1)])
        self._obstacles: tuple[PlacedSolid, ...] = ()
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
            geometry = shape_geometry(shape)
            pose = placement_matrix(obstacle.placement)   # type: ignore[attr-defined]
            if isinstance(geometry, MeshSet):
                center, radius = pose[:3, :3] @ geometry.center + pose[:3, 3], geometry.radius
            else:
                center, radius = pose[:3, 3], shape_bounding_radius(shape)
            solids.append(PlacedSolid(geometry, pose, center, radius))
        self._obstacles = tuple(solids)

    def link_poses(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """The poses of the model's links at ``q``, shape (L, 4, 4)."""
        flat = np.asarray(self._poses(np.asarray(q, dtype=float))).ravel()
        return flat.reshape(len(self.model.links), 4, 4)

    def free(self, q: NDArray[np.float64]) -> bool:
        """Whether ``q`` (n,) is free (module docstring)."""
        self.checks += 1
        poses = self.link_poses(q)
        meshes = self.model.meshes
        for i in self._moving:
            link = meshes[i]
            center = poses[i, :3, :3] @ link.center + poses[i, :3, 3]
            for solid in self._obstacles:
                if np.linalg.norm(center - solid.center) - link.radius - solid.radius > self.margin:
                    continue
                if self._touches(link, poses[i], solid.geometry, solid.pose, self._request):
                    return False
        return not any(self._touches(meshes[i], poses[i], meshes[j], poses[j], self._touch)
                       for i, j in self.model.pairs)

    def motion_free(self, a: NDArray[np.float64], b: NDArray[np.float64], step: float) -> bool:
        """Whether every configuration of the straight motion from ``a`` to ``b``, at most
        ``step`` [rad] apart (``b`` included, ``a`` not), is free."""
        if not step > 0.0:
            raise ValueError(f"step: must be > 0, got {step}")
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        return all(self.free(a + (b - a) * k / count) for k in range(1, count + 1))

    @staticmethod
    def _touches(link: MeshSet, pose: NDArray[np.float64], solid: Solid, other: NDArray[np.float64],
                 request: coal.CollisionRequest) -> bool:
        """Whether ``link``'s meshes at ``pose`` come within the request's margin of
        ``solid`` at ``other``: clear if every hull is; touching if triangles are; where a
        hull is touched and no triangle, the exact distance decides (one may lie wholly
        inside the other: :func:`~dynfab.geometry.exact_collision.exact_distance`)."""
        transform, placed = _transform(pose), _transform(other)
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
