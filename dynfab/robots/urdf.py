"""Parse URDF robot descriptions into immutable values.

Only the kinematic part of URDF is read: links (by name) and joints (type, parent,
child, origin, axis, limits, mimic). Visual, collision and inertial elements are
ignored. Parsing uses :mod:`xml.etree.ElementTree` and never evaluates text as code.

Units follow URDF: metres for lengths, radians for angles, m/s or rad/s for velocity
limits.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

__all__ = [
    "ACTUATED_JOINT_TYPES",
    "Joint",
    "JointLimit",
    "Link",
    "Mimic",
    "Origin",
    "UrdfError",
    "UrdfModel",
    "parse_urdf",
]

Vector3 = tuple[float, float, float]

#: Joint types that carry a configuration variable.
ACTUATED_JOINT_TYPES = frozenset({"revolute", "continuous", "prismatic"})
_SUPPORTED_JOINT_TYPES = ACTUATED_JOINT_TYPES | {"fixed"}
_UNSUPPORTED_JOINT_TYPES = frozenset({"floating", "planar"})


class UrdfError(ValueError):
    """A URDF text is malformed or uses a feature this package does not support."""


@dataclass(frozen=True)
class Origin:
    """Pose of a joint frame in its parent link frame.

    The transform is ``T = Trans(xyz) @ Rot(rpy)`` with
    ``Rot(rpy) = Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (fixed-axis roll, pitch, yaw).

    Attributes:
        xyz: Translation [m].
        rpy: Roll, pitch, yaw [rad].
    """

    xyz: Vector3 = (0.0, 0.0, 0.0)
    rpy: Vector3 = (0.0, 0.0, 0.0)


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
class Link:
    """A rigid body of the robot, known by its name."""

    name: str


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


def parse_urdf(text: str) -> UrdfModel:
    """Parse URDF XML text into a :class:`UrdfModel`.

    Args:
        text: The URDF document.

    Returns:
        The kinematic tree.

    Raises:
        UrdfError: Malformed XML, a missing or invalid attribute, an unsupported joint
            type (``floating``, ``planar``) or a structure that is not a single tree.
            The one-line message names the offending element.
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise UrdfError(f"URDF is not well-formed XML: {exc}") from None
    if root.tag != "robot":
        raise UrdfError(f"URDF root element must be <robot>, got <{root.tag}>")
    name = root.get("name", "")
    links = tuple(Link(_required(el, "name", "<link>")) for el in root.findall("link"))
    joints = tuple(_parse_joint(el) for el in root.findall("joint"))
    model = UrdfModel(name=name, links=links, joints=joints)
    _check_tree(model)
    return model


def _parse_joint(el: ET.Element) -> Joint:
    """Parse one ``<joint>`` element."""
    name = _required(el, "name", "<joint>")
    where = f"<joint name='{name}'>"
    jtype = _required(el, "type", where)
    if jtype in _UNSUPPORTED_JOINT_TYPES:
        raise UrdfError(f"{where}: joint type '{jtype}' is not supported "
                        f"(supported: {', '.join(sorted(_SUPPORTED_JOINT_TYPES))})")
    if jtype not in _SUPPORTED_JOINT_TYPES:
        raise UrdfError(f"{where}: unknown joint type '{jtype}'")
    parent = _required(_child(el, "parent", where), "link", f"{where} <parent>")
    child = _required(_child(el, "child", where), "link", f"{where} <child>")
    origin_el = el.find("origin")
    origin = Origin()
    if origin_el is not None:
        origin = Origin(xyz=_vector(origin_el, "xyz", f"{where} <origin>", (0.0, 0.0, 0.0)),
                        rpy=_vector(origin_el, "rpy", f"{where} <origin>", (0.0, 0.0, 0.0)))
    axis = (1.0, 0.0, 0.0)
    axis_el = el.find("axis")
    if axis_el is not None:
        axis = _unit(_vector(axis_el, "xyz", f"{where} <axis>", axis), f"{where} <axis>")
    limit = _parse_limit(el.find("limit"), where)
    if limit is None and jtype in ("revolute", "prismatic"):
        raise UrdfError(f"{where}: {jtype} joint needs a <limit> element")
    mimic_el = el.find("mimic")
    mimic = None
    if mimic_el is not None:
        mimic = Mimic(joint=_required(mimic_el, "joint", f"{where} <mimic>"),
                      multiplier=_number(mimic_el, "multiplier", f"{where} <mimic>", 1.0),
                      offset=_number(mimic_el, "offset", f"{where} <mimic>", 0.0))
    return Joint(name=name, type=jtype, parent=parent, child=child, origin=origin,
                 axis=axis, limit=limit, mimic=mimic)


