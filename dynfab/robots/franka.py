"""Franka's Panda as example-robot-data ships it, and what dynfab's built-in Panda shares
with it: the frames of ``panda_link0`` ... ``panda_link7``, of the hand body (Franka's
``panda_hand``, dynfab's ``panda_hand_body``; dynfab's ``panda_hand`` is the point between
the fingertips, Franka's ``panda_hand_tcp``) and of the fingers ``panda_leftfinger`` /
``panda_rightfinger`` on the prismatic ``panda_finger_joint1`` (``panda_finger_joint2``
mimics it), opening ``0 <= s <= 0.04`` m per finger.

example-robot-data is in the ``robots`` / ``test`` extras, not the core: without it
:func:`franka_link_meshes` returns None.
"""

from __future__ import annotations

import functools
from pathlib import Path

import trimesh

from .kinematics import Kinematics
from .link_meshes import link_collision_meshes
from .mesh_paths import resolve_uri
from .urdf import load_urdf

__all__ = ["DYNFAB_LINKS", "FINGER_JOINT", "FINGER_RANGE", "OPEN", "PANDA_JOINTS", "PANDA_URDF",
           "franka_kinematics", "franka_link_meshes", "franka_urdf"]

#: Franka's Panda description as example-robot-data ships it.
PANDA_URDF = "package://example-robot-data/robots/panda_description/urdf/panda.urdf"
#: The arm's joints, the planner's coordinates.
PANDA_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
#: The finger joint a scenario sets (locked); the other finger mimics it.
FINGER_JOINT = "panda_finger_joint1"
#: Franka's limits of the opening per finger [m].
FINGER_RANGE = (0.0, 0.04)
#: The default opening per finger: open, the hand before a grasp [m].
OPEN = 0.04
#: Franka's link with collision geometry -> dynfab's link with the same frame.
DYNFAB_LINKS: dict[str, str] = {**{f"panda_link{i}": f"panda_link{i}" for i in range(8)},
                                "panda_hand": "panda_hand_body", "panda_leftfinger": "panda_leftfinger",
                                "panda_rightfinger": "panda_rightfinger"}


def franka_urdf() -> Path | None:
    """The path of example-robot-data's ``panda.urdf``; None if it is not installed."""
    return resolve_uri(PANDA_URDF, None)


def franka_kinematics(fingers: float = OPEN) -> Kinematics:
    """Kinematics of example-robot-data's Panda: the arm joints active, the fingers locked
    at ``fingers`` [m] per finger.

    Raises:
        FileNotFoundError: example-robot-data is not installed.
    """
    path = franka_urdf()
    if path is None:
        raise FileNotFoundError(f"{PANDA_URDF}: install dynfab[robots] (example-robot-data)")
    return Kinematics(load_urdf(path), joints=PANDA_JOINTS, locked={FINGER_JOINT: fingers})


def franka_link_meshes() -> dict[str, list[trimesh.Trimesh]] | None:
    """Franka's collision meshes by dynfab link name, each in its link's frame; None
    without example-robot-data."""
    loaded = _loaded_meshes()
    return None if loaded is None else {link: [mesh.copy() for mesh in meshes] for link, meshes in loaded.items()}


@functools.cache
def _loaded_meshes() -> dict[str, tuple[trimesh.Trimesh, ...]] | None:
    """The meshes, read once per process."""
    path = franka_urdf()
    if path is None:
        return None
    model = load_urdf(path)
    return {dynfab: tuple(link_collision_meshes(model, franka)) for franka, dynfab in DYNFAB_LINKS.items()}
