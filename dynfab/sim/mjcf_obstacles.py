"""A scenario's obstacles as bodies of an MJCF document (for :mod:`dynfab.sim.mujoco_model`).

Obstacle ``k`` is the body ``obstacle<k>`` at its pose at t = 0: fixed in the world, or a
mocap body when it moves (the simulation sets its pose every physics step). Its geoms touch
robot geoms only (``contype`` 0, ``conaffinity`` the obstacle bit).

* A sphere, box, cylinder or capsule is one geom of that shape, named ``obstacle<k>``; for a
  planar robot a sphere is a vertical cylinder (the disc the planner sees). A plane is a box
  10 m wide filling its solid half-space.
* A mesh is its convex parts (:func:`dynfab.sim.mesh_parts.convex_parts`), geoms
  ``obstacle<k>_part<i>`` in geom group :data:`COLLISION_GROUP` (hidden from renderers, as
  MuJoCo's default visual options hide groups 3 to 5), and one visual geom ``obstacle<k>``
  of the whole mesh that touches nothing (``contype`` = ``conaffinity`` = 0): a depth camera
  sees the true surface, not the hulls, from either side (each triangle is written in both
  windings, as MuJoCo's renderer culls back faces and an open surface has two sides). Mesh
  assets are written inline (vertices, faces), with shell inertia (an open or flat mesh has
  no volume; obstacles have no mass anyway).
* A point cloud is no solid: its body has no geom. It is not in the physics nor in a
  camera's images; the planner knows it from the file and the metrics measure it.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from dynfab.geometry.shapes import Box, Capsule, Cylinder, Mesh, Plane, PointCloud, Sphere
from dynfab.sim.mesh_parts import convex_parts
from dynfab.sim.mjcf_values import mjcf_numbers
from dynfab.sim.mujoco_scene import SceneObstacle

__all__ = ["COLLISION_GROUP", "add_obstacle"]

#: Geom group of a mesh obstacle's convex parts (renderers hide it by default).
COLLISION_GROUP = 3
_OBSTACLE_RGBA = "0.2 0.4 0.9 0.8"


def add_obstacle(world: ET.Element, asset: ET.Element, k: int, obstacle: SceneObstacle, planar: bool,
                 conaffinity: int) -> None:
    """Add the body of obstacle ``k`` (module doc) to ``world``, its mesh assets to ``asset``."""
    pose = {"pos": mjcf_numbers(obstacle.position), "quat": mjcf_numbers(obstacle.orientation)}
    if obstacle.moving:
        pose["mocap"] = "true"
    shape = obstacle.shape
    body = ET.SubElement(world, "body", name=f"obstacle{k}", **pose)
    if isinstance(shape, PointCloud):
        return
    touching = {"contype": "0", "conaffinity": str(conaffinity), "rgba": _OBSTACLE_RGBA}
    if isinstance(shape, Mesh):
        _mesh_geoms(body, asset, k, shape, touching)
        return
    ET.SubElement(body, "geom", name=f"obstacle{k}", **_primitive(shape, planar), **touching)


def _primitive(shape: Sphere | Box | Cylinder | Capsule | Plane, planar: bool) -> dict[str, str]:
    """The ``type``, ``size`` (and a plane's ``pos``) of a primitive's geom."""
    if isinstance(shape, Sphere) and planar:
        return {"type": "cylinder", "size": f"{shape.radius} 1"}
    if isinstance(shape, Sphere):
        return {"type": "sphere", "size": repr(shape.radius)}
    if isinstance(shape, Box):
        return {"type": "box", "size": mjcf_numbers(np.array(shape.size) / 2)}
    if isinstance(shape, Cylinder):
        return {"type": "cylinder", "size": f"{shape.radius} {shape.length / 2}"}
    if isinstance(shape, Capsule):
        return {"type": "capsule", "size": f"{shape.radius} {shape.length / 2}"}
    return {"type": "box", "size": "5 5 5", "pos": "0 0 -5"}  # the solid half-space, 10 m wide


def _mesh_geoms(body: ET.Element, asset: ET.Element, k: int, mesh: Mesh, touching: dict[str, str]) -> None:
    """The convex parts (collision) and the whole mesh (visual) of mesh obstacle ``k``."""
    for i, part in enumerate(convex_parts(mesh)):
        name = f"obstacle{k}_part{i}"
        ET.SubElement(asset, "mesh", name=name, vertex=mjcf_numbers(part.reshape(-1)), inertia="shell")
        ET.SubElement(body, "geom", name=name, type="mesh", mesh=name, group=str(COLLISION_GROUP), **touching)
    vertices = mesh.vertices
    if len(vertices) < 4:  # MuJoCo wants four vertices: a lone triangle gets its centroid, unused
        vertices = np.vstack([vertices, vertices.mean(axis=0)])
    faces = np.concatenate([mesh.faces, mesh.faces[:, ::-1]])  # both windings: MuJoCo culls back faces
    ET.SubElement(asset, "mesh", name=f"obstacle{k}", vertex=mjcf_numbers(vertices.reshape(-1)),
                  face=" ".join(str(int(i)) for i in faces.reshape(-1)), inertia="shell")
    ET.SubElement(body, "geom", name=f"obstacle{k}", type="mesh", mesh=f"obstacle{k}", contype="0",
                  conaffinity="0", rgba=touching["rgba"])
