"""The compiled checker's obstacle buffer (``checker_kernel.c``): one row of 17 numbers per
obstacle, then the distance grids of its meshes and point clouds.

A row is ``[kind, centre (3), rotation (9, row-major), dimensions (3), bounding radius]``,
kinds 0-6 for sphere, box, cylinder, capsule, plane, mesh and point cloud (a focused cloud
is a cloud on a finer grid). A gridded obstacle's ``dimensions[0]`` is the offset [doubles]
of its grid (:meth:`~dynfab.geometry.distance_grid.DistanceGrid.packed`) from the row's
start; the radius bounds the shape about its origin (a plane: 0, the kernel does not read it).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.cloud_grid import cloud_distance_grid
from dynfab.geometry.distance_grid import DistanceGrid, distance_grid
from dynfab.geometry.exact_collision import shape_bounding_radius
from dynfab.geometry.focused_cloud import FocusedCloud
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Mesh, Plane, PointCloud, Sphere
from dynfab.motion.placed_obstacle import PlacedObstacle
from dynfab.robots.collision_model import cache_dir

__all__ = ["ROW", "gridded", "mesh_grid", "obstacle_buffer", "obstacle_row", "same_grids"]

#: numbers per obstacle row
ROW = 17
#: the kernel's code of each shape
_KIND: dict[type, int] = {Sphere: 0, Box: 1, Cylinder: 2, Capsule: 3, Plane: 4, Mesh: 5, PointCloud: 6,
                          FocusedCloud: 6}


def gridded(obstacle: PlacedObstacle) -> bool:
    """Whether the kernel reads ``obstacle`` from a distance grid (a mesh or a point cloud)."""
    return isinstance(obstacle.shape, Mesh | PointCloud)


def same_grids(old: Sequence[PlacedObstacle], new: Sequence[PlacedObstacle]) -> bool:
    """Whether ``new`` has as many obstacles as ``old`` and the same gridded shapes (the same
    objects) at the same places: then the buffer's grids serve it as they are."""
    return len(old) == len(new) and all(
        gridded(a) == gridded(b) and (not gridded(a) or a.shape is b.shape) for a, b in zip(old, new))


def obstacle_buffer(obstacles: Sequence[PlacedObstacle]) -> NDArray[np.float64]:
    """The buffer of ``obstacles`` (module docstring): their rows, then their grids, each
    gridded row's ``dimensions[0]`` its grid's offset."""
    rows = np.array([obstacle_row(o) for o in obstacles]).reshape(-1, ROW)
    grids = []
    end = rows.size
    for k, obstacle in enumerate(obstacles):
        if gridded(obstacle):
            shape = obstacle.shape
            grid = (mesh_grid(shape) if isinstance(shape, Mesh) else _cloud_grid(shape)).packed()
            rows[k, 13] = end - ROW * k
            grids.append(grid)
            end += grid.size
    return np.ascontiguousarray(np.concatenate([rows.reshape(-1), *grids]))


def mesh_grid(mesh: Mesh) -> DistanceGrid:
    """The lower-bound grid the checker reads ``mesh`` from (kept on the mesh and on disk:
    :func:`~dynfab.geometry.distance_grid.distance_grid`)."""
    return distance_grid(mesh, cache=cache_dir() / "distance-grids")


def obstacle_row(obstacle: PlacedObstacle) -> NDArray[np.float64]:
    """The row of ``obstacle`` (module docstring; a gridded one's offset is set by
    :func:`obstacle_buffer`)."""
    row = np.zeros(ROW)
    row[0] = _KIND[type(obstacle.shape)]
    row[1:4] = obstacle.placement.position
    row[4:13] = obstacle.placement.rotation.reshape(-1)
    dimensions = obstacle.shape.dimensions
    row[13:13 + len(dimensions)] = dimensions
    row[16] = 0.0 if isinstance(obstacle.shape, Plane) else shape_bounding_radius(obstacle.shape)
    return row


def _cloud_grid(cloud: PointCloud) -> DistanceGrid:
    """A cloud's grid: a focused cloud's at its pitch (:mod:`dynfab.geometry.focused_cloud`)."""
    if isinstance(cloud, FocusedCloud):
        return cloud_distance_grid(cloud, pitch=cloud.pitch)
    return cloud_distance_grid(cloud)
