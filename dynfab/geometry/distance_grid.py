"""A grid of lower bounds of the distance to a mesh's surface, for the global planner's checker.

The compiled checker (:mod:`dynfab.motion.checker_kernel`) must bound the distance of a robot
sphere centre ``p`` to a mesh in nanoseconds, never above the true distance ``f(p)`` (then a
configuration it accepts is free). The grid, in the mesh's frame, has nodes ``g`` every
``h`` [m] over the mesh's bounding box grown by ``margin``, and holds at each node a value
``v(g) ≤ f(g)``:

- exact (point-triangle distances) at nodes within ``band`` of some triangle: every node in
  a triangle's bounding box grown by ``band``; nodes outside all of them are farther than
  ``band`` from the mesh;
- farther out, with ``B = {x : f(x) ≤ band₀}`` (``band₀ = band − h``), ``f(g) ≥ band₀ + d(g, B)``
  (``f`` falls at rate 1 along the segment to the nearest surface point, which crosses the
  boundary of ``B``), and ``d(g, B) ≥ EDT(g) − h√3/2`` with ``EDT`` the Euclidean distance
  transform to the nodes with ``f ≤ band₀ + h√3/2`` (every point of ``B`` is within ``h√3/2``
  of such a node); so ``v(g) = max(band, band₀ + EDT(g) − h√3/2)``, up to about ``1.9 h``
  below ``f(g)``.

The band is :data:`BAND`, 10 cm. A robot sphere touches a mesh with its centre one radius
away, and the Panda's moving spheres reach 7.8 cm of radius, so with a narrower band the
nodes around the larger spheres' centres hold the far bound: with 4 cm (until session 18),
on MotionBenchMaker's kitchen (seed 10, problem 17) a goal whose ``panda_link5`` spheres
clear the counter by 2-5 mm read 8-11 mm *into* it, 13-16 mm low, and guidance refused it.
10 cm reads them within a few mm. Tried alone (session 17) it reached 2 more of 20 kitchen
problems on development seed 1, but on seed 11 one run (kitchen/0004) touched the kitchen
with a finger, 11 mm deep: its plan, now free to pass nearer, swept the hand 12-16 mm past a
cupboard's top edge at 0.5 of the velocity limits, the robot lagged 0.07 rad behind it
where the leaves braked, and cut the edge. Since the reference slows where its way is tight
(:meth:`~dynfab.motion.guidance.JointGuidance.speed_scale`), that run keeps 16.8 mm and the
10 cm band is the default (kitchen seed 1: 16/20, 4 cm 14/20; seed 11: 17/20, 4 cm 16/20;
0 mesh collisions). The exact distances are :mod:`dynfab.geometry.triangle_band`'s compiled
loop.

Between nodes, ``f`` being 1-Lipschitz gives ``f(p) ≥ f(g_j) − ‖p − g_j‖`` for every corner
``g_j`` of the cell, hence

    f(p) ≥ max_j (v(g_j) − ‖p − g_j‖)        [m],

what the kernel returns: exact at nodes, and below ``f(p)`` by at most
``2 min_j ‖p − g_j‖ ≤ h√3`` where the node values are exact (the nearest corner is within
``h√3/2``). The maximum is never below the trilinear mean of the same corner bounds
(``Σ_j w_j (v(g_j) − ‖p − g_j‖)``, used before: on the MotionBenchMaker kitchen at ``h`` = 1 cm
that mean was 1.0 cm below the true distance on average for robot spheres within 5 cm). Outside the grid the distance to the mesh's bounding box is the bound. The unsigned
distance is bounded: a sphere wholly inside a closed mesh is not seen (the planner's motions
start free and are checked densely, so they cannot get there without crossing the surface).

Memory: 8 bytes per node, at most :data:`MAX_NODES` (the pitch grows to stay within it).
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import distance_transform_edt

from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.triangle_band import triangle_band

__all__ = ["BAND", "DistanceGrid", "MAX_NODES", "distance_grid", "grid_key"]

#: Nodes this close to a triangle get exact distances [m] (module docstring).
BAND = 0.10
#: Most nodes of one grid (64 MB).
MAX_NODES = 8_000_000
#: Version of the build, part of the disk cache's key.
_VERSION = 1
#: Header length of :meth:`DistanceGrid.packed` (the kernel reads it).
HEADER = 13


@dataclass(frozen=True, eq=False)
class DistanceGrid:
    """Lower bounds of the distance to a mesh at grid nodes (module docstring), mesh frame.

    Attributes:
        origin: The first node (3,) [m].
        pitch: ``h``, the node spacing [m].
        values: (nx, ny, nz) lower bounds ``v(g)`` [m].
        low: The mesh's bounding box, lowest corner (3,) [m].
        high: Its highest corner (3,) [m].
    """

    origin: NDArray[np.float64]
    pitch: float
    values: NDArray[np.float64]
    low: NDArray[np.float64]
    high: NDArray[np.float64]

    def packed(self) -> NDArray[np.float64]:
        """The kernel's layout: ``nx, ny, nz, h, origin (3), low (3), high (3)``, then the
        values in C order (z fastest)."""
        header = np.concatenate([self.values.shape, [self.pitch], self.origin, self.low, self.high])
        return np.concatenate([header, self.values.ravel()])

    def lower_bound(self, points: ArrayLike) -> NDArray[np.float64]:
        """``max_j (v(g_j) − ‖p − g_j‖)`` over the cell's corners (...,) [m] of points (..., 3)
        in the mesh frame (outside the grid: the distance to the bounding box), as the kernel
        computes it."""
        p = np.asarray(points, dtype=float)
        flat = p.reshape(-1, 3)
        shape = np.array(self.values.shape)
        cell = (flat - self.origin) / self.pitch
        inside = np.all((cell >= 0) & (cell <= shape - 1), axis=1)
        result = np.linalg.norm(np.maximum(self.low - flat, 0) + np.maximum(flat - self.high, 0), axis=1)
        base = np.minimum(np.floor(cell[inside]).astype(int), shape - 2)
        fraction = cell[inside] - base
        best = np.full(int(inside.sum()), -np.inf)
        for corner in np.ndindex(2, 2, 2):
            node = base + np.array(corner)
            gap = np.linalg.norm((fraction - np.array(corner)) * self.pitch, axis=1)
            best = np.maximum(best, self.values[node[:, 0], node[:, 1], node[:, 2]] - gap)
        result[inside] = best
        return result.reshape(p.shape[:-1])


def distance_grid(mesh: Mesh, pitch: float = 0.01, margin: float = 0.1, band: float = BAND,
                  cache: Path | None = None) -> DistanceGrid:
    """The lower-bound grid of ``mesh`` (module docstring); kept on the mesh per arguments and,
    with ``cache``, on disk by the mesh's content (:func:`grid_key`): the same triangles in
    another run or process load in milliseconds instead of being built again (seconds).

    Args:
        mesh: The mesh.
        pitch: ``h`` [m]; grown if the grid would exceed :data:`MAX_NODES`.
        margin: How far the grid reaches beyond the mesh's bounding box [m].
        band: Nodes this close to a triangle get exact distances [m] (> ``pitch``).
        cache: A folder for grids on disk; None: memory only.
    """
    key = ("_distance_grid", pitch, margin, band)
    cached = mesh.__dict__.get(key)
    if cached is not None:
        return cached
    file = None if cache is None else cache / f"grid-{grid_key(mesh, pitch, margin, band)}.npz"
    if file is not None and file.is_file():
        try:
            with np.load(file) as stored:
                grid = DistanceGrid(stored["origin"], float(stored["pitch"]), stored["values"], stored["low"],
                                    stored["high"])
            mesh.__dict__[key] = grid
            return grid
        except (OSError, ValueError, KeyError):
            pass  # unreadable (a partial write of an older version): built again and replaced
    grid = _build(mesh, pitch, margin, band)
    mesh.__dict__[key] = grid
    if file is not None:
        _store(file, grid)
    return grid


def grid_key(mesh: Mesh, pitch: float, margin: float, band: float) -> str:
    """SHA-256 (hex, 32 characters) of what a grid depends on: the vertices, faces, the
    arguments and the build's version."""
    digest = hashlib.sha256(f"v{_VERSION} {pitch!r} {margin!r} {band!r} {MAX_NODES}\n".encode())
    digest.update(np.ascontiguousarray(mesh.vertices, dtype="<f8").tobytes())
    digest.update(np.ascontiguousarray(mesh.faces, dtype="<i8").tobytes())
    return digest.hexdigest()[:32]


