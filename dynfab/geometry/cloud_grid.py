"""The global planner's distance grid of a point cloud: a lower bound of the distance to it.

The same :class:`~dynfab.geometry.distance_grid.DistanceGrid` the compiled checker reads for
meshes (kind 5), built from the cloud's kept points ``C`` (voxel centres,
:mod:`dynfab.geometry.point_cloud`); a raw point lies within ``δ = h_v√3/2`` of its kept
centre (``h_v`` the cloud's voxel), so ``d(x, raw) ≥ d(x, C) − δ``. Node values ``v(g)``:

- within ``band`` of the cloud, exact: ``v(g) = d(g, C) − δ`` (a KD-tree query per node);
- farther, each point ``c`` rounded to its nearest node ``m(c)`` (within ``h√3/2`` of it,
  ``h`` the grid pitch) and ``EDT(g)`` the Euclidean distance transform of the occupied
  nodes (scipy.ndimage.distance_transform_edt): ``d(g, C) ≥ min_c (‖g − m(c)‖ − h√3/2) =
  EDT(g) − h√3/2``, so ``v(g) = max(0, EDT(g) − h√3/2 − δ)``.

Neither exceeds the distance to the raw cloud. Between nodes the checker (kernel kind 6,
read as meshes' kind 5) takes the largest corner bound

    f(p) ≥ max_j (v(g_j) − ‖p − g_j‖)            [m]

(each is a lower bound alone, the distance being 1-Lipschitz), short of ``d(p, C) − δ`` by at
most ``2 min_j ‖p − g_j‖ ≤ h√3`` near the cloud (:meth:`~dynfab.geometry.distance_grid.DistanceGrid.lower_bound` computes it
as the kernel does).

The grid covers the cloud's bounding box grown by ``margin`` (outside, the kernel takes
the distance to the box); at most :data:`~dynfab.geometry.distance_grid.MAX_NODES` nodes
(the pitch grows to stay within them). The build costs an EDT over the grid: about a
second for a 2 m cube at 1 cm.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import distance_transform_edt

from dynfab.geometry.distance_grid import MAX_NODES, DistanceGrid
from dynfab.geometry.point_cloud import PointCloud

__all__ = ["cloud_distance_grid"]


def cloud_distance_grid(cloud: PointCloud, pitch: float = 0.01, margin: float = 0.1, band: float = 0.03) -> DistanceGrid:
    """The lower-bound grid of a non-empty ``cloud`` (module docstring), world frame; cached
    on the cloud per arguments.

    Args:
        cloud: The cloud.
        pitch: ``h`` [m]; grown if the grid would exceed ``MAX_NODES``.
        margin: How far the grid reaches beyond the cloud's bounding box [m].
        band: Nodes this close to the cloud get exact distances [m].

    Raises:
        ValueError: The cloud is empty.
    """
    if cloud.empty:
        raise ValueError(f"point cloud {cloud.source} is empty: no distance grid")
    key = ("_distance_grid", pitch, margin, band)
    cached = cloud.__dict__.get(key)
    if cached is not None:
        return cached
    low, high = cloud.bounds
    extent = high - low + 2 * margin
    pitch = max(pitch, float(np.prod(extent) / MAX_NODES) ** (1 / 3) * 1.01)
    origin = low - margin
    shape = np.ceil(extent / pitch).astype(int) + 1
    nodes = np.clip(np.rint((cloud.points - origin) / pitch).astype(np.int64), 0, shape - 1)
    free = np.ones(tuple(shape), dtype=bool)
    free[nodes[:, 0], nodes[:, 1], nodes[:, 2]] = False
    transform = distance_transform_edt(free, sampling=pitch)
    values = np.maximum(transform - 0.5 * math.sqrt(3.0) * pitch - cloud.lowering, 0.0)
    near = np.argwhere(transform <= band + 0.5 * math.sqrt(3.0) * pitch)
    if len(near):
        exact, _ = cloud.tree.query(np.ascontiguousarray(origin + near * pitch))
        values[near[:, 0], near[:, 1], near[:, 2]] = exact - cloud.lowering
    grid = DistanceGrid(origin, pitch, values, low - cloud.lowering, high + cloud.lowering)  # raw points' box
    cloud.__dict__[key] = grid
    return grid
