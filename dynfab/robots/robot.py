"""Robot descriptions: kinematics plus what the planner needs to keep it safe."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cached_property

import casadi as ca
import numpy as np

from .kinematics import CasadiLike, Kinematics, UnknownLinkError
from .limits import MotionLimits, limits_from_joints

__all__ = ["BASE_JOINTS", "CollisionSphere", "DifferentialDriveBase", "Robot"]

#: Names of the three planar base joints a robot with a mobile base has first, in order:
#: ``base_x`` (prismatic along world x), ``base_y`` (prismatic along world y),
#: ``base_yaw`` (revolute or continuous about z).
BASE_JOINTS: tuple[str, str, str] = ("base_x", "base_y", "base_yaw")


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


@dataclass(frozen=True)
class DifferentialDriveBase:
    """A differential-drive mobile base: two driven wheels on a common axle.

    The base's pose is the planar pose ``(x, y, yaw)`` of the axle midpoint; its
    actuated velocities are the forward speed ``v`` along the heading and the yaw rate
    ``omega`` (unicycle model), which the two wheels realise without slip as
    ``omega_left = (v - omega b / 2) / r`` and ``omega_right = (v + omega b / 2) / r``
    (``r`` wheel radius, ``b`` wheel separation; see e.g. Siegwart, Nourbakhsh and
    Scaramuzza, *Introduction to Autonomous Mobile Robots*, 2nd ed., chapter 3).

    Attributes:
        wheel_radius: Radius of the driven wheels [m], positive.
        wheel_separation: Distance between the two driven wheels' contact points
            along the axle (track width) [m], positive.
        max_forward_speed: Largest absolute forward speed ``|v|`` [m/s], positive.
        max_yaw_rate: Largest absolute yaw rate ``|omega|`` [rad/s], positive.
    """

    wheel_radius: float
    wheel_separation: float
    max_forward_speed: float
    max_yaw_rate: float

    def __post_init__(self) -> None:
        for name in ("wheel_radius", "wheel_separation", "max_forward_speed",
                     "max_yaw_rate"):
            value = getattr(self, name)
            try:
                number = float(value)
            except (TypeError, ValueError):
                number = math.nan
            if not (math.isfinite(number) and number > 0.0):
                raise ValueError(f"differential-drive base: {name} must be a positive "
                                 f"finite number, got {value!r}")
            object.__setattr__(self, name, number)

    def wheel_speeds(self, forward_speed: float, yaw_rate: float) -> tuple[float, float]:
        """Wheel angular velocities ``(left, right)`` [rad/s] for a body velocity.

        Args:
            forward_speed: ``v`` along the heading [m/s].
            yaw_rate: ``omega``, counter-clockwise positive [rad/s].
        """
        half = 0.5 * self.wheel_separation * yaw_rate
        return ((forward_speed - half) / self.wheel_radius,
                (forward_speed + half) / self.wheel_radius)

    def body_velocity(self, left: float, right: float) -> tuple[float, float]:
        """Forward speed [m/s] and yaw rate [rad/s] of wheel velocities [rad/s].

        The inverse of :meth:`wheel_speeds`.
        """
        return (0.5 * self.wheel_radius * (left + right),
                self.wheel_radius * (right - left) / self.wheel_separation)


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
        base: The differential-drive base the robot stands on, or None for a
            holonomic robot (fixed arm, point robot): then every configuration
            variable is actuated and velocities are ``qdot``.
        limits: Velocity, acceleration (jerk, effort) limits of the velocity coordinates;
            ``None`` derives them from the kinematics (:func:`default_limits`).
        planning_spheres: Spheres global guidance checks configurations with instead
            (:attr:`planning_robot`), or None: ``collision_spheres``. Tighter spheres let a
            plan reach goals close to obstacles; the fabric keeps ``collision_spheres``, whose
            obstacle leaves act one per sphere, so more spheres on a link push it harder.
        planning_pairs: Index pairs into ``planning_spheres`` that must not overlap.
        fine_spheres: Spheres that fit the meshes more tightly (more of them), or None:
            where guidance's spheres find a configuration closer to the obstacles than its
            margin, its checker asks these (:attr:`fine_robot`), and the configuration is
            free if either set finds it so
            (:class:`~dynfab.motion.configuration_checker.ConfigurationChecker`). Kept by
            :attr:`planning_robot`, and used by the checker of a robot that plans on its own
            spheres (that one, or a robot without ``planning_spheres``), not on the fabric's
            spheres of a robot that has them; self-collision stays with the planning spheres.

    Convention for a robot with a ``base``: its first three joints (in the order of
    ``kinematics.joint_names``) are ``base_x`` (prismatic along world x), ``base_y``
    (prismatic along world y) and ``base_yaw`` (revolute or continuous about z), each a
    child of the previous one with zero origin rotation and no x-y origin offset, so that

        q = (x, y, yaw, arm...)   [m, m, rad, rad...]

    is the planar pose of the base frame (the frame below ``base_yaw``, at the drive-axle
    midpoint for a differential drive) followed by the arm's joints. Its actuated velocities are

        qdot_u = (v, omega, arm rates...)   [m/s, rad/s, rad/s...],

    ``v`` the forward speed along the base's heading and ``omega`` its yaw rate,
    related to the configuration velocity by the non-holonomic constraint
    ``qdot = J_nh(yaw) qdot_u`` with ``J_nh = blockdiag([[cos yaw, 0], [sin yaw, 0],
    [0, 1]], I)`` (paper section V, "Extension to non-Holonomic Constraints").
    """

    name: str
    kinematics: Kinematics
    goal_link: str
    collision_spheres: tuple[CollisionSphere, ...]
    self_collision_pairs: tuple[tuple[int, int], ...]
    planar: bool
    default_q: np.ndarray
    base: DifferentialDriveBase | None = None
    limits: MotionLimits | None = None
    planning_spheres: tuple[CollisionSphere, ...] | None = None
    planning_pairs: tuple[tuple[int, int], ...] = ()
    fine_spheres: tuple[CollisionSphere, ...] | None = None

    def __post_init__(self) -> None:
        kin = self.kinematics
        if self.base is not None:
            if not isinstance(self.base, DifferentialDriveBase):
                raise TypeError(f"robot '{self.name}': base must be a "
                                f"DifferentialDriveBase or None, got {type(self.base).__name__}")
            _check_base_joints(self.name, kin)
        if self.goal_link not in kin.link_names:
            raise UnknownLinkError(f"robot '{self.name}': unknown link '{self.goal_link}'; "
                                   f"valid links: {', '.join(kin.link_names)}")
        pairs = self._checked("self-collision pair", self.collision_spheres, self.self_collision_pairs)
        if self.planning_spheres is not None:
            object.__setattr__(self, "planning_spheres", tuple(self.planning_spheres))
            object.__setattr__(self, "planning_pairs",
                               self._checked("planning pair", self.planning_spheres, self.planning_pairs))
        elif self.planning_pairs:
            raise ValueError(f"robot '{self.name}': planning_pairs need planning_spheres")
        if self.fine_spheres is not None:
            object.__setattr__(self, "fine_spheres", tuple(self.fine_spheres))
            self._checked("fine sphere", self.fine_spheres, ())
        default_q = np.array(self.default_q, dtype=float).reshape(-1)
        if default_q.size != kin.dof:
            raise ValueError(f"robot '{self.name}': default_q must have {kin.dof} "
                             f"elements, got {default_q.size}")
        default_q.setflags(write=False)
        object.__setattr__(self, "collision_spheres", tuple(self.collision_spheres))
        object.__setattr__(self, "self_collision_pairs", pairs)
        object.__setattr__(self, "default_q", default_q)
        limits = default_limits(kin, self.base) if self.limits is None else self.limits
        names = velocity_names(kin, self.base is not None)
        if limits.names != names:
            raise ValueError(f"robot '{self.name}': limits must be given for the velocity "
                             f"coordinates {', '.join(names)}; got {', '.join(limits.names)}")
        object.__setattr__(self, "limits", limits)

    def _checked(self, what: str, spheres: Sequence[CollisionSphere],
                 pairs: Sequence[tuple[int, int]]) -> tuple[tuple[int, int], ...]:
        """``pairs`` as int tuples, once every sphere's link is known and every pair indexes
        two different ``spheres``."""
        links = self.kinematics.link_names
        for sphere in spheres:
            if sphere.link not in links:
                raise UnknownLinkError(f"robot '{self.name}': unknown link '{sphere.link}'; "
                                       f"valid links: {', '.join(links)}")
        checked = tuple((int(a), int(b)) for a, b in pairs)
        for a, b in checked:
            if not (0 <= a < len(spheres) and 0 <= b < len(spheres)) or a == b:
                raise ValueError(f"robot '{self.name}': {what} ({a}, {b}) "
                                 f"must index two different spheres of {len(spheres)}")
        return checked

    @cached_property
    def planning_robot(self) -> Robot:
        """The robot as global guidance checks configurations: with ``planning_spheres`` and
        ``planning_pairs`` as its collision spheres and pairs, or itself without them."""
        if self.planning_spheres is None:
            return self
        return replace(self, collision_spheres=self.planning_spheres, self_collision_pairs=self.planning_pairs,
                       planning_spheres=None, planning_pairs=())

    @cached_property
    def fine_robot(self) -> Robot | None:
        """The robot with ``fine_spheres`` as its collision spheres and no pairs (the
        second look of :attr:`fine_spheres`), or None without them."""
        if self.fine_spheres is None:
            return None
        return replace(self, collision_spheres=self.fine_spheres, self_collision_pairs=(), planning_spheres=None,
                       planning_pairs=(), fine_spheres=None)

    @property
    def velocity_names(self) -> tuple[str, ...]:
        """The velocity coordinates in order: the joints, or ``(v, omega, arm joints...)``
        on a differential-drive base."""
        return velocity_names(self.kinematics, self.base is not None)

    @property
    def position_index(self) -> tuple[int | None, ...]:
        """For each velocity coordinate, the configuration index it moves (``None`` for
        the base's ``v`` and ``omega``, which have no position limits)."""
        if self.base is None:
            return tuple(range(self.dof))
        return (None, None) + tuple(range(3, self.dof))

    @property
    def dof(self) -> int:
        """Number of configuration variables."""
        return self.kinematics.dof

    def link_position(self, q: object, link: str, offset: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
        """Root-frame position of a point fixed in ``link``, shape (3,) [m].

        Args:
            q: Configuration, shape (dof,), numbers.
            link: A link of the robot.
            offset: The point in ``link`` coordinates [m] (default: the link origin).

        Raises:
            UnknownLinkError: ``link`` is not a link of the robot.
        """
        return np.array(self.kinematics.position(np.asarray(q, dtype=float), link, offset=offset),
                        dtype=float).reshape(3)

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


def velocity_names(kin: Kinematics, on_base: bool) -> tuple[str, ...]:
    """Names of the velocity coordinates (see :class:`Robot`)."""
    return ("v", "omega") + kin.joint_names[3:] if on_base else kin.joint_names


def default_limits(kin: Kinematics, base: DifferentialDriveBase | None) -> MotionLimits:
    """Limits from the description (:func:`dynfab.robots.limits.limits_from_joints`); on a
    base, ``v`` and ``omega`` take its ``max_forward_speed`` and ``max_yaw_rate``, and the
    efforts of ``base_x`` and ``base_yaw``."""
    velocity, effort = kin.velocity_limits, kin.effort_limits
    if base is not None:
        velocity = np.concatenate([[base.max_forward_speed, base.max_yaw_rate], velocity[3:]])
        effort = np.concatenate([[effort[0], effort[2]], effort[3:]])
    return limits_from_joints(velocity_names(kin, base is not None), velocity, effort)


def _check_base_joints(name: str, kin: Kinematics) -> None:
    """Raise ValueError unless the first three joints are the planar base joints.

    Checks names and order (``BASE_JOINTS``), types, axes (world x, world y, z), the
    chain (``base_x`` hangs from the root link, each next joint from the previous
    joint's child) and origins without rotation or x-y offset (a z offset, the base's
    height, is allowed).
    """
    first = kin.joint_names[:3]
    if first != BASE_JOINTS:
        raise ValueError(f"robot '{name}': a robot with a differential-drive base must "
                         f"have the joints {', '.join(BASE_JOINTS)} first, in this order; "
                         f"its first joints are {', '.join(first) or 'none'}")
    joints = {joint.name: joint for joint in kin.model.joints}
    expected = (("prismatic",), ("prismatic",), ("revolute", "continuous"))
    axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    parent = kin.root_link
    for joint_name, types, axis in zip(BASE_JOINTS, expected, axes):
        joint = joints[joint_name]
        problem = None
        if joint.type not in types:
            problem = f"type must be {' or '.join(types)}, got {joint.type}"
        elif not np.allclose(joint.axis, axis, rtol=0.0, atol=1e-9):
            problem = f"axis must be {axis}, got {joint.axis}"
        elif joint.parent != parent:
            problem = f"parent link must be '{parent}', got '{joint.parent}'"
        elif (not joint.origin.is_identity_rotation
              or not np.allclose(joint.origin.xyz[:2], 0.0, rtol=0.0, atol=1e-12)):
            problem = "origin must have no rotation and no x-y offset"
        if problem is not None:
            raise ValueError(f"robot '{name}': base joint '{joint_name}': {problem}")
        parent = joint.child
