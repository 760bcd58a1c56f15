"""Collision meshes of URDF links as STL files MuJoCo can read.

MuJoCo reads STL, OBJ and MSH, not COLLADA (.dae), which many URDFs ship. Each link's
``<collision>`` elements are tessellated or read with trimesh
(:func:`dynfab.robots.link_meshes.link_collision_meshes`), merged into one mesh in the
link frame [m] (:func:`link_mesh_file`; meshes given for a built-in robot whose description
has none, :mod:`dynfab.robots.builtin_meshes`, go one by one through :func:`mesh_file`) and
written once to ``$DYNFAB_CACHE_DIR/mujoco-meshes/<sha256>.stl``
(``~/.cache/dynfab`` by default), keyed by the vertices and faces. MuJoCo collides the
convex hull of each mesh.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import trimesh

from dynfab.robots.collision_model import cache_dir
from dynfab.robots.link_meshes import link_collision_meshes
from dynfab.robots.urdf import UrdfModel

__all__ = ["link_mesh_file", "mesh_file"]


def link_mesh_file(model: UrdfModel, link: str) -> Path | None:
    """The STL file of ``link``'s collision geometry in its frame, or None without any.

    Raises:
        LinkMeshError: A mesh file is missing or unreadable (names the link).
    """
    meshes = link_collision_meshes(model, link)
    return mesh_file(meshes) if meshes else None


def mesh_file(meshes: Sequence[trimesh.Trimesh]) -> Path:
    """The STL file of ``meshes`` (at least one, in one link's frame [m]) merged into one.

    Raises:
        ValueError: ``meshes`` is empty.
    """
    if not meshes:
        raise ValueError("a link's mesh file needs at least one mesh")
    merged = trimesh.util.concatenate(list(meshes)) if len(meshes) > 1 else meshes[0]
    vertices = np.ascontiguousarray(merged.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(merged.faces, dtype=np.int64)
    digest = hashlib.sha256(vertices.tobytes() + faces.tobytes()).hexdigest()
    path = cache_dir() / "mujoco-meshes" / f"{digest}.stl"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_suffix(f".{digest[:8]}.part")
        trimesh.Trimesh(vertices=vertices, faces=faces, process=False).export(partial, file_type="stl")
        partial.replace(path)
    return path
