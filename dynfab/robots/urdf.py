"""Read URDF robot descriptions into immutable values, with yourdfpy.

yourdfpy parses the XML; this module turns its result into frozen values (links with
their collision geometry, joints with origin, axis, limits, mimic) and checks what the
kinematics rely on: known joint types, a single tree, non-zero axes of moving joints,
limits of revolute and prismatic joints. As in urdfdom (and so pinocchio), the axis of a
fixed joint is ignored, a ``<mimic>`` of a joint that does not move on its own is
dropped, ``lower > upper`` means no position limit (Bullet's convention), and visual or
collision geometry of a kind URDF does not define is skipped. Mesh ``filename``s are
resolved to files (:mod:`dynfab.robots.mesh_paths`); nothing is evaluated as code. The
values are those of :mod:`dynfab.robots.urdf_model`.
"""

from __future__ import annotations

import dataclasses
import io
import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import yourdfpy

from dynfab.geometry.shapes import Box, Cylinder, ShapeError, Sphere

from .mesh_paths import resolve_uri
from .urdf_model import (ACTUATED_JOINT_TYPES, CollisionGeometry, Inertial, Joint, JointLimit, Link,
                         MeshFile, Mimic, Origin, UrdfError, UrdfModel, Vector3)

__all__ = [
    "ACTUATED_JOINT_TYPES",
    "CollisionGeometry",
    "Inertial",
    "Joint",
    "JointLimit",
    "Link",
    "MeshFile",
    "Mimic",
    "Origin",
    "UrdfError",
    "UrdfModel",
    "load_urdf",
    "parse_urdf",
]

_SUPPORTED_JOINT_TYPES = ACTUATED_JOINT_TYPES | {"fixed"}
_UNSUPPORTED_JOINT_TYPES = frozenset({"floating", "planar"})
_GEOMETRY_TAGS = frozenset({"box", "cylinder", "sphere", "mesh"})


def load_urdf(path: str | os.PathLike[str], package_dirs: Sequence[str | os.PathLike[str]] = ()
              ) -> UrdfModel:
    """Read a URDF file; mesh URIs resolve against its folder, its parents and ``package_dirs``.

    Args:
        path: The file, or a ``package://NAME/...`` or ``file://`` URI of it (found as
            :func:`~dynfab.robots.mesh_paths.resolve_uri` finds meshes).
        package_dirs: Extra folders for ``package://`` URIs.

    Raises:
        OSError: The file cannot be read (FileNotFoundError: a URI that names no file).
        UrdfError: The file is not a valid URDF; the message starts with the path.
    """
    path = urdf_path(path, package_dirs)
    text = path.read_bytes()
    try:
        return parse_urdf(text, base_dir=path.parent, package_dirs=package_dirs)
    except UrdfError as exc:
        raise UrdfError(f"{os.fspath(path)}: {exc}") from None


def urdf_path(path: str | os.PathLike[str], package_dirs: Sequence[str | os.PathLike[str]] = ()) -> Path:
    """The file ``path`` names: itself, or the file a ``package://`` / ``file://`` URI names.

    Raises:
        FileNotFoundError: a URI that names no file; the message says where it looked.
    """
    text = os.fspath(path)
    if not text.startswith(("package://", "file://")):
        return Path(text)
    found = resolve_uri(text, None, package_dirs)
    if found is None:
        raise FileNotFoundError(f"{text}: no such file; package://NAME/... is looked up in package_dirs, "
                                "$DYNFAB_PACKAGE_PATH and the robot data installed from PyPI "
                                "(example-robot-data, pybullet_data)")
    return found


def parse_urdf(text: str | bytes, base_dir: str | os.PathLike[str] | None = None,
               package_dirs: Sequence[str | os.PathLike[str]] = ()) -> UrdfModel:
    """Parse URDF XML into a :class:`UrdfModel`.

    Args:
        text: The URDF document.
        base_dir: Folder of the URDF file, for relative and ``package://`` mesh URIs
            (``None``: meshes stay unresolved unless ``package_dirs`` finds them).
        package_dirs: Extra folders in which ``package://NAME/...`` is looked up.

    Raises:
        UrdfError: Malformed XML, a missing or invalid attribute, an unsupported joint
            type (``floating``, ``planar``) or a structure that is not a single tree; the
            one-line message names the offending element.
    """
    data = (text.encode("utf-8") if isinstance(text, str) else text).lstrip()
    try:  # yourdfpy falls back to a lenient parser on broken XML: refuse it first
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        raise UrdfError(f"URDF is not well-formed XML: {exc}") from None
    if root.tag != "robot":
        raise UrdfError(f"URDF root element must be <robot>, got <{root.tag}>")
    _drop_unknown_geometry(root)
    try:
        robot = yourdfpy.URDF.load(io.BytesIO(ET.tostring(root)), build_scene_graph=False,
                                   load_meshes=False, load_collision_meshes=False).robot
    except Exception as exc:  # yourdfpy raises whatever its parsing met; name the element
        raise UrdfError(_locate_parse_error(root, exc)) from None
    search = [Path(d) for d in package_dirs]
    links = tuple(_link(link, base_dir, search) for link in robot.links)
    joints = _independent_unless_led(tuple(_joint(joint) for joint in robot.joints))
    model = UrdfModel(name=robot.name or "", links=links, joints=joints)
    _check_tree(model)
    return model


