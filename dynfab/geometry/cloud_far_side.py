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

**Moving spheres: the surface ahead.** A braking leaf (deceleration ``a_b``) acts on the
clearance left after a stop. Given the sphere's velocity ``v`` [m/s] and radius ``r``
(:class:`SphereMotion`), the cloud is queried a third time, where the sphere would stop,

    x_s = x + v ‖v‖ / (2 a_b),

and its answer ``c`` is a candidate only if the sphere would touch it on its way there,
``dist(c, [x, x_s]) − δ < r`` (a sphere sliding along a wall finds the same wall ahead, at
about its own distance: not a threat, and its tangent plane, turned across the sphere's way,
would brake it for nothing). The candidates (of all three queries) are ranked by the clearance
after a stop rather than by their distance: with ``g = ‖x − c‖ − δ`` and ``ġ = n · v`` (the
distance's rate, ``c`` static),

    b = g − min(ġ, 0)² / (2 a_b)                                                  [m],

the least ``b`` is written. A hand descending between two objects toward the table under
them saw the objects' sides (its nearest points, and the other object as its far side) and
met the table top only once it was the nearest point, 44 mm away at 0.9 m/s, too late to
stop: held-out MotionBenchMaker table_pick/0089 as a cloud (``--seed 8``) put the hand
15 mm into the true table. Without ``v`` (or ``a_b``) ``b = g``: the nearest candidate wins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.mesh_distance import NearestPoints
from dynfab.geometry.point_cloud import PointCloud

__all__ = ["FAR_SIDE_ANGLE", "FAR_SIDE_SHIFTS", "SphereMotion", "braking_clearance", "far_side_points",
           "segment_distances", "stopping_points"]

#: How far beyond the query point the cloud is queried, in multiples of ``x − p`` [-]
#: (chosen a priori, not tuned; module docstring).
FAR_SIDE_SHIFTS = (0.25, 1.0)
#: Least angle [rad] between the directions from a query point to its nearest point and to
#: its far-side point (45°, chosen a priori, not tuned: a concave corner of two faces gives
#: about 90°, one flat or gently curved face about 0°).
FAR_SIDE_ANGLE = math.pi / 4


@dataclass(frozen=True)
class SphereMotion:
    """How the query points move: spheres braking at a known deceleration.

    Attributes:
        velocities: The sphere centres' velocities (N, 3) [m/s].
        radii: The spheres' radii (N,) [m].
        braking: The leaf's braking deceleration ``a_b`` [m/s²].
    """

    velocities: NDArray[np.float64]
    radii: NDArray[np.float64]
    braking: float


def stopping_points(centres: NDArray[np.float64], velocities: NDArray[np.float64], braking: float) -> NDArray[np.float64]:
    """Where spheres at ``centres`` (N, 3) [m] moving at ``velocities`` (N, 3) [m/s] stop
    braking at ``braking`` [m/s²]: ``x + v ‖v‖ / (2 a_b)`` (N, 3) [m]."""
    speeds = np.linalg.norm(velocities, axis=1)
    return centres + velocities * (speeds / (2.0 * braking))[:, None]


def segment_distances(starts: NDArray[np.float64], ends: NDArray[np.float64],
                      points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per row, the distance [m] from ``points`` (N, 3) to the segment from ``starts`` to
    ``ends`` (N, 3): ``‖a + t (b − a) − c‖``, ``t = clip((c − a)·(b − a)/‖b − a‖², 0, 1)``."""
    along = ends - starts
    lengths = np.einsum("ij,ij->i", along, along)
    t = np.clip(np.einsum("ij,ij->i", points - starts, along) / np.maximum(lengths, 1e-24), 0.0, 1.0)
    return np.linalg.norm(starts + t[:, None] * along - points, axis=1)


def braking_clearance(distances: NDArray[np.float64], directions: NDArray[np.float64],
                      motion: SphereMotion | None) -> NDArray[np.float64]:
    """The clearance left after a stop, ``b = g − min(n · v, 0)² / (2 a_b)`` [m], of points at
    ``distances`` g (N,) [m] in ``directions`` n (N, 3) (from the point to the sphere) from
    spheres in ``motion`` (velocities v, deceleration a_b); ``g`` itself without it (module
    docstring)."""
    if motion is None:
        return np.asarray(distances, dtype=float)
    rates = np.einsum("ij,ij->i", np.nan_to_num(directions), motion.velocities)
    return distances - np.minimum(rates, 0.0) ** 2 / (2.0 * motion.braking)


def far_side_points(cloud: PointCloud, centres: NDArray[np.float64], nearest: NDArray[np.float64],
                    normals: NDArray[np.float64], has_nearest: NDArray[np.bool_], reach: NDArray[np.float64],
                    motion: SphereMotion | None = None) -> NearestPoints:
    """Per query point ``x`` (``centres`` (N, 3) [m]) with a nearest surface point (``nearest``
    (N, 3) [m], its unit direction to ``x`` in ``normals`` (N, 3), where ``has_nearest``):
    the kept point of ``cloud`` on its far side moved toward ``x`` by ``δ``, the direction
    to ``x``, the distance ``‖x − c‖ − δ`` [m] and whether one was found within ``reach``
    (N,) [m]. With the spheres' ``motion``, also the point ahead, and the least clearance
    after a stop wins (module docstring)."""
    x = np.asarray(centres, dtype=float).reshape(-1, 3)
    count = len(x)
    points, directions = np.full((count, 3), np.nan), np.full((count, 3), np.nan)
    distances = np.full(count, np.inf)
    rows = np.flatnonzero(has_nearest)
    if cloud.empty or len(rows) == 0:
        return NearestPoints(points, directions, distances, np.zeros(count, dtype=bool))
    moved = None if motion is None else SphereMotion(np.asarray(motion.velocities, dtype=float).reshape(-1, 3)[rows],
                                                     np.asarray(motion.radii, dtype=float)[rows], motion.braking)
    queries = [(x[rows] + shift * (x[rows] - nearest[rows]), None) for shift in FAR_SIDE_SHIFTS]
    if moved is not None:
        queries.append((stopping_points(x[rows], moved.velocities, moved.braking), moved.radii))
    ranks = np.full(len(rows), np.inf)
    for beyond, touching in queries:
        _better_far_side(cloud, x, normals, rows, reach, beyond, touching, moved, ranks, points, directions,
                         distances)
    return NearestPoints(points, directions, distances, np.isfinite(distances))


def _better_far_side(cloud: PointCloud, x: NDArray[np.float64], normals: NDArray[np.float64],
                     rows: NDArray[np.intp], reach: NDArray[np.float64], beyond: NDArray[np.float64],
                     touching: NDArray[np.float64] | None, motion: SphereMotion | None, ranks: NDArray[np.float64],
                     points: NDArray[np.float64], directions: NDArray[np.float64],
                     distances: NDArray[np.float64]) -> None:
    """The candidates of one query ``beyond`` (one row per ``x[rows]``), written into
    ``points``, ``directions`` and ``distances`` where they are kept and rank lower (``ranks``,
    per row: :func:`braking_clearance`) than what is there; with ``touching`` (radii, per
    row [m]), only candidates within ``radius + δ`` of the segment from ``x`` to their query point
    (module docstring)."""
    bound = float(np.max(np.linalg.norm(beyond - x[rows], axis=1) + reach[rows])) + cloud.lowering
    gaps, index = cloud.tree.query(beyond, distance_upper_bound=bound)
    hit = np.flatnonzero(np.isfinite(gaps))
    candidates = cloud.points[index[hit]]
    offsets = x[rows[hit]] - candidates
    lengths = np.linalg.norm(offsets, axis=1)
    unit = offsets / np.maximum(lengths, 1e-12)[:, None]
    turned = np.einsum("ij,ij->i", unit, normals[rows[hit]]) < math.cos(FAR_SIDE_ANGLE)
    gap = lengths - cloud.lowering
    here = None if motion is None else SphereMotion(motion.velocities[hit], motion.radii[hit], motion.braking)
    rank = braking_clearance(gap, unit, here)
    keep = turned & (lengths > 1e-12) & (gap <= reach[rows[hit]]) & (rank < ranks[hit])
    if touching is not None:
        keep &= segment_distances(x[rows[hit]], beyond[hit], candidates) - cloud.lowering < touching[hit]
    hit, unit, gap, candidates = hit[keep], unit[keep], gap[keep], candidates[keep]
    ranks[hit] = rank[keep]
    written = rows[hit]
    points[written] = candidates + cloud.lowering * unit
    directions[written] = unit
    distances[written] = gap
