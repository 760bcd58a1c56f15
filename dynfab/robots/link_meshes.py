"""The collision geometry of a link as triangle meshes in the link frame (trimesh).

Each ``<collision>`` of a link becomes one :class:`trimesh.Trimesh`, already placed by its
origin and scaled: boxes, cylinders and spheres are tessellated, meshes are read from the
resolved file (STL, OBJ, DAE, ... whatever trimesh reads). Coordinates are metres in the
link frame.
"""

from __future__ import annotations

import functools

import numpy as np
import trimesh

from dynfab.geometry.shapes import Box, Cylinder, Sphere

from .urdf import CollisionGeometry, MeshFile, UrdfError, UrdfModel

__all__ = ["LinkMeshError", "collision_mesh", "link_collision_meshes"]

#: Tessellation of primitives: cylinder sections and icosphere subdivisions.
_CYLINDER_SECTIONS = 32
_SPHERE_SUBDIVISIONS = 3


class LinkMeshError(UrdfError):
    """A collision mesh that is missing or cannot be read, or a link without geometry."""


def link_collision_meshes(model: UrdfModel, link: str) -> list[trimesh.Trimesh]:
    """Every collision geometry of ``link`` as a mesh in the link frame [m].

    Returns an empty list for a link without ``<collision>`` elements.

    Raises:
        LinkMeshError: A mesh file that was not found or that trimesh cannot read; the
            message names the link and the URI.
        KeyError: ``link`` is not a link of ``model``.
    """
    links = {entry.name: entry for entry in model.links}
    return [collision_mesh(geometry, link) for geometry in links[link].collisions]


def collision_mesh(geometry: CollisionGeometry, link: str) -> trimesh.Trimesh:
    """One collision geometry as a mesh in the link frame (see :func:`link_collision_meshes`)."""
    shape = geometry.shape
    if isinstance(shape, MeshFile):
        mesh = _read_mesh(shape, link).copy()
        mesh.apply_scale(np.array(shape.scale))
    elif isinstance(shape, Box):
        mesh = trimesh.creation.box(extents=shape.size)
    elif isinstance(shape, Cylinder):
        mesh = trimesh.creation.cylinder(radius=shape.radius, height=shape.length,
                                         sections=_CYLINDER_SECTIONS)
    elif isinstance(shape, Sphere):
        mesh = trimesh.creation.icosphere(subdivisions=_SPHERE_SUBDIVISIONS, radius=shape.radius)
    else:
        raise LinkMeshError(f"link '{link}': unsupported collision geometry {type(shape).__name__}")
    transform = np.eye(4)
    transform[:3, :3] = np.array(geometry.origin.rotation)
    transform[:3, 3] = geometry.origin.xyz
    mesh.apply_transform(transform)
    return mesh


def _read_mesh(shape: MeshFile, link: str) -> trimesh.Trimesh:
    if shape.path is None:
        raise LinkMeshError(f"link '{link}': collision mesh '{shape.uri}' not found (give the folder "
                            "that holds its package in package_dirs or DYNFAB_PACKAGE_PATH)")
    try:
        return load_mesh_file(shape.path)
    except Exception as exc:  # trimesh raises many kinds of errors on bad files
        raise LinkMeshError(f"link '{link}': collision mesh '{shape.uri}' cannot be read "
                            f"({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})") from None


@functools.lru_cache(maxsize=256)
def load_mesh_file(path: str) -> trimesh.Trimesh:
    """A mesh file as one triangle mesh (scenes are concatenated); cached per path, so
    callers that change it must copy it first."""
    loaded = trimesh.load(path, force="mesh", process=False)
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError("no triangles in the file")
    return loaded