def _drop_unknown_geometry(root: ET.Element) -> None:
    """Remove ``<visual>``/``<collision>`` elements whose geometry URDF does not define
    (simulator extensions such as pybullet's ``<plane>``), as urdfdom-based loaders skip them."""
    for link in root.iter("link"):
        for element in list(link):
            if element.tag not in ("visual", "collision"):
                continue
            geometry = element.find("geometry")
            kinds = [] if geometry is None else [child.tag for child in geometry]
            if not kinds or any(kind not in _GEOMETRY_TAGS for kind in kinds):
                link.remove(element)


def _independent_unless_led(joints: tuple[Joint, ...]) -> tuple[Joint, ...]:
    """Drop a ``<mimic>`` whose leader is not a moving joint that mimics nothing: the joint
    then moves on its own, as in urdfdom and pinocchio (shipped files do contain such tags)."""
    leaders = {joint.name for joint in joints if joint.is_actuated}
    return tuple(dataclasses.replace(joint, mimic=None)
                 if joint.mimic is not None and joint.mimic.joint not in leaders else joint
                 for joint in joints)


def _locate_parse_error(root: ET.Element, exc: Exception) -> str:
    """A one-line message for an exception of yourdfpy, naming the element it came from."""
    for element in root:
        if element.tag not in ("link", "joint"):
            continue
        name = element.get("name")
        where = f"<{element.tag} name='{name}'>" if name else f"<{element.tag}>"
        if not name:
            return f"{where}: missing attribute 'name'"
        if element.tag == "joint":
            for tag in ("parent", "child"):
                if element.find(tag) is None:
                    return f"{where}: missing <{tag}> element"
            problem = _joint_attribute_problem(element)
            if problem:
                return f"{where}: {problem}"
    detail = str(exc).splitlines()[0] if str(exc) else ""
    return f"URDF could not be parsed ({type(exc).__name__}: {detail})"


def _joint_attribute_problem(element: ET.Element) -> str | None:
    """The first non-numeric or mis-sized number attribute of a joint's sub-elements."""
    sizes = {("origin", "xyz"): 3, ("origin", "rpy"): 3, ("axis", "xyz"): 3,
             ("limit", "lower"): 1, ("limit", "upper"): 1, ("limit", "velocity"): 1,
             ("limit", "effort"): 1, ("mimic", "multiplier"): 1, ("mimic", "offset"): 1}
    for (tag, attribute), size in sizes.items():
        sub = element.find(tag)
        value = None if sub is None else sub.get(attribute)
        if value is None:
            continue
        try:
            numbers = [float(part) for part in value.split()]
        except ValueError:
            return f"<{tag}>: attribute '{attribute}' is not a number: '{value}'"
        if len(numbers) != size:
            count = "three numbers" if size == 3 else "one number"
            return f"<{tag}>: attribute '{attribute}' must be {count}, got '{value}'"
    return None


def _link(link: yourdfpy.Link, base_dir: str | os.PathLike[str] | None,
          package_dirs: list[Path]) -> Link:
    """A link with its collision geometry (primitives as shapes, meshes as files)."""
    where = f"<link name='{link.name}'>"
    collisions = []
    for collision in link.collisions or ():
        geometry = collision.geometry
        origin = Origin.from_matrix(collision.origin)
        try:
            if geometry.box is not None:
                shape: Box | Cylinder | Sphere | MeshFile = Box(tuple(geometry.box.size))
            elif geometry.cylinder is not None:
                shape = Cylinder(geometry.cylinder.radius, geometry.cylinder.length)
            elif geometry.sphere is not None:
                shape = Sphere(geometry.sphere.radius)
            elif geometry.mesh is not None:
                shape = _mesh(geometry.mesh, base_dir, package_dirs)
            else:
                raise UrdfError(f"{where} <collision>: no geometry")
        except (ShapeError, TypeError, ValueError) as exc:
            raise UrdfError(f"{where} <collision>: {exc}") from None
        collisions.append(CollisionGeometry(origin=origin, shape=shape))
    return Link(name=link.name, collisions=tuple(collisions), inertial=_inertial(link.inertial, where))


