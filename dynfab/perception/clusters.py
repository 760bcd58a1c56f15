"""Clusters of a point cloud: the connected components of its occupied voxels.

Points ``p`` fall in voxels ``⌊p / h⌋`` of edge ``h`` [m]; two occupied voxels are connected
when they touch (share a face, edge or corner: the 26-neighbourhood), and a cluster is a
connected component. Points closer than ``h`` along each axis always share a cluster; two
surfaces more than ``2h`` apart along some axis never do.

Cost: one sort of the N voxel keys, one binary search of the occupied voxels for the 13
voxels of each one's half-neighbourhood, and a sparse connected-components pass (scipy, on a CSR graph: a COO one
costs 0.3 ms more to convert) over the occupied voxels.
"""

from __future__ import annotations

import itertools

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["voxel_clusters"]

#: The 13 voxel offsets of half the 26-neighbourhood (the other half are their negatives).
_HALF_NEIGHBOURS = np.array([offset for offset in itertools.product((-1, 0, 1), repeat=3)
                             if offset > (0, 0, 0)], dtype=np.int64)


def voxel_clusters(points: NDArray[np.float64], edge: float) -> tuple[NDArray[np.int64], int]:
    """The cluster of each point (module docstring) and how many there are.

    Args:
        points: (N, 3) finite points [m].
        edge: Voxel edge ``h`` [m], > 0.

    Returns:
        ``(labels, count)``: ``labels`` (N,) in ``0 .. count − 1``.
    """
    if not edge > 0.0:
        raise ValueError(f"edge must be > 0, got {edge}")
    if len(points) == 0:
        return np.zeros(0, dtype=np.int64), 0
    cells = np.floor(points / edge).astype(np.int64)
    cells -= cells.min(axis=0) - 1  # >= 1: every neighbour index stays >= 0
    sizes = cells.max(axis=0) + 2
    strides = np.array([sizes[1] * sizes[2], sizes[2], 1], dtype=np.int64)
    keys = cells @ strides
    voxels, of_point = np.unique(keys, return_inverse=True)
    targets = voxels[:, None] + (_HALF_NEIGHBOURS @ strides)[None, :]  # (M, 13): all offsets in one search
    found = np.minimum(np.searchsorted(voxels, targets), len(voxels) - 1)
    rows, offsets = np.nonzero(voxels[found] == targets)
    columns = found[rows, offsets]
    graph = csr_matrix((np.ones(len(rows), dtype=np.int8), (rows, columns)), shape=(len(voxels),) * 2)
    count, of_voxel = connected_components(graph, directed=False)
    return of_voxel[of_point.reshape(-1)].astype(np.int64), int(count)
