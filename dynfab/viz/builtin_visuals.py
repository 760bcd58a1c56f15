"""How the built-in robots look: their URDFs (dynfab/robots/data) carry no visuals.

- The Panda (``panda``, the arm of ``boxer-panda``): Franka's visual meshes from
  ``example-robot-data`` (the ``view`` extra installs it), whose link frames
  ``panda_link0`` ... ``panda_link7`` are those of the built-in URDF. The built-in
  ``panda_hand`` is Franka's hand frame moved 0.1034 m along its z axis (to the TCP), so
  the hand mesh sits 0.1034 m behind it and the fingers (Franka's finger joints are
  0.0584 m along the hand's z) 0.045 m behind it, drawn 3 cm open.
- The Boxer: boxes, cylinders and spheres of the sizes its URDF's header gives (chassis
  0.74143 x 0.55093 x 0.2884 m on ``chassis_link``, drive wheels of radius 0.08 m,
  casters of radius 0.0625 m).
- The point robot: none (its collision sphere is drawn).
"""

from __future__ import annotations

import numpy as np
import trimesh

from dynfab.viz.robot_visuals import ROBOT_COLOR, LinkVisual, mesh_file

_FRANKA = "package://example-robot-data/robots/panda_description/meshes/visual/"
_HAND_BODY = 0.1034  # [m] from Franka's hand frame to the TCP (the built-in panda_hand)
_FINGER_BASE = 0.0584  # [m] Franka's finger joints along the hand's z
_FINGER_OPENING = 0.03  # [m] each finger's travel as drawn
_BOXER_CHASSIS = (0.74143, 0.55093, 0.2884)  # [m]
_DARK_GREY = (0.25, 0.25, 0.27)
_WHEEL_RADIUS, _WHEEL_WIDTH, _CASTER_RADIUS = 0.08, 0.04, 0.0625  # [m]


def builtin_visuals(name: str) -> tuple[tuple[LinkVisual, ...], tuple[str, ...]]:
    """The meshes of built-in robot ``name`` and the mesh URIs that were not found."""
    parts: list[LinkVisual | str] = []
    if name in ("boxer", "boxer-panda"):
        parts += _boxer()
    if name in ("panda", "boxer-panda"):
        parts += _panda()
    return (tuple(p for p in parts if isinstance(p, LinkVisual)), tuple(p for p in parts if isinstance(p, str)))


def _panda() -> list[LinkVisual | str]:
    placed = [(f"panda_link{i}", f"link{i}.dae", np.eye(4)) for i in range(8)]
    hand = _translation(0.0, 0.0, -_HAND_BODY)
    finger_z = _FINGER_BASE - _HAND_BODY
    right = _translation(0.0, -_FINGER_OPENING, finger_z) @ trimesh.transformations.rotation_matrix(np.pi, (0, 0, 1))
    placed += [("panda_hand", "hand.dae", hand), ("panda_hand", "finger.dae", _translation(0.0, _FINGER_OPENING, finger_z)),
               ("panda_hand", "finger.dae", right)]
    parts: list[LinkVisual | str] = []
    for link, filename, transform in placed:
        mesh = mesh_file(_FRANKA + filename, None)
        if isinstance(mesh, str):
            parts.append(f"link '{link}': {mesh}")
            continue
        mesh.apply_transform(transform)
        parts.append(LinkVisual(link, mesh, ROBOT_COLOR if filename != "hand.dae" else _DARK_GREY))
    return parts


def _boxer() -> list[LinkVisual | str]:
    chassis = trimesh.creation.box(extents=_BOXER_CHASSIS)
    chassis.apply_translation((0.0, 0.0, _BOXER_CHASSIS[2] / 2))
    parts: list[LinkVisual | str] = [LinkVisual("chassis_link", chassis, (0.85, 0.75, 0.15))]
    for side in ("left", "right"):
        wheel = trimesh.creation.cylinder(radius=_WHEEL_RADIUS, height=_WHEEL_WIDTH)
        wheel.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
        parts.append(LinkVisual(f"wheel_{side}_link", wheel, _DARK_GREY))
        caster = trimesh.creation.icosphere(subdivisions=2, radius=_CASTER_RADIUS)
        parts.append(LinkVisual(f"caster_{side}_link", caster, _DARK_GREY))
    return parts


def _translation(x: float, y: float, z: float) -> np.ndarray:
    return trimesh.transformations.translation_matrix((x, y, z))
