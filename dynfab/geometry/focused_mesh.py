"""The part of a mesh near the robot, for the global planner: the same surface on a finer grid.

The checker's grid of a mesh (:mod:`dynfab.geometry.distance_grid`, pitch ``h`` = 1 cm)
reads up to ``h√3`` = 1.7 cm below the distance to the surface between its nodes. In a
cupboard, the robot's hand millimetres from the panels, that refuses goals and starts the
meshes clear (MotionBenchMaker kitchen, issue 20). For axis-aligned boxes ``K_j`` (mesh
frame; their union ``K``) the surface ``M`` is covered by its parts in each box and the
part outside them all,

    M = ∪_j (M ∩ K_j) ∪ (M ∖ K°),   d(x, M) = min(min_j d(x, M ∩ K_j), d(x, M ∖ K°))   [m],

so the minimum of a lower bound of each is one of the whole (the checker takes the minimum
over obstacles). :class:`FocusedMesh` holds ``M ∩ K_j``, each triangle clipped at the box's
six planes (convex polygons fanned back into triangles), its grid built at the finer
``pitch`` (short of its distance by at most ``pitch·√3``). :class:`CarvedMesh` stands for
``M ∖ K°``: its triangles are the whole mesh's (what coal measures: ``d(x, M)``, the
minimum being the same), its grid the whole mesh's raised inside the boxes to the depth
below their faces,

    v'(g) = max(v(g), max_j depth_j(g)),   depth_j(g) = max(0, min_a min(g_a − low_a, high_a − g_a)),

a lower bound of ``d(g, M ∖ K°)`` (``≥ d(g, M) ≥ v(g)``; ``M ∖ K°`` lies outside every
open box) built in one pass over the nodes, no triangle measured again. A closed mesh's
pieces are open: their distances are the unsigned ones, as the grid's always are.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.distance_grid import DistanceGrid
from dynfab.geometry.mesh_shape import Mesh

__all__ = ["CarvedMesh", "FocusedMesh", "carved", "carved_grid", "clip_mesh"]

#: A box ``(low (3,), high (3,))`` in the mesh's frame [m].
Box3 = tuple[NDArray[np.float64], NDArray[np.float64]]


@dataclass(frozen=True, eq=False)
class FocusedMesh(Mesh):
    """The triangles of a mesh clipped to one box (module docstring).

    Attributes:
        pitch: node spacing of the planner's grid of these triangles [m].
    """

    pitch: float = 0.004

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.pitch) and self.pitch > 0.0):
            raise ValueError(f"focused mesh {self.source}: pitch must be a positive number, got {self.pitch}")


@dataclass(frozen=True, eq=False)
class CarvedMesh(Mesh):
    """A mesh's surface outside boxes, for the planner's grid (module docstring): the whole
    mesh's triangles, its grid raised inside the boxes (:func:`carved_grid`).

    Attributes:
        holes: the boxes ``(low, high)`` whose inside another obstacle covers.
    """

    holes: tuple[Box3, ...] = field(default=())


def clip_mesh(mesh: Mesh, low: ArrayLike, high: ArrayLike, pitch: float) -> FocusedMesh | None:
    """``mesh``'s surface inside the box ``[low, high]`` (mesh frame) [m] as a
    :class:`FocusedMesh` gridded at ``pitch`` [m]; None if no triangle of positive area is
    inside.

    Raises:
        ValueError: ``low`` or ``high`` is not 3 finite numbers with ``low ≤ high``.
    """
    lower, upper = _box(mesh, low, high)
    inside: list[NDArray[np.float64]] = []
    for triangle in mesh.vertices[mesh.faces]:
        polygon = triangle
        for axis in range(3):
            polygon = _clip(_clip(polygon, axis, lower[axis], 1.0), axis, upper[axis], -1.0)
        inside.extend(np.stack([polygon[0], polygon[k], polygon[k + 1]]) for k in range(1, len(polygon) - 1))
    if not inside:
        return None
    corners = np.stack(inside)
    areas = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    corners = corners[areas > 1e-12]   # Mesh's own threshold: slivers of a clip bound nothing
    if len(corners) == 0:
        return None
    return FocusedMesh(corners.reshape(-1, 3), np.arange(3 * len(corners)).reshape(-1, 3),
                       f"{mesh.source} (focus)", pitch)


def carved(mesh: Mesh, holes: Sequence[tuple[ArrayLike, ArrayLike]]) -> CarvedMesh:
    """``mesh`` standing for its surface outside the boxes ``holes`` (mesh frame) [m].

    Raises:
        ValueError: a box is not 3 finite numbers low and high with ``low ≤ high``.
    """
    boxes = tuple(_box(mesh, low, high) for low, high in holes)
    return CarvedMesh(mesh.vertices, mesh.faces, mesh.source, boxes)


def carved_grid(grid: DistanceGrid, holes: Sequence[Box3]) -> DistanceGrid:
    """``grid`` (the whole mesh's) with each node's value raised to its depth inside the
    boxes ``holes``: ``v'(g)`` of the module docstring [m]."""
    shape = grid.values.shape
    axes = [grid.origin[a] + grid.pitch * np.arange(shape[a]) for a in range(3)]
    values = grid.values.copy()
    for low, high in holes:
        depth = [np.minimum(axes[a] - low[a], high[a] - axes[a]) for a in range(3)]
        inner = np.minimum(np.minimum(depth[0][:, None, None], depth[1][None, :, None]), depth[2][None, None, :])
        np.maximum(values, inner, out=values)
    return replace(grid, values=values)


def _box(mesh: Mesh, low: ArrayLike, high: ArrayLike) -> Box3:
    """``(low, high)`` as arrays, checked."""
    lower, upper = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    if lower.shape != (3,) or upper.shape != (3,) or not (np.isfinite(lower).all() and np.isfinite(upper).all()):
        raise ValueError(f"focus box of {mesh.source}: low and high must be 3 finite numbers, got {low} and {high}")
    if (lower > upper).any():
        raise ValueError(f"focus box of {mesh.source}: low {lower} exceeds high {upper}")
    return lower, upper


def _clip(polygon: NDArray[np.float64], axis: int, value: float, side: float) -> NDArray[np.float64]:
    """The part of the convex ``polygon`` (k, 3) where ``side·(x[axis] − value) ≥ 0``
    (Sutherland-Hodgman against one plane); (0, 3) if none."""
    if len(polygon) == 0:
        return polygon
    height = side * (polygon[:, axis] - value)
    kept: list[NDArray[np.float64]] = []
    for k in range(len(polygon)):
        a, b = polygon[k], polygon[(k + 1) % len(polygon)]
        ha, hb = height[k], height[(k + 1) % len(polygon)]
        if ha >= 0.0:
            kept.append(a)
        if (ha >= 0.0) != (hb >= 0.0):
            kept.append(a + (ha / (ha - hb)) * (b - a))
    return np.array(kept).reshape(-1, 3)
