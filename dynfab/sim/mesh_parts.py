"""Convex parts of a mesh obstacle, for MuJoCo's collisions.

MuJoCo collides a mesh geom by the convex hull of its vertices, so a mesh obstacle becomes
several convex geoms whose union covers its surface:

* each connected component (triangles sharing vertices) that is closed and convex (every
  edge convex, or its volume that of its hull to a relative 1e-6) is one part, its own
  hull: exact;
* every triangle of any other component (open, non-convex, a lone triangle) is one part, a
  prism: the triangle moved by ``± SHELL / 2`` along its unit normal ``n``, corners
  ``c_i ± (SHELL / 2) n`` [m]. The union of the prisms is the surface thickened by
  ``SHELL / 2`` on each side: MuJoCo touches it at most ``SHELL / 2`` before the true surface
  (the metrics', :mod:`dynfab.scenario.exact_metrics`), never after.

No convex decomposition library is used (CoACD, V-HACD: not dependencies here, not tried;
their hulls approximate the shape within a tolerance, which may overstate it): a shelf's or
MBM's kitchen meshes are closed convex pieces and a few hundred other triangles at most, one
prism each. A mesh may have at most
:data:`MAX_PARTS` parts: more geoms make every physics step slower (and the prisms of 10⁶
triangles would take 144 MB); the scenario loader refuses such a mesh under MuJoCo
(:mod:`dynfab.scenario.mujoco_obstacles`).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import trimesh
from numpy.typing import NDArray

from dynfab.geometry.mesh_shape import Mesh

__all__ = ["MAX_PARTS", "SHELL", "TooManyPartsError", "convex_parts"]

#: Thickness [m] of the prism made of a triangle (half of it on each side of the surface).
SHELL = 0.001
#: Most convex parts (MuJoCo geoms) one mesh obstacle may become.
MAX_PARTS = 5000
#: Relative volume a closed component may miss of its hull and still count as convex.
_VOLUME_TOLERANCE = 1e-6


class TooManyPartsError(ValueError):
    """A mesh would become more than :data:`MAX_PARTS` convex parts.

    Attributes:
        parts: How many it would become.
    """

    def __init__(self, mesh: Mesh, parts: int) -> None:
        super().__init__(f"mesh {mesh.source} becomes {parts} convex parts in MuJoCo (one per triangle of a "
                         f"component that is not closed and convex), more than {MAX_PARTS}; simplify it or "
                         "split it into convex pieces")
        self.parts = parts


@lru_cache(maxsize=64)
def convex_parts(mesh: Mesh) -> tuple[NDArray[np.float64], ...]:
    """The vertices (k, 3) of each convex part of ``mesh`` in its frame [m] (module doc):
    the closed convex components' first, then one prism (6, 3) per other triangle.

    Raises:
        TooManyPartsError: More than :data:`MAX_PARTS` parts (counted before any prism is made).
    """
    merged = trimesh.Trimesh(np.array(mesh.vertices), np.array(mesh.faces), process=True)
    hulls: list[NDArray[np.float64]] = []
    others: list[trimesh.Trimesh] = []
    for component in merged.split(only_watertight=False, repair=False):
        if _closed_convex(component):
            hulls.append(np.array(component.vertices, dtype=float))
        else:
            others.append(component)
    parts = len(hulls) + sum(len(component.faces) for component in others)
    if parts > MAX_PARTS:
        raise TooManyPartsError(mesh, parts)
    corners = [np.array(component.vertices, dtype=float)[component.faces] for component in others]
    prisms = _prisms(np.concatenate(corners)) if corners else []
    return tuple(hulls) + tuple(prisms)


def _closed_convex(component: trimesh.Trimesh) -> bool:
    """Whether ``component`` is closed, consistently wound and convex: every edge convex
    (trimesh's test), or its volume |V| >= (1 - :data:`_VOLUME_TOLERANCE`) V_hull (the solid
    lies in its hull, so equal volumes make them one; this holds for either winding, as
    files come)."""
    if not (component.is_watertight and component.is_winding_consistent) or len(component.vertices) < 4:
        return False
    if component.is_convex:
        return True
    hull = component.convex_hull.volume
    return hull > 0.0 and abs(component.volume) >= (1.0 - _VOLUME_TOLERANCE) * hull


def _prisms(corners: NDArray[np.float64]) -> list[NDArray[np.float64]]:
    """One prism (6, 3) per triangle of ``corners`` (F, 3, 3): the corners moved by
    ``± SHELL / 2`` along the triangle's unit normal."""
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    keep = lengths > 0.0  # a triangle that merging vertices made degenerate bounds nothing
    corners, normals = corners[keep], normals[keep] / lengths[keep, None]
    offset = 0.5 * SHELL * normals[:, None, :]
    return list(np.concatenate([corners + offset, corners - offset], axis=1))
