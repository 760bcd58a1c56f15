"""A URDF robot description as immutable values: links with collision geometry, joints.

Units follow URDF: metres for lengths, radians for angles, m/s or rad/s for velocity
limits. :mod:`dynfab.robots.urdf` reads files into these values.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dynfab.geometry.shapes import Box, Cylinder, Sphere

__all__ = ["ACTUATED_JOINT_TYPES", "CollisionGeometry", "Inertial", "Joint", "JointLimit", "Link", "MeshFile",
           "Mimic", "Origin", "UrdfError", "UrdfModel"]

Vector3 = tuple[float, float, float]
Matrix3 = tuple[Vector3, Vector3, Vector3]

#: Joint types that move (carry a configuration variable unless they mimic another).
ACTUATED_JOINT_TYPES = frozenset({"revolute", "continuous", "prismatic"})


class UrdfError(ValueError):
    """A URDF text is malformed or uses a feature this package does not support."""


@dataclass(frozen=True)
class Origin:
    """Pose of a frame in its parent link frame: ``x_parent = rotation @ x + xyz``.

    URDF writes it as ``xyz`` and fixed-axis ``rpy`` with
    ``rotation = Rz(yaw) @ Ry(pitch) @ Rx(roll)``; the matrix is what is kept.

    Attributes:
        xyz: Translation [m].
        rotation: Rotation matrix as three rows [-].
    """

    xyz: Vector3 = (0.0, 0.0, 0.0)
    rotation: Matrix3 = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))

    @classmethod
    def from_matrix(cls, matrix: np.ndarray | None) -> Origin:
        """The origin of a 4x4 homogeneous transform (``None``: identity)."""
        if matrix is None:
            return cls()
        m = np.asarray(matrix, dtype=float)
        if m.shape != (4, 4) or not np.isfinite(m).all():
            raise UrdfError(f"origin must be a finite pose, got {m.tolist()}")
        rotation = tuple(tuple(float(x) for x in row) for row in m[:3, :3])
        return cls(xyz=(float(m[0, 3]), float(m[1, 3]), float(m[2, 3])),
                   rotation=rotation)  # type: ignore[arg-type]

    @property
    def is_identity_rotation(self) -> bool:
        """True if the rotation is the identity (to 1e-12)."""
        return bool(np.allclose(self.rotation, np.eye(3), rtol=0.0, atol=1e-12))


@dataclass(frozen=True)
class JointLimit:
    """Position and velocity limits of an actuated joint.

    Attributes:
        lower: Lower position limit [rad or m].
        upper: Upper position limit [rad or m].
        velocity: Maximum absolute velocity [rad/s or m/s].
        effort: Maximum absolute effort [N m or N], ``None`` if not given.
    """

    lower: float
    upper: float
    velocity: float
    effort: float | None = None


@dataclass(frozen=True)
class Mimic:
    """A joint that follows another: ``q = multiplier * q_joint + offset``.

    Attributes:
        joint: Name of the followed joint.
        multiplier: Gain [-].
        offset: Offset [rad or m].
    """

    joint: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class MeshFile:
    """A mesh referenced by a URDF ``<mesh>`` element.

    Attributes:
        uri: The ``filename`` as written (``package://``, ``file://`` or a relative path).
        path: The file it resolves to, or ``None`` if no candidate exists (see
            :func:`dynfab.robots.mesh_paths.resolve_uri`).
        scale: Scale per axis [-].
    """

    uri: str
    path: str | None
    scale: Vector3 = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class CollisionGeometry:
    """One ``<collision>`` element of a link.

    Attributes:
        origin: Pose of the geometry in the link frame.
        shape: A primitive (:class:`~dynfab.geometry.shapes.Box`, ``Cylinder`` along z,
            ``Sphere``) or a :class:`MeshFile`.
    """

    origin: Origin
    shape: Box | Cylinder | Sphere | MeshFile


@dataclass(frozen=True)
class Inertial:
    """A link's ``<inertial>``: its mass and its inertia about its centre of mass.

    Attributes:
        mass: Mass m [kg], >= 0.
        origin: Centre of mass (``xyz``) and the axes of ``inertia`` (``rpy``) in the link
            frame.
        inertia: Symmetric inertia tensor about the centre of mass in the ``origin`` axes,
            rows ``(ixx, ixy, ixz), (ixy, iyy, iyz), (ixz, iyz, izz)`` [kg m^2].
    """

    mass: float
    origin: Origin
    inertia: Matrix3

    def link_frame_inertia(self) -> np.ndarray:
        """The inertia about the centre of mass in link axes, ``R I Rᵀ`` [kg m^2], (3, 3)."""
        rotation = np.array(self.origin.rotation)
        return rotation @ np.array(self.inertia) @ rotation.T


@dataclass(frozen=True)
class Link:
    """A rigid body of the robot.

    Attributes:
        name: Link name.
        collisions: Its ``<collision>`` geometries (empty if it has none).
        inertial: Its ``<inertial>``, or ``None`` if the URDF gives none.
    """

    name: str
    collisions: tuple[CollisionGeometry, ...] = ()
    inertial: Inertial | None = None


@dataclass(frozen=True)
class Joint:
    """A joint connecting a parent link to a child link.

    The child frame is ``T_parent_child(q) = T_origin @ M(q)`` where ``M`` is a rotation
    by ``q`` about ``axis`` (revolute, continuous), a translation by ``q * axis``
    (prismatic) or the identity (fixed).

    Attributes:
        name: Joint name.
        type: ``"revolute"``, ``"continuous"``, ``"prismatic"`` or ``"fixed"``.
        parent: Parent link name.
        child: Child link name.
        origin: Joint frame in the parent link frame.
        axis: Unit motion axis in the joint frame.
        limit: Limits; ``None`` for continuous and fixed joints without a limit tag.
        mimic: Set if the joint follows another joint instead of being actuated.
    """

    name: str
    type: str
    parent: str
    child: str
    origin: Origin = Origin()
    axis: Vector3 = (1.0, 0.0, 0.0)
    limit: JointLimit | None = None
    mimic: Mimic | None = None

    @property
    def is_actuated(self) -> bool:
        """True if the joint has its own configuration variable."""
        return self.type in ACTUATED_JOINT_TYPES and self.mimic is None


@dataclass(frozen=True)
class UrdfModel:
    """The kinematic tree of a URDF robot.

    Attributes:
        name: Robot name (the ``name`` attribute of ``<robot>``).
        links: Links in document order.
        joints: Joints in document order.
    """

    name: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]

    @property
    def link_names(self) -> tuple[str, ...]:
        """Names of all links in document order."""
        return tuple(link.name for link in self.links)

    @property
    def root_link(self) -> str:
        """The unique link that is no joint's child."""
        children = {joint.child for joint in self.joints}
        return next(link.name for link in self.links if link.name not in children)

    def parent_joint(self, link: str) -> Joint | None:
        """The joint whose child is ``link``, or ``None`` for the root."""
        return next((j for j in self.joints if j.child == link), None)

    def child_joints(self, link: str) -> tuple[Joint, ...]:
        """Joints whose parent is ``link``, in document order."""
        return tuple(j for j in self.joints if j.parent == link)
