"""Collision meshes of the built-in robots, whose own descriptions carry none, so that a
run of ``panda`` or ``boxer-panda`` is measured on meshes as URDF robots are
(:mod:`dynfab.scenario.exact_metrics`):

- the Panda's links ``panda_link0`` ... ``panda_link7``, ``panda_hand_body`` and the two
  fingers: Franka's collision meshes as example-robot-data ships them (same frames,
  :mod:`dynfab.robots.franka`; the fingers where the robot's locked finger joint puts them);
- the Boxer's ``chassis_link``: Clearpath's collision box of the body, 0.74143 x 0.55093 x
  0.2884 m, from the link's origin (the centre of the bottom face) up (the wheels lie
  inside its footprint).

Without example-robot-data there are no Panda meshes: :func:`builtin_collision_meshes`
returns None and the run keeps the sphere figures.
"""

from __future__ import annotations

import numpy as np
import trimesh

from .franka import franka_link_meshes
from .robot import Robot

__all__ = ["BOXER_BODY_BOX", "MESHED_BUILTINS", "builtin_collision_meshes"]

#: Clearpath's collision box of the Boxer's body (x, y, z) [m].
BOXER_BODY_BOX = (0.74143, 0.55093, 0.2884)
#: Built-in robots measured on meshes (when example-robot-data is installed).
MESHED_BUILTINS = ("panda", "boxer-panda")


def builtin_collision_meshes(robot: Robot) -> dict[str, list[trimesh.Trimesh]] | None:
    """The meshes of a built-in ``robot`` by link, each in its link's frame; None for a
    robot not in :data:`MESHED_BUILTINS`, one whose description has collision geometry of
    its own (a URDF robot named like a built-in one), or without example-robot-data."""
    if robot.name not in MESHED_BUILTINS or any(link.collisions for link in robot.kinematics.model.links):
        return None
    meshes = franka_link_meshes()
    if meshes is None:
        return None
    if "chassis_link" in robot.kinematics.link_names:
        body = trimesh.creation.box(extents=BOXER_BODY_BOX)
        body.apply_translation(np.array([0.0, 0.0, BOXER_BODY_BOX[2] / 2]))
        meshes["chassis_link"] = [body]
    return meshes
