"""A triangle mesh as an obstacle shape: vertices and faces in the shape's own frame.

Placed like every shape (:class:`dynfab.geometry.shapes.Placement`: ``x = R x_s + p``). A
mesh need not be closed: an open surface (a cupboard's panels, a scanned scene) is a valid
obstacle; the robot keeps away from its triangles, from either side. A closed (watertight)
mesh also has an inside, which signed distances report as negative
(:mod:`dynfab.geometry.mesh_distance`).

The derived structures (trimesh object, coal BVH, the checker's distance grid) are built on
first use and kept on the value, so a mesh placed many times is prepared once.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    import trimesh

__all__ = ["Mesh"]


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh in its own frame [m].

    Attributes:
        vertices: (V, 3) vertex coordinates [m], finite (read-only).
        faces: (F, 3) vertex indices of each triangle, F >= 1 (read-only); triangles without
            area (collinear corners) are dropped on construction.
        source: Where it came from (a file name), for messages.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    source: str = field(default="")

    def __post_init__(self) -> None:
        vertices = np.array(self.vertices, dtype=float).reshape(-1, 3)
        faces = np.array(self.faces, dtype=np.int64).reshape(-1, 3)
        if len(faces) == 0:
            raise ValueError(f"mesh {self.source} has no triangles")
        if not np.isfinite(vertices).all():
            raise ValueError(f"mesh {self.source} has NaN or infinite vertices")
        if faces.min() < 0 or faces.max() >= len(vertices):
            raise ValueError(f"mesh {self.source} has faces that index missing vertices")
        corners = vertices[faces]
        areas = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
        faces = faces[areas > 1e-12]  # degenerate triangles bound nothing, and coal's distances fail on them
        if len(faces) == 0:
            raise ValueError(f"mesh {self.source} has no triangles with an area")
        vertices.setflags(write=False)
        faces.setflags(write=False)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "faces", faces)

    @property
    def dimensions(self) -> tuple[float, ...]:
        """No sizes: the vertices are the geometry."""
        return ()

    @cached_property
    def triangles(self) -> trimesh.Trimesh:
        """The mesh as a :class:`trimesh.Trimesh` (not processed: vertices as given)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)

    @cached_property
    def solid(self) -> trimesh.Trimesh | None:
        """The mesh with its coincident vertices merged if that closes it (every edge
        shared by exactly two faces), for inside tests; None for an open surface. An STL
        file repeats every vertex in each face that has it, so :attr:`triangles` of a
        closed STL mesh is open: it must be merged to see its inside."""
        import trimesh

        merged = trimesh.Trimesh(self.vertices, self.faces, process=False)
        merged.merge_vertices()
        return merged if merged.is_watertight else None

    @property
    def watertight(self) -> bool:
        """Whether the mesh is closed once its coincident vertices are merged (:attr:`solid`):
        then it has an inside."""
        return self.solid is not None

    @cached_property
    def bounding_radius(self) -> float:
        """Radius [m] of the ball about the frame origin that holds every vertex."""
        return float(np.max(np.linalg.norm(self.vertices, axis=1)))

    @cached_property
    def bounds(self) -> NDArray[np.float64]:
        """(2, 3): the lowest and highest vertex coordinates per axis [m] (read-only, kept:
        the mesh queries ask it every call, 1 ms on a 12 k-vertex mesh)."""
        bounds = np.array([self.vertices.min(axis=0), self.vertices.max(axis=0)])
        bounds.setflags(write=False)
        return bounds
