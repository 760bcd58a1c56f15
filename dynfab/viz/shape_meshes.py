"""Obstacle shapes (:mod:`dynfab.geometry.shapes`) as triangle meshes in their own frame."""

from __future__ import annotations

import trimesh

from dynfab.geometry.shapes import Box, Capsule, Cylinder, Plane, Shape, Sphere

#: Side of the square that draws a plane [m] (the solid half-space is unbounded).
PLANE_SIDE = 3.0
#: Thickness of the slab under a plane's surface [m].
PLANE_THICKNESS = 0.01


def shape_mesh(shape: Shape, planar: bool = False) -> trimesh.Trimesh:
    """The triangles of ``shape`` in its frame [m].

    A sphere seen by a planar robot is a disc: drawn as an upright cylinder of the
    sphere's radius and diameter. A plane is a :data:`PLANE_SIDE` square slab just below
    its surface (z <= 0 of its frame is solid).
    """
    if isinstance(shape, Sphere):
        if planar:
            return trimesh.creation.cylinder(radius=shape.radius, height=2.0 * shape.radius)
        return trimesh.creation.icosphere(subdivisions=3, radius=shape.radius)
    if isinstance(shape, Box):
        return trimesh.creation.box(extents=shape.size)
    if isinstance(shape, Cylinder):
        return trimesh.creation.cylinder(radius=shape.radius, height=shape.length)
    if isinstance(shape, Capsule):
        return trimesh.creation.capsule(height=shape.length, radius=shape.radius)
    if isinstance(shape, Plane):
        slab = trimesh.creation.box(extents=(PLANE_SIDE, PLANE_SIDE, PLANE_THICKNESS))
        slab.apply_translation((0.0, 0.0, -PLANE_THICKNESS / 2))
        return slab
    raise TypeError(f"no mesh for {type(shape).__name__}")
