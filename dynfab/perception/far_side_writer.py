"""The far-side slots of the per-tick point-cloud writer: per sphere a second point of a cloud,
on another side than its nearest point, chosen in one compiled function.

The same rule as :func:`~dynfab.geometry.cloud_far_side.far_side_points` (which the
scenario's :class:`~dynfab.perception.surfaces.SurfaceFeed` uses), split around the KD-tree
queries so that the per-tick writer (:mod:`dynfab.perception.nearest_cloud_points`) needs no
per-sphere Python: for a sphere centre ``x`` whose first slot holds the point ``p`` (normal
``n_1``, ``active``), the cloud is queried at ``x'_s = x + s (x − p)`` for each shift ``s`` of
:data:`~dynfab.geometry.cloud_far_side.FAR_SIDE_SHIFTS` (:func:`beyond`), giving candidates
``c_s`` (found or not, ``f_s``); then, with ``u_s = (x − c_s)/‖x − c_s‖`` and ``g_s = ‖x −
c_s‖ − δ`` [m],

    keep_s = active · f_s · [u_s · n_1 < cos(FAR_SIDE_ANGLE)] · [‖x − c_s‖ > 10⁻¹²] · [g_s ≤ reach],

the candidate of the first shift if kept, replaced by a later one kept and strictly nearer
(``g`` smaller). With a braking leaf (``a_b``) the sphere velocities ``v`` (3K) are an input
too: the cloud is also queried where each sphere would stop, ``x_s = x + v ‖v‖/(2 a_b)``, its
candidate kept only where ``dist(c, [x, x_s]) − δ < r_i`` (the sphere's radius), and "nearer" means a
smaller clearance after a stop, ``g − min(u · v, 0)²/(2 a_b)``
(:func:`~dynfab.geometry.cloud_far_side.braking_clearance`). Written as the first slots are: point ``c + δ u``, normal ``u`` (``+z`` where
none is kept), velocity 0, active 1 where one is kept [m, -, m/s]. Each kept point is a kept
point of the cloud, so its clearance ``‖x − c‖ − δ`` is a lower bound of the distance to a
measured point.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.cloud_far_side import FAR_SIDE_ANGLE, FAR_SIDE_SHIFTS, stopping_points

__all__ = ["beyond", "far_side_function", "query_count"]

#: Shorter offsets than this [m] give no direction (the candidate is not kept).
_TINY = 1e-12


def beyond(centres: NDArray[np.float64], points: NDArray[np.float64], active: NDArray[np.float64],
           reach: NDArray[np.float64], lowering: float, velocities: NDArray[np.float64] | None = None,
           braking: float | None = None) -> list[tuple[NDArray[np.float64], float]]:
    """Per shift ``s``: the query points ``x + s (x − p)`` (K, 3) [m] and the KD-tree's
    distance bound ``s · max ‖x − p‖ + max reach + δ`` [m] over the active spheres
    (``centres`` x, first-slot ``points`` p, both (K, 3); ``active`` (K,); ``reach`` (K,)):
    no candidate the rule keeps lies farther from its query point (module docstring). With
    ``velocities`` (K, 3) [m/s] and ``braking`` [m/s²], last, the stopping points and their
    bound ``max ‖x_s − x‖ + max reach + δ``."""
    offsets = centres - points
    rows = active > 0.5
    longest = float(np.sqrt(np.max(np.einsum("ij,ij->i", offsets[rows], offsets[rows])))) if rows.any() else 0.0
    top = float(reach.max()) + lowering
    queries = [(centres + shift * offsets, shift * longest + top) for shift in FAR_SIDE_SHIFTS]
    if velocities is not None and braking is not None:
        stops = stopping_points(centres, velocities, braking)
        ahead = np.linalg.norm(stops - centres, axis=1)
        queries.append((stops, float(np.max(ahead[rows])) + top if rows.any() else top))
    return queries


def query_count(braking: float | None) -> int:
    """How many far-side queries a leaf braking at ``braking`` [m/s²] (None: not braking)
    makes per sphere: the shifts, and the stopping point when braking."""
    return len(FAR_SIDE_SHIFTS) + (braking is not None)


def far_side_function(radii: NDArray[np.float64], name: str, braking: float | None = None) -> ca.Function:
    """``(z, n_1, active, far, v) ↦ (points, normals, velocities, active)`` of the far-side
    slots of ``K = len(radii)`` spheres of these radii [m] (module docstring): ``z = [x (3K),
    reach (K), c (3K), f (K), δ]`` the per-tick writer's input, ``n_1`` (3K) and ``active`` (K)
    its first slots, ``far`` the candidates and found flags of each query in turn
    (:func:`query_count`), ``[c_s (3K), f_s (K)]``, and ``v`` (3K) the sphere velocities [m/s]
    (unused without ``braking`` [m/s²])."""
    count = len(radii)
    z = ca.SX.sym("z", 8 * count + 1)
    first_normals = ca.SX.sym("n", 3 * count)
    first_active = ca.SX.sym("a", count)
    queries = query_count(braking)
    far = ca.SX.sym("far", 4 * count * queries)
    sphere_velocities = ca.SX.sym("v", 3 * count)
    delta = z[8 * count]
    up = ca.DM([0.0, 0.0, 1.0])
    turn = math.cos(FAR_SIDE_ANGLE)
    points, normals, actives = [], [], []
    for i in range(count):
        x, reach = z[3 * i:3 * i + 3], z[3 * count + i]
        normal_1 = first_normals[3 * i:3 * i + 3]
        velocity = sphere_velocities[3 * i:3 * i + 3]
        stop = x + velocity * ca.norm_2(velocity) / (2.0 * braking) if braking is not None else x
        kept, best, point, normal = ca.SX(0), ca.SX(0), ca.SX.zeros(3), up
        for s in range(queries):
            block = far[4 * count * s:4 * count * (s + 1)]
            candidate, found = block[3 * i:3 * i + 3], block[3 * count + i]
            offset = x - candidate
            length = ca.norm_2(offset)
            unit = offset / ca.fmax(length, _TINY)
            this_gap = length - delta
            rank = this_gap
            if braking is not None:
                rank = this_gap - ca.fmin(ca.dot(unit, velocity), 0.0) ** 2 / (2.0 * braking)
            keep = (first_active[i] * found * (ca.dot(unit, normal_1) < turn) * (length > _TINY)
                    * (this_gap <= reach))
            if s == len(FAR_SIDE_SHIFTS):   # the stopping point's candidate: only one the stopped sphere touches
                along = stop - x
                t = ca.fmin(ca.fmax(ca.dot(candidate - x, along) / ca.fmax(ca.dot(along, along), 1e-24), 0.0), 1.0)
                keep = keep * (ca.norm_2(x + t * along - candidate) - delta < float(radii[i]))
            take = keep * (1 - kept + kept * (rank < best))
            best = ca.if_else(take > 0.5, rank, best)
            point = ca.if_else(take > 0.5, candidate + delta * unit, point)
            normal = ca.if_else(take > 0.5, unit, normal)
            kept = ca.fmax(kept, keep)
        points.append(kept * point)
        normals.append(normal)
        actives.append(kept)
    return ca.Function(name, [z, first_normals, first_active, far, sphere_velocities],
                       [ca.vertcat(*points), ca.vertcat(*normals), ca.SX.zeros(3 * count), ca.vertcat(*actives)])