def _inertial(inertial: yourdfpy.Inertial | None, where: str) -> Inertial | None:
    """The ``<inertial>`` values (URDF defaults: mass 0, zero inertia, identity origin);
    refuses a negative or non-finite mass and a non-finite or asymmetric inertia."""
    if inertial is None:
        return None
    where = f"{where} <inertial>"
    mass = _finite(inertial.mass, 0.0)
    if not (math.isfinite(mass) and mass >= 0.0):
        raise UrdfError(f"{where}: mass must be a non-negative number, got {inertial.mass}")
    tensor = np.zeros((3, 3)) if inertial.inertia is None else np.asarray(inertial.inertia, dtype=float)
    if tensor.shape != (3, 3) or not np.isfinite(tensor).all() or not np.allclose(tensor, tensor.T):
        raise UrdfError(f"{where}: inertia must be six finite numbers, got {tensor.tolist()}")
    try:
        origin = Origin.from_matrix(inertial.origin)
    except UrdfError as exc:
        raise UrdfError(f"{where}: {exc}") from None
    rows = tuple(tuple(float(x) for x in row) for row in tensor)
    return Inertial(mass=mass, origin=origin, inertia=rows)  # type: ignore[arg-type]


def _mesh(mesh: yourdfpy.Mesh, base_dir: str | os.PathLike[str] | None,
          package_dirs: list[Path]) -> MeshFile:
    scale = mesh.scale
    if scale is None:
        factors: Vector3 = (1.0, 1.0, 1.0)
    else:
        values = np.asarray(scale, dtype=float).reshape(-1)  # urdfdom reads the first three
        array = np.broadcast_to(values[:3] if values.size >= 3 else values, (3,))
        factors = (float(array[0]), float(array[1]), float(array[2]))
    path = resolve_uri(mesh.filename, base_dir, package_dirs)
    return MeshFile(uri=mesh.filename, path=None if path is None else os.fspath(path), scale=factors)


def _joint(joint: yourdfpy.Joint) -> Joint:
    """A joint's values; checks its type, axis and limits."""
    where = f"<joint name='{joint.name}'>"
    jtype = joint.type
    if jtype in _UNSUPPORTED_JOINT_TYPES:
        raise UrdfError(f"{where}: joint type '{jtype}' is not supported "
                        f"(supported: {', '.join(sorted(_SUPPORTED_JOINT_TYPES))})")
    if jtype not in _SUPPORTED_JOINT_TYPES:
        raise UrdfError(f"{where}: unknown joint type '{jtype}'")
    if not joint.parent:
        raise UrdfError(f"{where} <parent>: missing attribute 'link'")
    if not joint.child:
        raise UrdfError(f"{where} <child>: missing attribute 'link'")
    axis: Vector3 = (1.0, 0.0, 0.0)
    if jtype != "fixed":  # URDF ignores the axis of a fixed joint
        axis = _unit(joint.axis, f"{where} <axis>")
    limit = _limit(joint.limit, where)
    if limit is None and jtype in ("revolute", "prismatic"):
        raise UrdfError(f"{where}: {jtype} joint needs a <limit> element")
    mimic = None
    if joint.mimic is not None:
        mimic = Mimic(joint=joint.mimic.joint, multiplier=_finite(joint.mimic.multiplier, 1.0),
                      offset=_finite(joint.mimic.offset, 0.0))
    return Joint(name=joint.name, type=jtype, parent=joint.parent, child=joint.child,
                 origin=Origin.from_matrix(joint.origin), axis=axis, limit=limit, mimic=mimic)


def _limit(limit: yourdfpy.Limit | None, where: str) -> JointLimit | None:
    """The ``<limit>`` values; ``lower``/``upper`` default to 0 as in URDF."""
    if limit is None:
        return None
    where = f"{where} <limit>"
    if limit.velocity is None:
        raise UrdfError(f"{where}: missing attribute 'velocity'")
    lower, upper = _finite(limit.lower, 0.0), _finite(limit.upper, 0.0)
    velocity = _finite(limit.velocity, 0.0)
    if not all(math.isfinite(x) for x in (lower, upper, velocity)):
        raise UrdfError(f"{where}: limits must be finite, got lower={limit.lower}, "
                        f"upper={limit.upper}, velocity={limit.velocity}")
    if lower > upper:  # Bullet's convention for a joint without position limits
        lower, upper = -math.inf, math.inf
    if velocity < 0.0:
        raise UrdfError(f"{where}: velocity must be non-negative, got {velocity}")
    effort = None if limit.effort is None else float(limit.effort)
    return JointLimit(lower=lower, upper=upper, velocity=velocity, effort=effort)


def _finite(value: object, default: float) -> float:
    """``value`` as a float, ``default`` if it is ``None``."""
    return default if value is None else float(value)  # type: ignore[arg-type]


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


def _unit(axis: object, where: str) -> Vector3:
    """A joint axis normalised to unit length."""
    vector = np.asarray(axis if axis is not None else (1.0, 0.0, 0.0), dtype=float).reshape(-1)
    if vector.size != 3 or not np.isfinite(vector).all():
        raise UrdfError(f"{where}: axis must be three finite numbers, got {vector.tolist()}")
    norm = float(np.linalg.norm(vector))
    if norm < 1e-12:
        raise UrdfError(f"{where}: axis must not be zero")
    x, y, z = (float(v) for v in (vector if abs(norm - 1.0) < 1e-15 else vector / norm))
    return (x, y, z)