def _parse_limit(el: ET.Element | None, where: str) -> JointLimit | None:
    """Parse a ``<limit>`` element; ``lower``/``upper`` default to 0 as in URDF."""
    if el is None:
        return None
    where = f"{where} <limit>"
    if el.get("velocity") is None:
        raise UrdfError(f"{where}: missing attribute 'velocity'")
    lower = _number(el, "lower", where, 0.0)
    upper = _number(el, "upper", where, 0.0)
    velocity = _number(el, "velocity", where, 0.0)
    effort = _number(el, "effort", where, math.nan)
    if lower > upper:
        raise UrdfError(f"{where}: lower {lower} exceeds upper {upper}")
    if velocity < 0.0:
        raise UrdfError(f"{where}: velocity must be non-negative, got {velocity}")
    return JointLimit(lower=lower, upper=upper, velocity=velocity,
                      effort=None if math.isnan(effort) else effort)


def _check_tree(model: UrdfModel) -> None:
    """Check unique names, known links and a single rooted tree without cycles."""
    if not model.links:
        raise UrdfError("URDF has no <link> elements")
    _check_unique([link.name for link in model.links], "link")
    _check_unique([joint.name for joint in model.joints], "joint")
    names = set(model.link_names)
    seen_children: set[str] = set()
    for joint in model.joints:
        for role, link in (("parent", joint.parent), ("child", joint.child)):
            if link not in names:
                raise UrdfError(f"<joint name='{joint.name}'>: {role} link '{link}' "
                                "is not a <link> of this robot")
        if joint.child in seen_children:
            raise UrdfError(f"<joint name='{joint.name}'>: link '{joint.child}' has "
                            "more than one parent joint")
        seen_children.add(joint.child)
    roots = [n for n in model.link_names if n not in seen_children]
    if len(roots) != 1:
        raise UrdfError(f"URDF must form one tree with a single root link, "
                        f"found roots {roots}")
    reached = _reachable(model, roots[0])
    if reached != names:
        raise UrdfError(f"URDF joints form a cycle through links "
                        f"{sorted(names - reached)}")
    joints = {joint.name: joint for joint in model.joints}
    for joint in model.joints:
        if joint.mimic is None:
            continue
        target = joints.get(joint.mimic.joint)
        if target is None or not target.is_actuated:
            raise UrdfError(f"<joint name='{joint.name}'> <mimic>: '{joint.mimic.joint}' "
                            "is not an actuated joint of this robot")


def _reachable(model: UrdfModel, root: str) -> set[str]:
    """Links reachable from ``root`` through parent -> child joints."""
    reached, stack = {root}, [root]
    while stack:
        for joint in model.child_joints(stack.pop()):
            if joint.child not in reached:
                reached.add(joint.child)
                stack.append(joint.child)
    return reached


def _check_unique(names: list[str], kind: str) -> None:
    """Raise if a name occurs twice."""
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise UrdfError(f"<{kind} name='{name}'>: duplicate {kind} name")
        seen.add(name)


def _child(el: ET.Element, tag: str, where: str) -> ET.Element:
    """The required sub-element ``tag`` of ``el``."""
    sub = el.find(tag)
    if sub is None:
        raise UrdfError(f"{where}: missing <{tag}> element")
    return sub


def _required(el: ET.Element, attribute: str, where: str) -> str:
    """The required, non-empty attribute ``attribute`` of ``el``."""
    value = el.get(attribute)
    if value is None or not value.strip():
        raise UrdfError(f"{where}: missing attribute '{attribute}'")
    return value.strip()


def _number(el: ET.Element, attribute: str, where: str, default: float) -> float:
    """A finite float attribute, or ``default`` if absent."""
    value = el.get(attribute)
    if value is None:
        return default
    try:
        number = float(value)
    except ValueError:
        raise UrdfError(f"{where}: attribute '{attribute}' is not a number: "
                        f"'{value}'") from None
    if not math.isfinite(number):
        raise UrdfError(f"{where}: attribute '{attribute}' must be finite, got '{value}'")
    return number


def _vector(el: ET.Element, attribute: str, where: str, default: Vector3) -> Vector3:
    """A 3-vector attribute written as three space-separated numbers."""
    value = el.get(attribute)
    if value is None:
        return default
    parts = value.split()
    try:
        numbers = tuple(float(p) for p in parts)
    except ValueError:
        numbers = ()
    if len(numbers) != 3 or not all(math.isfinite(x) for x in numbers):
        raise UrdfError(f"{where}: attribute '{attribute}' must be three finite numbers, "
                        f"got '{value}'")
    return (numbers[0], numbers[1], numbers[2])


def _unit(axis: Vector3, where: str) -> Vector3:
    """Normalise a joint axis to unit length."""
    norm = math.sqrt(sum(x * x for x in axis))
    if norm < 1e-12:
        raise UrdfError(f"{where}: axis must not be zero")
    if abs(norm - 1.0) < 1e-15:
        return axis
    return (axis[0] / norm, axis[1] / norm, axis[2] / norm)
