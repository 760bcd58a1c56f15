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
(``g`` smaller); written as the first slots are: point ``c + δ u``, normal ``u`` (``+z`` where
none is kept), velocity 0, active 1 where one is kept [m, -, m/s]. Each kept point is a kept
point of the cloud, so its clearance ``‖x − c‖ − δ`` is a lower bound of the distance to a
measured point.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.cloud_far_side import FAR_SIDE_ANGLE, FAR_SIDE_SHIFTS

__all__ = ["beyond", "far_side_function"]

#: Shorter offsets than this [m] give no direction (the candidate is not kept).
_TINY = 1e-12


def beyond(centres: NDArray[np.float64], points: NDArray[np.float64], active: NDArray[np.float64],
           reach: NDArray[np.float64], lowering: float) -> list[tuple[NDArray[np.float64], float]]:
    """Per shift ``s``: the query points ``x + s (x − p)`` (K, 3) [m] and the KD-tree's
    distance bound ``s · max ‖x − p‖ + max reach + δ`` [m] over the active spheres
    (``centres`` x, first-slot ``points`` p, both (K, 3); ``active`` (K,); ``reach`` (K,)):
    no candidate the rule keeps lies farther from its query point (module docstring)."""
    offsets = centres - points
    rows = active > 0.5
    longest = float(np.sqrt(np.max(np.einsum("ij,ij->i", offsets[rows], offsets[rows])))) if rows.any() else 0.0
    top = float(reach.max()) + lowering
    return [(centres + shift * offsets, shift * longest + top) for shift in FAR_SIDE_SHIFTS]


def far_side_function(count: int, name: str) -> ca.Function:
    """``(z, n_1, active, far) ↦ (points, normals, velocities, active)`` of the far-side slots of
    ``count`` spheres (module docstring): ``z = [x (3K), reach (K), c (3K), f (K), δ]`` the
    per-tick writer's input, ``n_1`` (3K) and ``active`` (K) its first slots, ``far`` the
    candidates and found flags of each shift in turn, ``[c_s (3K), f_s (K)]``."""
    z = ca.SX.sym("z", 8 * count + 1)
    first_normals = ca.SX.sym("n", 3 * count)
    first_active = ca.SX.sym("a", count)
    far = ca.SX.sym("far", 4 * count * len(FAR_SIDE_SHIFTS))
    delta = z[8 * count]
    up = ca.DM([0.0, 0.0, 1.0])
    turn = math.cos(FAR_SIDE_ANGLE)
    points, normals, actives = [], [], []
    for i in range(count):
        x, reach = z[3 * i:3 * i + 3], z[3 * count + i]
        normal_1 = first_normals[3 * i:3 * i + 3]
        kept, gap, point, normal = ca.SX(0), ca.SX(0), ca.SX.zeros(3), up
        for s in range(len(FAR_SIDE_SHIFTS)):
            block = far[4 * count * s:4 * count * (s + 1)]
            candidate, found = block[3 * i:3 * i + 3], block[3 * count + i]
            offset = x - candidate
            length = ca.norm_2(offset)
            unit = offset / ca.fmax(length, _TINY)
            this_gap = length - delta
            keep = (first_active[i] * found * (ca.dot(unit, normal_1) < turn) * (length > _TINY)
                    * (this_gap <= reach))
            take = keep * (1 - kept + kept * (this_gap < gap))
            gap = ca.if_else(take > 0.5, this_gap, gap)
            point = ca.if_else(take > 0.5, candidate + delta * unit, point)
            normal = ca.if_else(take > 0.5, unit, normal)
            kept = ca.fmax(kept, keep)
        points.append(kept * point)
        normals.append(normal)
        actives.append(kept)
    return ca.Function(name, [z, first_normals, first_active, far],
                       [ca.vertcat(*points), ca.vertcat(*normals), ca.SX.zeros(3 * count), ca.vertcat(*actives)])
