"""The ball a camera's points are cropped to: where a fixed-base robot's spheres can ever be.

A point farther from every position any robot collision sphere can take than the fabric's
range cannot move the robot (neither the nearest-point leaf nor the global planner's
checker, which tests the robot's own configurations), so a camera may drop it before any
other work (:class:`~dynfab.perception.depth_camera.DepthCamera`'s ``workspace``).

:func:`robot_workspace` bounds the reach from the URDF alone. On the chain from the root to
a sphere's link, the joints before the first movable one are fixed: they put that joint's
frame origin at a constant point ``f``. Rotations keep lengths, so each later joint origin
adds at most ``‖xyz_j‖``, a prismatic joint at most ``max(|lower|, |upper|)`` along its axis,
and the sphere its centre offset ``‖c‖`` and radius ``r``:

    ‖x(q) − f‖ + r <= Σ_j ‖xyz_j‖ + Σ_prismatic max(|lower|, |upper|) + ‖c‖ + r      [m]

for every ``q``. The ball is centred on the first such ``f`` met and holds every sphere's
bound (``‖f_i − f‖`` added for a sphere on another chain), grown by ``margin``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dynfab.robots.robot import Robot
from dynfab.robots.urdf_model import UrdfModel

__all__ = ["Workspace", "robot_workspace"]


@dataclass(frozen=True)
class Workspace:
    """A ball outside which a camera's points are dropped before anything else.

    Attributes:
        centre: Its centre (3,) [m, world frame].
        radius: Its radius [m].
    """

    centre: tuple[float, float, float]
    radius: float

    def __post_init__(self) -> None:
        try:
            centre = tuple(float(value) for value in self.centre)
            radius = float(self.radius)
        except (TypeError, ValueError):
            raise ValueError(f"workspace: expected a centre of three numbers and a radius, got "
                             f"{self.centre!r} and {self.radius!r}") from None
        if len(centre) != 3 or not all(math.isfinite(value) for value in centre):
            raise ValueError(f"workspace.centre: expected three finite numbers, got {self.centre}")
        if not (math.isfinite(radius) and radius > 0.0):
            raise ValueError(f"workspace.radius: must be a positive finite number, got {self.radius}")
        object.__setattr__(self, "centre", centre)
        object.__setattr__(self, "radius", radius)


def robot_workspace(robot: Robot, margin: float) -> Workspace:
    """The ball holding every collision sphere of ``robot`` in every configuration, grown by
    ``margin`` [m] (module docstring).

    Raises:
        ValueError: ``margin`` is negative, the robot is on a mobile base, or a joint's travel
            is unbounded (a prismatic joint without limits, a floating or planar joint); a
            robot without collision spheres. A prismatic joint's travel is read from its own
            limits, measured from 0.
    """
    if not margin >= 0.0:
        raise ValueError(f"margin must be >= 0, got {margin}")
    if robot.base is not None:
        raise ValueError(f"robot {robot.name!r} is on a mobile base: its reach has no fixed ball")
    if not robot.collision_spheres:
        raise ValueError(f"robot {robot.name!r} has no collision spheres: no reach to bound")
    model, kinematics = robot.kinematics.model, robot.kinematics
    zero = np.zeros(kinematics.dof)
    centre: np.ndarray | None = None
    bounds: list[tuple[np.ndarray, float]] = []
    for sphere in robot.collision_spheres:
        anchor, length = _chain_bound(model, sphere.link)
        if anchor is None:  # no joint moves this sphere: it stays where it is at q = 0
            fixed = np.asarray(kinematics.position(zero, sphere.link, offset=sphere.center), dtype=float).reshape(3)
            bounds.append((fixed, sphere.radius))
            continue
        origin = np.asarray(kinematics.position(zero, anchor), dtype=float).reshape(3)
        centre = origin if centre is None else centre
        bounds.append((origin, length + float(np.linalg.norm(sphere.center)) + sphere.radius))
    if centre is None:
        centre = bounds[0][0]
    radius = max(float(np.linalg.norm(point - centre)) + reach for point, reach in bounds)
    return Workspace(tuple(centre), radius + margin)


def _chain_bound(model: UrdfModel, link: str) -> tuple[str | None, float]:
    """The child link of the first movable joint from the root to ``link`` (None if none
    moves) and the sum of the later joints' ``‖xyz‖`` and prismatic travels [m]."""
    chain = []
    joint = model.parent_joint(link)
    while joint is not None:
        chain.append(joint)
        joint = model.parent_joint(joint.parent)
    chain.reverse()
    first = next((i for i, joint in enumerate(chain) if joint.type != "fixed"), None)
    if first is None:
        return None, 0.0
    length = 0.0
    for joint in chain[first:]:
        if joint is not chain[first]:
            length += float(np.linalg.norm(joint.origin.xyz))
        if joint.type in ("revolute", "continuous", "fixed"):
            continue
        if joint.type != "prismatic" or joint.limit is None:
            raise ValueError(f"joint {joint.name!r} ({joint.type}) has no bounded travel: no fixed reach")
        length += max(abs(joint.limit.lower), abs(joint.limit.upper))
    return chain[first].child, length