def _store(file: Path, grid: DistanceGrid) -> None:
    """Write ``grid`` to ``file`` atomically (a temporary file renamed); a folder that cannot
    be written leaves the grid in memory only."""
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=file.parent, suffix=".npz", delete=False) as handle:
            np.savez(handle, origin=grid.origin, pitch=grid.pitch, values=grid.values, low=grid.low, high=grid.high)
        os.replace(handle.name, file)
    except OSError:
        pass


def _build(mesh: Mesh, pitch: float, margin: float, band: float) -> DistanceGrid:
    """The grid of ``mesh`` (module docstring), computed."""
    low, high = mesh.bounds
    extent = high - low + 2 * margin
    pitch = max(pitch, float(np.prod(extent) / MAX_NODES) ** (1 / 3) * 1.01)
    band = max(band, 2 * pitch)
    origin = low - margin
    shape = np.ceil(extent / pitch).astype(int) + 1
    exact = triangle_band(mesh.vertices[mesh.faces], origin, pitch, tuple(int(n) for n in shape), band)
    inner = band - pitch
    half_diagonal = 0.5 * math.sqrt(3) * pitch
    near = exact <= inner + half_diagonal
    transform = distance_transform_edt(~near, sampling=pitch) if near.any() else np.full(exact.shape, np.inf)
    far = np.maximum(band, inner + transform - half_diagonal)
    values = np.where(exact <= band, exact, far)  # beyond band a triangle left out may be nearer
    return DistanceGrid(origin, pitch, values, low, high)
