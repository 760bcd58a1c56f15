"""Robot descriptions: kinematics plus what the planner needs to keep it safe."""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .kinematics import CasadiLike, Kinematics, UnknownLinkError

__all__ = ["CollisionSphere", "Robot"]


@dataclass(frozen=True)
class CollisionSphere:
    """A sphere fixed in a link that bounds part of the robot's body.

    Attributes:
        link: Link carrying the sphere.
        center: Centre in link coordinates [m].
        radius: Radius [m], positive.
    """

    link: str
    center: tuple[float, float, float]
    radius: float

    def __post_init__(self) -> None:
        center = tuple(float(x) for x in self.center)
        if len(center) != 3 or not all(math.isfinite(x) for x in center):
            raise ValueError(f"collision sphere on '{self.link}': center must be three "
                             f"finite numbers, got {self.center}")
        if not (math.isfinite(self.radius) and self.radius > 0.0):
            raise ValueError(f"collision sphere on '{self.link}': radius must be "
                             f"positive, got {self.radius}")
        object.__setattr__(self, "center", center)
        object.__setattr__(self, "radius", float(self.radius))


@dataclass(frozen=True, eq=False)
class Robot:
    """A robot as the planner sees it.

    Attributes:
        name: Robot name.
        kinematics: Forward kinematics of the robot's tree.
        goal_link: Link whose position goals refer to (end effector).
        collision_spheres: Spheres bounding the body, used against obstacles.
        self_collision_pairs: Index pairs into ``collision_spheres`` that must not
            overlap each other.
        planar: If True the workspace is the xy-plane: goals are [x, y] and obstacles
            act as discs.
        default_q: Default configuration, shape (dof,) [rad or m], read-only.
    """

    name: str
    kinematics: Kinematics
    goal_link: str
    collision_spheres: tuple[CollisionSphere, ...]
    self_collision_pairs: tuple[tuple[int, int], ...]
    planar: bool
    default_q: np.ndarray

    def __post_init__(self) -> None:
        kin = self.kinematics
        for link in [self.goal_link] + [s.link for s in self.collision_spheres]:
            if link not in kin.link_names:
                raise UnknownLinkError(f"robot '{self.name}': unknown link '{link}'; "
                                       f"valid links: {', '.join(kin.link_names)}")
        count = len(self.collision_spheres)
        pairs = tuple((int(a), int(b)) for a, b in self.self_collision_pairs)
        for a, b in pairs:
            if not (0 <= a < count and 0 <= b < count) or a == b:
                raise ValueError(f"robot '{self.name}': self-collision pair ({a}, {b}) "
                                 f"must index two different spheres of {count}")
        default_q = np.array(self.default_q, dtype=float).reshape(-1)
        if default_q.size != kin.dof:
            raise ValueError(f"robot '{self.name}': default_q must have {kin.dof} "
                             f"elements, got {default_q.size}")
        default_q.setflags(write=False)
        object.__setattr__(self, "collision_spheres", tuple(self.collision_spheres))
        object.__setattr__(self, "self_collision_pairs", pairs)
        object.__setattr__(self, "default_q", default_q)

    @property
    def dof(self) -> int:
        """Number of configuration variables."""
        return self.kinematics.dof

    @property
    def sphere_radii(self) -> np.ndarray:
        """Radii of the collision spheres, shape (k,) [m]."""
        return np.array([s.radius for s in self.collision_spheres], dtype=float)

    def sphere_centers(self, q: object) -> CasadiLike | np.ndarray:
        """Centres of the collision spheres in the root frame, shape (k, 3) [m].

        Args:
            q: Configuration, shape (dof,): ``ca.SX`` or ``ca.MX`` (then the result is
                of that type) or array-like numbers (then a numpy array).
        """
        points = [(s.link, s.center) for s in self.collision_spheres]
        centers = self.kinematics.positions(q, points)
        if isinstance(q, (ca.SX, ca.MX)):
            return centers
        return np.array(centers, dtype=float).reshape(len(points), 3)
