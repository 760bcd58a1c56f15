"""Mesh files read into :class:`~dynfab.geometry.mesh_shape.Mesh` values, in bounded time
and memory.

Any format trimesh reads as triangles (STL, OBJ, DAE, PLY, GLB, OFF, ...); a file with
several bodies (a DAE or OBJ scene) becomes one mesh of all their triangles, in the file's
frame. Limits: a file larger than :data:`MAX_MESH_BYTES` is refused before it is read, and a
mesh of more than :data:`MAX_MESH_FACES` triangles after (simplify it first: the nearest
points of a 10⁶-face mesh cost tens of microseconds per robot sphere).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from dynfab.geometry.bounded_files import bounded_file
from dynfab.geometry.mesh_shape import Mesh

__all__ = ["MAX_MESH_BYTES", "MAX_MESH_FACES", "MeshFileError", "read_mesh"]

#: Largest mesh file read [bytes] (a binary STL of 4 million triangles).
MAX_MESH_BYTES = 200_000_000
#: Most triangles a mesh obstacle may have.
MAX_MESH_FACES = 1_000_000


class MeshFileError(ValueError):
    """A mesh file that is missing, unreadable, too large, or holds no triangles."""


def read_mesh(path: str | os.PathLike[str], scale: Sequence[float] = (1.0, 1.0, 1.0)) -> Mesh:
    """The triangles of a mesh file, scaled per axis about the file's origin.

    Args:
        path: The file.
        scale: Factor per axis (> 0) [-].

    Raises:
        MeshFileError: the file is missing, larger than :data:`MAX_MESH_BYTES`, cannot be
            read as triangles, has none (or none with an area), more than
            :data:`MAX_MESH_FACES`, or non-finite vertices; the message says which.
    """
    import trimesh

    path = bounded_file(path, MAX_MESH_BYTES, "a mesh file", "simplify it", MeshFileError)
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds of errors on bad files
        first = str(exc).splitlines()[0] if str(exc) else ""
        raise MeshFileError(f"{path.name} cannot be read as a mesh ({type(exc).__name__}: {first})") from None
    faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))))
    if not isinstance(loaded, trimesh.Trimesh) or len(faces) == 0:
        raise MeshFileError(f"{path.name} has no triangles (a point cloud or an empty file is not a mesh)")
    if len(faces) > MAX_MESH_FACES:
        raise MeshFileError(f"{path.name} has {len(faces)} triangles, more than {MAX_MESH_FACES} (simplify it)")
    vertices = np.asarray(loaded.vertices, dtype=float) * np.asarray(scale, dtype=float)
    if not np.isfinite(vertices).all():
        raise MeshFileError(f"{path.name} has NaN or infinite vertices")
    try:
        return Mesh(vertices, faces, source=path.name)
    except ValueError as error:  # faces that index missing vertices, or none with an area
        raise MeshFileError(str(error).replace(f"mesh {path.name}", path.name)) from None
