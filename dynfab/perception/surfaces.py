"""Feeding the nearest-point leaf: each tick, the nearest surface point to each robot sphere.

The surfaces are meshes and point clouds (:class:`~dynfab.geometry.point_cloud.PointCloud`,
world frame, static: a KD-tree query per sphere, the clearance lowered by the cloud's voxel
half-diagonal so that it never exceeds the distance to a measured point).

For the configuration ``q`` the robot's sphere centres ``p_i`` are computed (forward
kinematics), brought into each mesh's frame, and the nearest points within
``reach`` of it are found (``range + r_i`` at rest, more when it moves: below) (:func:`~dynfab.geometry.mesh_distance.nearest_on_mesh`,
whose bounding-box test skips the meshes out of reach). One surface per sphere is written,
the one the leaf acts on most: the least clearance left after a stop,
``b = d − min(n · (ṗ_i − v_s), 0)² / (2 a_b)`` (:func:`~dynfab.geometry.cloud_far_side.braking_clearance`,
``v_s`` the surface's velocity; the nearest without braking or ``q̇``). Ranked by ``d`` alone,
a hand at 1.5 m/s toward a cupboard door 15 cm off kept a surface 10 cm beside it and met
the door at 10 cm, too fast to stop (MBM kitchen seed 12/0010 on the meshes' plan, session 21). Its point,
outward normal and velocity (the mesh's translation velocity: meshes move
without turning, as shapes do) are written into the leaf
(:class:`~dynfab.fabric.leaves.surface_points.NearestSurfaceAvoidance`), and ``active`` is 1
where a point was found. A sphere with nothing in reach is left inactive: beyond its range the
barrier is zero anyway.

**A braking leaf reaches farther into a cloud.** With braking (``a_b``, the leaf's
:class:`~dynfab.fabric.leaves.barrier.Barrier`) the leaf's energy acts on the clearance left
after a stop, ``x_b = x − δ_o − min(ẋ, 0)²/(2 a_b)``, and is nonzero while ``x_b`` is below
its range ``r`` (``δ_o`` its offset): a sphere approaching at ``|ẋ| ≤ ‖ṗ_i‖`` needs the
surfaces out to

    reach_i(q̇) = r + δ_o + r_i + ‖ṗ_i‖² / (2 a_b)          [m],   ṗ_i = J_{p_i}(q) q̇,

or the leaf meets a surface only once it is within ``r`` and too fast to stop (a link 10 mm
into a table at 1 m/s, MotionBenchMaker table_under_pick/0036 as a cloud: the stop from 1 m/s
at 4 m/s² takes 12.5 cm, the range is 10 cm; MBM kitchen seed 12/0010 on the meshes' plan
(session 21): the hand at 1.2 m/s saw a cupboard door 11 cm off and went 52 mm into it). A
shape leaf reads its distance at any range; so, given ``q̇``, the meshes' and the clouds'
nearest points are looked for within ``reach_i(q̇)``.

A surface may carry an *allowance* ``a ≥ 0`` [m] (guidance gives one near a grasp goal the
robot's spheres overlap, :mod:`dynfab.motion.guided_fabric`): its nearest point is written
``a`` farther along the inward normal, ``c' = c − a n``, so the leaf sees the clearance
``nᵀ(p − c') − r = d − r + a`` and lets the sphere enter the surface by ``a``; surfaces are
compared and reached by that clearance (``d + a``, within ``reach``). With ``a = 0``
nothing changes.

Cost: one coal query per (sphere, mesh) in reach, 2-30 µs each for meshes of 10-10⁴
triangles, plus the forward kinematics.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance
from dynfab.fabric.parameters import LeafViews
from dynfab.geometry.cloud_far_side import SphereMotion, braking_clearance, far_side_points
from dynfab.geometry.mesh_distance import NearestPoints, nearest_on_mesh
from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Placement
from dynfab.robots.robot import Robot

__all__ = ["PlacedMesh", "SurfaceFeed", "surface_clearance"]


@dataclass(frozen=True)
class PlacedMesh:
    """A mesh at one instant.

    Attributes:
        mesh: The mesh, in its own frame.
        placement: Where its frame is.
        velocity: Its frame's translation velocity (3,) [m/s].
        allowance: How far [m] the leaf lets spheres enter it (module docstring).
    """

    mesh: Mesh
    placement: Placement
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    allowance: float = 0.0


class SurfaceFeed:
    """Writes a :class:`NearestSurfaceAvoidance` leaf's parameters (module docstring).

    Attributes:
        leaf: The leaf fed.
        reach: Per sphere of the leaf, how far from it surfaces are looked for [m].
    """

    def __init__(self, robot: Robot, leaf: NearestSurfaceAvoidance, views: LeafViews) -> None:
        self.leaf = leaf
        self._views = views
        radii = np.asarray(robot.sphere_radii, dtype=float)[list(leaf.spheres)]
        self.reach = leaf.barrier.horizon + leaf.barrier.offset + radii
        self._radii = radii
        self._braking = leaf.barrier.braking
        q = ca.SX.sym("q", robot.kinematics.dof)
        qdot = ca.SX.sym("qdot", robot.kinematics.dof)
        centres = robot.sphere_centers(q)[list(leaf.spheres), :] if leaf.spheres else ca.SX(0, 3)
        self._centres = ca.Function("sphere_centres", [q], [centres])
        velocities = ca.reshape(ca.jtimes(ca.vec(centres), q, qdot), centres.shape)
        self._velocities = ca.Function("sphere_velocities", [q, qdot], [velocities])

    def sphere_velocities(self, q: NDArray[np.float64], qdot: NDArray[np.float64] | None
                          ) -> NDArray[np.float64] | None:
        """The leaf's sphere centres' velocities ``ṗ_i = J_i(q) q̇`` (k, 3) [m/s] where they
        matter (a braking leaf, ``q̇`` given), else None."""
        if qdot is None or self._braking is None or not self.leaf.spheres:
            return None
        return np.asarray(self._velocities(q, qdot), dtype=float).reshape(-1, 3)

    def braking_reach(self, velocities: NDArray[np.float64] | None) -> NDArray[np.float64]:
        """Per sphere, how far from its centre surfaces are looked for [m]:
        ``reach_i + ‖ṗ_i‖²/(2 a_b)`` given the spheres' ``velocities``
        (:meth:`sphere_velocities`), else ``reach_i`` (module docstring)."""
        if velocities is None:
            return self.reach
        assert self._braking is not None
        return self.reach + np.sum(velocities**2, axis=1) / (2.0 * self._braking)

    def write(self, q: NDArray[np.float64], meshes: Sequence[PlacedMesh], clouds: Sequence[PointCloud] = (),
              cloud_allowances: Sequence[float] = (), qdot: NDArray[np.float64] | None = None) -> None:
        """Find and write the nearest surface point of every sphere at configuration ``q``
        among ``meshes`` and ``clouds`` (``cloud_allowances``: one per cloud [m], zeros if
        empty; ``qdot`` [rad/s]: the reach grows by each sphere's stopping distance,
        :meth:`braking_reach`; module docstring)."""
        if not self.leaf.spheres:
            return
        centres = np.asarray(self._centres(q), dtype=float).reshape(-1, 3)
        count = len(centres)
        sphere_velocities = self.sphere_velocities(q, qdot) if meshes or clouds or self.leaf.far_side else None
        reach = self.braking_reach(sphere_velocities)
        motion = None if sphere_velocities is None else SphereMotion(sphere_velocities, self._radii, self._braking)
        best = np.full(count, np.inf)   # the rank (module docstring) of the surface written so far [m]
        points, normals, velocities = np.zeros((count, 3)), np.zeros((count, 3)), np.zeros((count, 3))
        for placed in meshes:
            rotation = placed.placement.rotation
            local = nearest_on_mesh(placed.mesh, placed.placement.to_local(centres),
                                    max_distance=float(reach.max()) - placed.allowance,
                                    signed_within=float(self._radii.max()))
            found = NearestPoints(local.points @ rotation.T + np.asarray(placed.placement.position),
                                  local.normals @ rotation.T, local.distances, local.found)   # world frame
            written = _keep_nearer(found, placed.allowance, reach, best, points, normals,
                                   _relative(motion, placed.velocity))
            velocities[written] = placed.velocity
        allowances = list(cloud_allowances) or [0.0] * len(clouds)
        for cloud, allowance in zip(clouds, allowances, strict=True):
            found = cloud.nearest(centres, max_distance=float(reach.max()) - allowance)
            velocities[_keep_nearer(found, allowance, reach, best, points, normals, motion)] = 0.0
        active = np.isfinite(best)
        normals[~active] = (0.0, 0.0, 1.0)
        if self.leaf.far_side:
            far_points, far_normals, far_active = self._far_side(centres, points, normals, active, clouds,
                                                                 allowances, reach, motion)
            points, normals = np.concatenate([points, far_points]), np.concatenate([normals, far_normals])
            velocities = np.concatenate([velocities, np.zeros_like(velocities)])
            active = np.concatenate([active, far_active])
        self._views["points"] = points
        self._views["normals"] = normals
        self._views["velocities"] = velocities
        self._views["active"] = active.astype(float)

    @staticmethod
    def _far_side(centres: NDArray[np.float64], points: NDArray[np.float64], normals: NDArray[np.float64],
                  active: NDArray[np.bool_], clouds: Sequence[PointCloud], allowances: Sequence[float],
                  reach: NDArray[np.float64], motion: SphereMotion | None
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
        """The far-side slots (:mod:`dynfab.geometry.cloud_far_side`): per sphere the far-side
        point of the clouds with the least clearance after a stop (the nearest without the
        spheres' ``motion``), less each cloud's allowance as the first slots are, its normal
        and whether there is one (static: velocity 0)."""
        count = len(centres)
        best = np.full(count, np.inf)
        far_points, far_normals = np.zeros((count, 3)), np.tile((0.0, 0.0, 1.0), (count, 1))
        for cloud, allowance in zip(clouds, allowances, strict=True):
            found = far_side_points(cloud, centres, points, normals, active, reach - allowance, motion)  # within reach
            rank = braking_clearance(found.distances + allowance, found.normals, motion)
            better = found.found & (rank < best)
            best[better] = rank[better]
            far_points[better] = found.points[better] - allowance * found.normals[better]
            far_normals[better] = found.normals[better]
        return far_points, far_normals, np.isfinite(best)


def _relative(motion: SphereMotion | None, velocity: tuple[float, float, float]) -> SphereMotion | None:
    """The spheres' ``motion`` relative to a surface moving at ``velocity`` (3,) [m/s]."""
    if motion is None or not any(velocity):
        return motion
    return SphereMotion(motion.velocities - np.asarray(velocity, dtype=float), motion.radii, motion.braking)


def _keep_nearer(found: NearestPoints, allowance: float, reach: NDArray[np.float64] | float,
                 best: NDArray[np.float64], points: NDArray[np.float64], normals: NDArray[np.float64],
                 motion: SphereMotion | None) -> NDArray[np.bool_]:
    """Write a surface's points ``found`` (world frame) where they rank before ``best``
    (module docstring: with the spheres' ``motion``, by the clearance left after a stop) and
    lie within ``reach`` [m], seen ``allowance`` [m] farther (``c' = c − a n``): into
    ``best``, ``points`` and ``normals``; the rows written."""
    seen = found.distances + allowance
    rank = braking_clearance(seen, found.normals, motion)
    closer = found.found & (rank < best) & (seen <= reach)
    best[closer] = rank[closer]
    points[closer] = found.points[closer] - allowance * found.normals[closer]
    normals[closer] = found.normals[closer]
    return closer


def surface_clearance(centres: NDArray[np.float64], radii: NDArray[np.float64], surface: Mesh | PointCloud,
                      placement: Placement) -> float:
    """The least clearance ``d_i − r_i`` [m] the nearest-point leaf sees between spheres
    (centres (K, 3), world frame, radii (K,)) and one surface without allowance: the signed
    mesh distance (``surface`` placed at ``placement``), or a cloud's lowered one (world
    frame, ``placement`` unused); ``inf`` without spheres."""
    if not len(centres):
        return float("inf")
    if isinstance(surface, PointCloud):
        found = surface.nearest(centres)
    else:
        found = nearest_on_mesh(surface, placement.to_local(centres), signed_within=float(np.max(radii)))
    return float(np.min(np.where(found.found, found.distances - radii, np.inf)))
