"""Exact distances of grid nodes to a mesh near its triangles, the costly step of a mesh's
distance grid (:mod:`dynfab.geometry.distance_grid`).

For every triangle ``t`` and every node ``g = origin + h·(i, j, k)`` in ``t``'s bounding box
grown by ``band`` (clipped to the grid),

    exact[i, j, k] = min over such t of d(g, t)        [m],

``+inf`` at nodes no triangle's box reaches, with ``d`` the Euclidean point-triangle distance
(Ericson, *Real-Time Collision Detection*, 5.1.5: the closest point by the Voronoi region it
lies in). The work grows with the triangles and with ``(2·band/h)³``: the compiled loop
(``triangle_band.c``, built once with the planner's compiler and cached like the
configuration checker) takes 1/15-1/20 of numpy's time (MBM's meshes at a 10 cm band and
1 cm pitch, 2026-11-27 at load 3: the 12,288-triangle shelf of ``table_bars`` 4.1 s against
64 s; ``bench/bench_meshes.py`` at the grids' own band); without a compiler numpy does it.
"""

from __future__ import annotations

import ctypes
from functools import cache
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["numpy_triangle_band", "point_triangle_distances", "triangle_band"]

_SOURCE = Path(__file__).with_name("triangle_band.c")
_DOUBLES = ctypes.POINTER(ctypes.c_double)
_INTS = ctypes.POINTER(ctypes.c_int)


def triangle_band(triangles: NDArray[np.float64], origin: NDArray[np.float64], pitch: float,
                  shape: tuple[int, int, int], band: float) -> NDArray[np.float64]:
    """``exact`` of the module docstring, shape ``shape``, for ``triangles`` (T, 3, 3) [m]."""
    exact = np.full(shape, np.inf)
    triangles = np.ascontiguousarray(triangles, dtype=float).reshape(-1, 3, 3)
    origin = np.ascontiguousarray(origin, dtype=float)
    function = _compiled()
    if function is not None:
        dims = np.ascontiguousarray(shape, dtype=np.intc)
        function(triangles.ctypes.data_as(_DOUBLES), len(triangles), origin.ctypes.data_as(_DOUBLES), float(pitch),
                 dims.ctypes.data_as(_INTS), float(band), exact.ctypes.data_as(_DOUBLES))
        return exact
    return numpy_triangle_band(triangles, origin, pitch, shape, band, exact)


def numpy_triangle_band(triangles: NDArray[np.float64], origin: NDArray[np.float64], pitch: float,
                        shape: tuple[int, int, int], band: float,
                        exact: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    """:func:`triangle_band` in numpy (into ``exact`` if given), the compiled loop's fallback
    and its test's reference."""
    exact = np.full(shape, np.inf) if exact is None else exact
    last_node = np.array(shape) - 1
    for triangle in triangles:
        first = np.maximum(np.floor((triangle.min(axis=0) - band - origin) / pitch).astype(int), 0)
        last = np.minimum(np.ceil((triangle.max(axis=0) + band - origin) / pitch).astype(int), last_node)
        axes = [np.arange(first[a], last[a] + 1) for a in range(3)]
        index = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        distances = point_triangle_distances(origin + index * pitch, triangle)
        block = exact[first[0]:last[0] + 1, first[1]:last[1] + 1, first[2]:last[2] + 1]
        np.minimum(block, distances.reshape(block.shape), out=block)
    return exact


@cache
def _compiled() -> ctypes._CFuncPtr | None:
    """The compiled ``dynfab_triangle_band``, or None without a working compiler."""
    from dynfab.motion.checker_library import cached_library   # the checker's compile-and-cache

    path = cached_library(_SOURCE.read_text(encoding="utf-8"), "triangle-band", "the mesh distance grids' loop")
    if path is None:
        return None
    function = ctypes.CDLL(str(path)).dynfab_triangle_band
    function.argtypes = [_DOUBLES, ctypes.c_int, _DOUBLES, ctypes.c_double, _INTS, ctypes.c_double, _DOUBLES]
    function.restype = None
    return function


def point_triangle_distances(points: NDArray[np.float64], triangle: NDArray[np.float64]) -> NDArray[np.float64]:
    """Exact distances (N,) [m] of points (N, 3) to a triangle (3, 3) (Ericson, Real-Time
    Collision Detection, 5.1.5: the closest point by the Voronoi region it lies in)."""
    a, b, c = triangle
    ab, ac = b - a, c - a
    ap = points - a
    d1, d2 = ap @ ab, ap @ ac
    bp = points - b
    d3, d4 = bp @ ab, bp @ ac
    cp = points - c
    d5, d6 = cp @ ab, cp @ ac
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denominator = va + vb + vc
        v = np.where(denominator != 0, vb / denominator, 0.0)
        w = np.where(denominator != 0, vc / denominator, 0.0)
        closest = a + v[:, None] * ab + w[:, None] * ac  # inside the face
        edge_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        t = np.clip(d1 / np.where(d1 - d3 != 0, d1 - d3, 1.0), 0, 1)
        closest = np.where(edge_ab[:, None], a + t[:, None] * ab, closest)
        edge_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        t = np.clip(d2 / np.where(d2 - d6 != 0, d2 - d6, 1.0), 0, 1)
        closest = np.where(edge_ac[:, None], a + t[:, None] * ac, closest)
        edge_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        t = np.clip((d4 - d3) / np.where((d4 - d3) + (d5 - d6) != 0, (d4 - d3) + (d5 - d6), 1.0), 0, 1)
        closest = np.where(edge_bc[:, None], b + t[:, None] * (c - b), closest)
    closest = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, closest)
    closest = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, closest)
    closest = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, closest)
    return np.linalg.norm(points - closest, axis=1)
