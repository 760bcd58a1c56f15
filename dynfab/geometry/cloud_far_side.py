"""A second point of a cloud per query point: one on another side than its nearest point.

One nearest point per robot sphere stands for one surface. A sphere between two surfaces of a
cloud (a hand between a cage's bar and its side wall) then sees only the nearer one, and meets
the other only when that becomes the nearer, possibly too close and too fast to brake for
(MotionBenchMaker cage/0038 as a cloud: a fingertip at 0.9 m/s found the wall 65 mm away and
went 34 mm into it). Primitives do not have this: each box has its own slot.

For a query point ``x`` whose nearest surface point is ``p`` (the point the leaf was given,
``‖x − p‖ = g_1``), the cloud is queried beyond ``x``, away from ``p``:

    x'_α = x + α (x − p),   α ∈ FAR_SIDE_SHIFTS = (1/4, 1),

where ``p``'s surface is ``(1 + α) g_1`` away, so a surface of another side within about that
of ``x`` is nearer (at ``α = 1``, ``x'`` is the mirror image of ``p`` through ``x``). The
small shift finds a side that is as near as ``p``'s nearly at its own nearest point (a wall at
``w`` from ``x``, perpendicular to ``p``'s side: found while ``w < 1.25 g_1``, ``√(w² +
(g_1/4)²) − w`` farther than its nearest point); the mirror finds farther ones, less exactly.
On a flat surface below ``x`` the candidate is ``p``'s own neighbourhood again (the foot of
``x'``), so a candidate ``c`` is kept only where its direction from ``x`` turns from the
first one's by more than :data:`FAR_SIDE_ANGLE`, and the nearest kept one to ``x`` wins:

    n = (x − c)/‖x − c‖,   n · n_1 < cos(FAR_SIDE_ANGLE),   ‖x − c‖ − δ ≤ reach,

and written as the nearest points are, ``c + δ n`` (δ the voxel half-diagonal): its clearance
``‖x − c‖ − δ`` is a lower bound of the distance to a measured point, as the first one's is.
Any kept point gives a lower bound of the distance to the cloud, so the second slot never
overstates a clearance; it adds a second barrier where two sides are near.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.mesh_distance import NearestPoints
from dynfab.geometry.point_cloud import PointCloud

__all__ = ["FAR_SIDE_ANGLE", "FAR_SIDE_SHIFTS", "far_side_points"]

#: How far beyond the query point the cloud is queried, in multiples of ``x − p`` [-]
#: (chosen a priori, not tuned; module docstring).
FAR_SIDE_SHIFTS = (0.25, 1.0)
#: Least angle [rad] between the directions from a query point to its nearest point and to
#: its far-side point (45°, chosen a priori, not tuned: a concave corner of two faces gives
#: about 90°, one flat or gently curved face about 0°).
FAR_SIDE_ANGLE = math.pi / 4


def far_side_points(cloud: PointCloud, centres: NDArray[np.float64], nearest: NDArray[np.float64],
                    normals: NDArray[np.float64], has_nearest: NDArray[np.bool_],
                    reach: NDArray[np.float64]) -> NearestPoints:
    """Per query point ``x`` (``centres`` (N, 3) [m]) with a nearest surface point (``nearest``
    (N, 3) [m], its unit direction to ``x`` in ``normals`` (N, 3), where ``has_nearest``):
    the kept point of ``cloud`` on its far side moved toward ``x`` by ``δ``, the direction
    to ``x``, the distance ``‖x − c‖ − δ`` [m] and whether one was found within ``reach``
    (N,) [m] (module docstring)."""
    x = np.asarray(centres, dtype=float).reshape(-1, 3)
    count = len(x)
    points, directions = np.full((count, 3), np.nan), np.full((count, 3), np.nan)
    distances = np.full(count, np.inf)
    rows = np.flatnonzero(has_nearest)
    if cloud.empty or len(rows) == 0:
        return NearestPoints(points, directions, distances, np.zeros(count, dtype=bool))
    for shift in FAR_SIDE_SHIFTS:
        _closer_far_side(cloud, x, nearest, normals, rows, reach, shift, points, directions, distances)
    return NearestPoints(points, directions, distances, np.isfinite(distances))


def _closer_far_side(cloud: PointCloud, x: NDArray[np.float64], nearest: NDArray[np.float64],
                     normals: NDArray[np.float64], rows: NDArray[np.intp], reach: NDArray[np.float64], shift: float,
                     points: NDArray[np.float64], directions: NDArray[np.float64],
                     distances: NDArray[np.float64]) -> None:
    """The candidates of one query beyond ``x[rows]`` (``x + shift (x − p)``), written into
    ``points``, ``directions`` and ``distances`` where they are kept and nearer than what is
    there (module docstring)."""
    beyond = x[rows] + shift * (x[rows] - nearest[rows])
    bound = float(np.max(shift * np.linalg.norm(x[rows] - nearest[rows], axis=1) + reach[rows])) + cloud.lowering
    gaps, index = cloud.tree.query(beyond, distance_upper_bound=bound)
    hit = np.isfinite(gaps)
    rows, index = rows[hit], index[hit]
    candidates = cloud.points[index]
    offsets = x[rows] - candidates
    lengths = np.linalg.norm(offsets, axis=1)
    unit = offsets / np.maximum(lengths, 1e-12)[:, None]
    turned = np.einsum("ij,ij->i", unit, normals[rows]) < math.cos(FAR_SIDE_ANGLE)
    gap = lengths - cloud.lowering
    keep = turned & (lengths > 1e-12) & (gap <= reach[rows]) & (gap < distances[rows])
    rows, unit, gap, candidates = rows[keep], unit[keep], gap[keep], candidates[keep]
    points[rows] = candidates + cloud.lowering * unit
    directions[rows] = unit
    distances[rows] = gap
