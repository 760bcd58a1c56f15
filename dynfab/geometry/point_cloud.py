"""A point cloud as an obstacle: measured surface points, voxel-downsampled, in bounded memory.

A cloud of raw points ``P`` (N, 3) [m] becomes the centres of the occupied cells of a voxel
grid of edge ``h`` (one point per cell, keys ``⌊p / h⌋``, numpy ``unique``). Every raw point
lies in its cell, within ``δ = h√3/2`` of the cell's centre, so for any point ``x``

    d(x, P) ≥ d(x, C) − δ                 [m],

with ``C`` the kept centres: what the planners read (:func:`nearest_in_cloud` lowers the
clearance by ``δ``; :mod:`dynfab.geometry.cloud_grid` builds the checker's grid from ``C``
with the same ``δ``), so neither ever overstates the distance to a measured point.

Bounded memory: the raw points are reduced in chunks of :data:`CHUNK` points (the
temporaries are chunk-sized whatever ``N``), and whenever more than ``max_points`` cells are
occupied the edge doubles until at most ``max_points`` remain (default
:data:`MAX_CLOUD_POINTS`: 24 MB of kept points, 8 MB of keys). 10⁷ raw points take about
2.5 s. Non-finite rows (a depth sensor's missing
returns) are dropped and counted, not refused.

The KD-tree is pykdtree's: on a table top beside a box (a plane of points next to 3-D
structure) scipy's cKDTree took 1-6 ms for the 58 nearest-point queries of a Panda tick (its
cells keep the loose extent of their parents along axes never split, so a query above the
table visits thousands of points), pykdtree 16-30 µs. Its queries run on OpenMP threads; one
thread is asked for (``OMP_NUM_THREADS=1`` unless set before the first tree is built):
58 queries are too few to share, and threads waiting on a loaded machine cost milliseconds.

The surface between measured points is not known: a cloud sampled every ``s`` leaves gaps
a sphere of radius below ``s/2`` could pass; robot spheres are centimetres wide.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.mesh_shape import Mesh

if TYPE_CHECKING:
    from pykdtree.kdtree import KDTree

    from dynfab.geometry.mesh_distance import NearestPoints

__all__ = ["CHUNK", "DEFAULT_VOXEL", "MAX_CLOUD_POINTS", "PointCloud", "downsampled", "finite_rows", "kd_tree"]

#: Default voxel edge ``h`` [m].
DEFAULT_VOXEL = 0.01
#: Default cap on the points a cloud keeps after downsampling.
MAX_CLOUD_POINTS = 1_000_000
#: Raw points reduced at once (bounds the temporaries).
CHUNK = 1_000_000
#: Points per leaf of the KD-tree: 32 builds a 52-118 k point cloud 20-25 % faster than
#: pykdtree's 16, its query of 58 Panda spheres 1-3 % slower (CPU time, 2026-11-26).
_LEAF_SIZE = 32
#: Edge of the triangle standing for each point in exact collision checks [m].
_SPECK = 1e-4


@dataclass(frozen=True, eq=False)
class PointCloud:
    """Kept points of a cloud (module docstring), in the world frame.

    Attributes:
        points: (M, 3) voxel centres [m], finite, read-only; M may be 0 (an empty cloud).
        voxel: ``h``, the cell edge the points were reduced to [m]; 0: points as given.
        dropped: Raw rows dropped for being NaN or infinite.
        source: Where it came from (a file name), for messages.
    """

    points: NDArray[np.float64]
    voxel: float = 0.0
    dropped: int = 0
    source: str = field(default="")

    def __post_init__(self) -> None:
        points = np.array(self.points, dtype=float).reshape(-1, 3)
        if not np.isfinite(points).all():
            raise ValueError(f"point cloud {self.source}: NaN or infinite points (drop them first: finite_rows)")
        if not (math.isfinite(self.voxel) and self.voxel >= 0.0):
            raise ValueError(f"point cloud {self.source}: voxel must be a finite number >= 0, got {self.voxel}")
        points.setflags(write=False)
        object.__setattr__(self, "points", points)

    @classmethod
    def from_points(cls, raw: ArrayLike, voxel: float = DEFAULT_VOXEL, max_points: int = MAX_CLOUD_POINTS,
                    source: str = "") -> PointCloud:
        """Reduce raw points (N, 3) [m]: non-finite rows dropped, then voxel-downsampled
        (module docstring).

        Raises:
            ValueError: ``raw`` is not (N, 3) numbers, ``voxel`` is not positive or
                ``max_points`` below 1.
        """
        array = np.asarray(raw)
        if array.ndim != 2 or array.shape[1] != 3 or not np.issubdtype(array.dtype, np.number):
            raise ValueError(f"point cloud {source}: expected an (N, 3) array of numbers, got shape "
                             f"{array.shape} of {array.dtype}")
        if not (math.isfinite(voxel) and voxel > 0.0) or max_points < 1:
            raise ValueError(f"point cloud {source}: voxel must be positive and max_points at least 1, "
                             f"got {voxel} and {max_points}")
        kept, edge, dropped = downsampled(array, voxel, max_points)
        return cls(kept, edge, dropped, source)

    @property
    def dimensions(self) -> tuple[float, ...]:
        """No sizes: the points are the geometry."""
        return ()

    @property
    def empty(self) -> bool:
        """Whether it has no points (then it is no obstacle)."""
        return len(self.points) == 0

    @property
    def lowering(self) -> float:
        """``δ = h√3/2`` [m]: how far a raw point may be from its kept centre."""
        return 0.5 * math.sqrt(3.0) * self.voxel

    @cached_property
    def tree(self) -> KDTree:
        """A KD-tree of the kept points (pykdtree, built on first use; a non-empty cloud)."""
        return kd_tree(self.points)

    @property
    def bounds(self) -> NDArray[np.float64]:
        """(2, 3): the lowest and highest coordinates per axis [m] (a non-empty cloud)."""
        return np.array([self.points.min(axis=0), self.points.max(axis=0)])

    @cached_property
    def bounding_radius(self) -> float:
        """Radius [m] of the ball about the frame origin that holds every point."""
        return float(np.max(np.linalg.norm(self.points, axis=1))) if len(self.points) else 0.0

    def distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """``d(x, C) − δ`` (...,) [m] of points (..., 3): a lower bound of the distance to the
        raw cloud (``inf`` for an empty cloud)."""
        x = np.asarray(points, dtype=float)
        if self.empty:
            return np.full(x.shape[:-1], np.inf)
        distances, _ = self.tree.query(x.reshape(-1, 3))
        return (distances - self.lowering).reshape(x.shape[:-1])

    def nearest(self, centres: ArrayLike, max_distance: float = np.inf) -> NearestPoints:
        """Per query point ``x`` (N, 3): the nearest kept point ``c`` moved toward ``x`` by
        ``δ``, ``c + δ n`` with ``n = (x − c)/‖x − c‖``, and the distance ``‖x − c‖ − δ``
        [m] (a lower bound of the distance to the raw cloud, and the exact distance to that
        moved point), for the points within ``max_distance`` of it (``found``).

        ``n`` is the gradient of the distance to the cloud at ``x``: the nearest-point leaf's
        tangent plane through the moved point is then exact to first order at ``x``. A query
        point on a kept point gets ``n = +z``.
        """
        from dynfab.geometry.mesh_distance import NearestPoints

        x = np.asarray(centres, dtype=float).reshape(-1, 3)
        count = len(x)
        points, normals = np.full((count, 3), np.nan), np.full((count, 3), np.nan)
        distances = np.full(count, np.inf)
        if self.empty or count == 0:
            return NearestPoints(points, normals, distances, np.zeros(count, dtype=bool))
        bound = max_distance + self.lowering if math.isfinite(max_distance) else None
        gaps, index = self.tree.query(x, distance_upper_bound=bound)
        found = np.isfinite(gaps)
        rows = np.flatnonzero(found)
        nearest = self.points[index[rows]]
        offsets = x[rows] - nearest
        lengths = gaps[rows]
        unit = np.where(lengths[:, None] > 1e-12, offsets / np.maximum(lengths, 1e-12)[:, None], (0.0, 0.0, 1.0))
        normals[rows] = unit
        points[rows] = nearest + self.lowering * unit
        distances[rows] = lengths - self.lowering
        return NearestPoints(points, normals, distances, found)

    @cached_property
    def specks(self) -> Mesh:
        """The cloud as triangles for exact collision checks (coal): per point a right
        triangle of legs :data:`_SPECK` with its corner at the point, so the distance to
        it is at most the distance to the point and at least that less 0.1 mm."""
        count = len(self.points)
        if count == 0:
            raise ValueError(f"point cloud {self.source} is empty: no triangles")
        vertices = np.repeat(self.points, 3, axis=0)
        vertices[1::3, 0] += _SPECK
        vertices[2::3, 1] += _SPECK
        return Mesh(vertices, np.arange(3 * count).reshape(-1, 3), source=self.source or "point cloud")


def kd_tree(points: NDArray[np.float64]) -> KDTree:
    """pykdtree's KD-tree of ``points`` (N, d), its queries on one OpenMP thread (module
    docstring: ``OMP_NUM_THREADS=1`` unless set before the first tree)."""
    os.environ.setdefault("OMP_NUM_THREADS", "1")  # read once, when pykdtree's OpenMP starts
    from pykdtree.kdtree import KDTree

    return KDTree(np.ascontiguousarray(points), leafsize=_LEAF_SIZE)


def finite_rows(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], int]:
    """The rows of ``points`` (N, 3) whose three coordinates are finite, and how many were not
    (``points`` itself when all are: one pass over the array, no row mask or copy)."""
    if np.isfinite(points).all():
        return points, 0
    keep = np.isfinite(points[:, 0]) & np.isfinite(points[:, 1]) & np.isfinite(points[:, 2])
    return points[keep], int(len(points) - np.count_nonzero(keep))


def downsampled(raw: NDArray[np.floating], voxel: float, max_points: int) -> tuple[NDArray[np.float64], float, int]:
    """One point per occupied cell of edge ``h`` (its centre), ``h`` doubled until at most
    ``max_points`` cells are occupied; also the edge used and the non-finite rows dropped.

    The rows are reduced :data:`CHUNK` at a time: integer cells ``⌊p / h⌋`` packed into one
    int64 key (21 bits per axis), merged into the distinct cells so far, the edge doubled
    as soon as they are more than ``max_points``; memory stays within ``max_points +``
    :data:`CHUNK` keys whatever the number of rows.

    Raises:
        ValueError: a coordinate is more than 2²⁰ cells from the origin (10 km at 1 cm).
    """
    edge = voxel
    keys = np.zeros(0, dtype=np.int64)
    dropped = 0
    for start in range(0, len(raw), CHUNK):
        chunk, bad = finite_rows(np.asarray(raw[start:start + CHUNK], dtype=float))
        dropped += bad
        keys = _distinct(np.concatenate([keys, _cells(chunk, edge)]))
        while len(keys) > max_points:
            edge *= 2.0
            keys = _distinct(_pack(np.floor_divide(_unpack(keys), 2)))
    return _centres(keys, edge), edge, dropped


_BITS = 21
_OFFSET = 1 << (_BITS - 1)
_MASK = (1 << _BITS) - 1
#: The weights that pack shifted cells ``(i, j, k)`` into ``i 2⁴² + j 2²¹ + k`` (no carries: each is below 2²¹).
_FIELDS = np.array([1 << (2 * _BITS), 1 << _BITS, 1], dtype=np.int64)


def _cells(points: NDArray[np.float64], edge: float) -> NDArray[np.int64]:
    """Packed keys of the cells ``⌊p / h⌋`` of finite points (the offset added in floating point,
    exact for cells within ±2²⁰; one (N, 3) float temporary, floored in place, and its integer
    copy; the three fields packed by one product with ``(2⁴², 2²¹, 1)``)."""
    cells = points / edge
    np.floor(cells, out=cells)
    if cells.size and (cells.min() < -_OFFSET or cells.max() >= _OFFSET):
        raise ValueError(f"point cloud: a coordinate of {np.abs(points).max():.3g} m is more than "
                         f"{_OFFSET} cells of {edge} m from the origin")
    cells += _OFFSET
    return cells.astype(np.int64) @ _FIELDS


def _pack(cells: NDArray[np.int64]) -> NDArray[np.int64]:
    return _packed(cells + _OFFSET)


def _packed(shifted: NDArray[np.int64]) -> NDArray[np.int64]:
    """Keys of cells already shifted by the offset (non-negative, below 2²¹)."""
    keys = shifted[:, 0] << (2 * _BITS)
    keys |= shifted[:, 1] << _BITS
    keys |= shifted[:, 2]
    return keys


def _unpack(keys: NDArray[np.int64]) -> NDArray[np.int64]:
    return np.stack([(keys >> (2 * _BITS)) & _MASK, (keys >> _BITS) & _MASK, keys & _MASK], axis=1) - _OFFSET


def _centres(keys: NDArray[np.int64], edge: float) -> NDArray[np.float64]:
    """The centres ``(cell + ½) h`` of packed cells (N, 3) [m]."""
    centres = np.empty((len(keys), 3))
    centres[:, 0] = keys >> (2 * _BITS)
    centres[:, 1] = (keys >> _BITS) & _MASK
    centres[:, 2] = keys & _MASK
    centres -= _OFFSET - 0.5
    centres *= edge
    return centres


def _distinct(keys: NDArray[np.int64]) -> NDArray[np.int64]:
    """The distinct keys, sorted (a sort and a comparison: numpy's ``unique`` is slower here)."""
    ordered = np.sort(keys)
    return ordered[np.concatenate(([True], ordered[1:] != ordered[:-1]))] if len(ordered) else ordered
