"""The clusters of a frame that hold arrived points: what moves, without clustering what does not.

Clustering a whole frame (:func:`~dynfab.perception.clusters.voxel_clusters`) costs in
proportion to its points, most of them on static surfaces (a floor in view: 10⁵ points). A
thing that moves has *arrived* points (its pixels came nearer since the previous frame:
:class:`~dynfab.perception.depth_changes.DepthChanges`); a static one has none. So:

1. the arrived points are clustered (voxel edge ``h``); groups of fewer than ``min_seeds``
   are dropped, and of the rest the :data:`MAX_REGIONS` largest are kept;
2. each group's bounding box grown by ``reach`` [m] is a region; the frame's points in the
   regions are clustered (edge ``h``);
3. a cluster is kept when it holds an arrived point and lies inside the regions shrunk by
   ``h``: one that reaches a region's border may go on beyond it (a wall, the floor) and is
   not summarised from a cut piece.

So a moving thing is tracked whole when it lies within ``reach`` of its arrived points (any
thing of diameter up to ``reach``); a larger moving thing, or one touching a large static
surface (closer than ``h``), is not tracked (it still reaches the planner's cloud, without a
velocity). The cost follows the regions' points, plus a pass over the frame's x coordinates per region.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.perception.clusters import voxel_clusters

__all__ = ["MAX_REGIONS", "arrival_clusters", "in_box", "rows_in_box"]

#: Most regions searched per frame (the largest groups of arrived points).
MAX_REGIONS = 4


def arrival_clusters(points: NDArray[np.float64], arrived: NDArray[np.bool_], edge: float, reach: float,
                     min_seeds: int) -> tuple[NDArray[np.int64], NDArray[np.int64], int]:
    """The kept clusters of the module docstring.

    Args:
        points: (N, 3) finite points [m].
        arrived: (N,) whether each point arrived.
        edge: Voxel edge ``h`` [m], > 0.
        reach: Growth of a group's box into a region [m], >= 0.
        min_seeds: Fewest arrived points a group needs, >= 1.

    Returns:
        ``(rows, labels, count)``: the rows of ``points`` in kept clusters and each one's
        cluster in ``0 .. count − 1``.

    Raises:
        ValueError: ``arrived`` is not one flag per point.
    """
    arrived = np.asarray(arrived, dtype=bool)
    if arrived.shape != (len(points),):
        raise ValueError(f"arrived: expected one flag per point ({len(points)},), got shape {arrived.shape}")
    none = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), 0)
    seeds = np.flatnonzero(arrived)
    if len(seeds) < min_seeds:
        return none
    seed_labels, seed_count = voxel_clusters(points[seeds], edge)
    sizes = np.bincount(seed_labels, minlength=seed_count)
    groups = [group for group in np.argsort(-sizes, kind="stable")[:MAX_REGIONS] if sizes[group] >= min_seeds]
    if not groups:
        return none
    boxes = []
    for group in groups:
        members = points[seeds[seed_labels == group]]
        boxes.append((members.min(axis=0) - reach, members.max(axis=0) + reach))
    found = [rows_in_box(points, low, high) for low, high in boxes]
    rows = np.unique(np.concatenate(found)) if len(found) > 1 else found[0]
    region = points[rows]
    inner = np.zeros(len(rows), dtype=bool)
    for low, high in boxes:
        inner |= in_box(region, low + edge, high - edge)
    labels, count = voxel_clusters(region, edge)
    seeded = np.bincount(labels, weights=arrived[rows], minlength=count) > 0
    cut = np.bincount(labels, weights=~inner, minlength=count) > 0
    kept = seeded & ~cut
    renumber = np.cumsum(kept) - 1
    chosen = kept[labels]
    return rows[chosen], renumber[labels[chosen]], int(kept.sum())


def in_box(points: NDArray[np.float64], low: NDArray[np.float64], high: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Whether each of ``points`` (N, 3) lies in the box ``[low, high]`` (N,), column by column
    (numpy's ``all`` along a row of three is slow)."""
    inside = (points[:, 0] >= low[0]) & (points[:, 0] <= high[0])
    for axis in (1, 2):
        inside &= (points[:, axis] >= low[axis]) & (points[:, axis] <= high[axis])
    return inside


def rows_in_box(points: NDArray[np.float64], low: NDArray[np.float64], high: NDArray[np.float64]) -> NDArray[np.int64]:
    """The rows of ``points`` in the box ``[low, high]``: x tested on every point, y on those
    that pass, then z."""
    xs = points[:, 0]
    rows = np.flatnonzero((xs >= low[0]) & (xs <= high[0]))
    for axis in (1, 2):
        values = points[rows, axis]
        rows = rows[(values >= low[axis]) & (values <= high[axis])]
    return rows
