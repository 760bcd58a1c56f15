"""The ``robot:`` key of a scenario: a built-in name (or ``{name, fingers}``: the
Panda's finger opening) or a URDF as it ships, with its active and locked joints, package
folders and collision model (spheres and pairs, or ``auto``)."""

from __future__ import annotations

from collections.abc import Mapping
import dataclasses
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Annotated, Any, ClassVar, Literal

from pydantic import BeforeValidator, model_validator

from dynfab.describe import describe
from dynfab.robots.mesh_paths import resolve_uri
from dynfab.scenario.fields import ScenarioError
from dynfab.scenario.model_errors import tagged_union
from dynfab.scenario.model_types import Choice, Flag, Items, Range, ScenarioModel, Text, Whole, fail
from dynfab.scenario.ranges import MAX_JOINT_VALUE, MAX_SPHERE_TOLERANCE, Length, Point3


BUILTIN_ROBOTS: tuple[str, ...] = ("panda", "point", "boxer", "boxer-panda")
#: Built-in robots with the Panda's hand, whose finger opening a scenario may set.
FINGERED_ROBOTS: tuple[str, ...] = ("panda", "boxer-panda")
#: Franka's limits of the opening per finger [m] (dynfab.robots.franka.FINGER_RANGE).
FINGERS_MIN, FINGERS_MAX = 0.0, 0.04


@dataclass(frozen=True)
class BuiltinRobotSpec:
    """A built-in robot with options: ``robot: {name: panda, fingers: 0.02}``.

    Attributes:
        name: A name from :data:`BUILTIN_ROBOTS`.
        fingers: The Panda's opening per finger [m], 0 (closed) ... 0.04 (open, the
            default); only for :data:`FINGERED_ROBOTS`.
    """

    name: str
    fingers: float | None = None


@dataclass(frozen=True)
class CollisionSphereSpec:
    """A collision sphere fixed to a link of a URDF robot.

    Attributes:
        link: Link the sphere is attached to.
        center: Centre in the link frame [m].
        radius: Radius [m] (> 0).
    """

    link: str
    center: tuple[float, float, float]
    radius: float


@dataclass(frozen=True)
class UrdfRobotSpec:
    """A user robot described by a URDF file.

    Attributes:
        urdf: Path of the URDF file: relative to the scenario file's directory, absolute, or
            ``package://NAME/...`` (see :func:`dynfab.robots.mesh_paths.resolve_uri`).
        goal_link: Default goal link of the robot.
        collision_spheres: Spheres used for obstacle and self-collision avoidance, or
            ``"auto"``: fitted to the links' collision geometry (see
            :mod:`dynfab.robots.collision_model`).
        self_collision_pairs: Pairs (i, j) of indices into ``collision_spheres``, or
            ``"auto"``: chosen by sampling configurations (the default with auto spheres).
        sphere_tolerance: With auto spheres: largest distance of a collision-mesh surface
            point outside all spheres [m].
        planar: True if the workspace is the xy-plane (goals [x, y]).
        package_dirs: Folders where ``package://`` mesh URIs are looked up (resolved
            against the scenario file's directory).
        joints: Active joints in the order of ``q``; None: every movable, non-mimic joint.
        locked: Values of the other movable joints [rad or m]; unnamed ones 0 clipped
            into their limits.
    """

    urdf: Path
    goal_link: str
    collision_spheres: tuple[CollisionSphereSpec, ...] | Literal["auto"] = ()
    self_collision_pairs: tuple[tuple[int, int], ...] | Literal["auto"] = ()
    sphere_tolerance: float = 0.01
    planar: bool = False
    package_dirs: tuple[Path, ...] = ()
    joints: tuple[str, ...] | None = None
    locked: Mapping[str, float] = dataclasses.field(default_factory=lambda: MappingProxyType({}))


def _text_keys(value: Any) -> Any:
    """A mapping with text keys (values are checked by the field type)."""
    if not isinstance(value, Mapping):
        raise fail(f"expected a mapping, got {describe(value)}")
    for key in value:
        if not isinstance(key, str):
            raise fail(f"keys must be text, got {describe(key)}")
    return value


def _auto_or_list(value: Any) -> str | None:
    return "auto" if value == "auto" else "list" if isinstance(value, list | tuple) else None


Name = Annotated[str, Text()]
JointValue = Annotated[float, Range(-MAX_JOINT_VALUE, MAX_JOINT_VALUE)]


class CollisionSphereMapping(ScenarioModel):
    """``{link, center: [x, y, z] [m] in the link frame, radius [m]}``."""

    link: Name
    center: Point3
    radius: Length


SphereList = Annotated[tuple[CollisionSphereMapping, ...], Items(what="spheres", allow_empty=True)]
PairList = Annotated[tuple[Annotated[tuple[Annotated[int, Whole(0, 10_000)], ...],
                                     Items((2,), what="sphere indices")], ...],
                     Items(what="pairs", allow_empty=True, max_items=100_000)]

Spheres = tagged_union({"auto": Literal["auto"], "list": SphereList}, None,
                       "auto or a list of {link, center, radius}", _auto_or_list)
Pairs = tagged_union({"auto": Literal["auto"], "list": PairList}, None,
                     "auto or a list of [i, j] sphere index pairs", _auto_or_list)


class UrdfRobotMapping(ScenarioModel):
    """``robot:`` as a URDF file with its goal link, joints and collision model."""

    expected: ClassVar[str] = "a built-in robot name or a mapping"
    urdf: Annotated[str, Text(4096)]
    goal_link: Name
    collision_spheres: Spheres = ()
    self_collision_pairs: Pairs | None = None
    planar: Annotated[bool, Flag()] = False
    package_dirs: Annotated[tuple[Annotated[str, Text(4096)], ...], Items(what="folders", allow_empty=True)] = ()
    joints: Annotated[tuple[Name, ...], Items(what="joint names", allow_empty=True)] | None = None
    locked: Annotated[dict[str, JointValue], BeforeValidator(_text_keys)] = {}
    sphere_tolerance: Annotated[float, Range(0.0, MAX_SPHERE_TOLERANCE, open_lower=True, unit=" m")] | None = None

    @model_validator(mode="after")
    def _pairs_fit_spheres(self) -> UrdfRobotMapping:
        spheres = self.collision_spheres
        if self.sphere_tolerance is not None and spheres != "auto":
            raise fail("only applies to collision_spheres: auto", "sphere_tolerance")
        pairs = self.self_collision_pairs
        if spheres == "auto" and pairs not in (None, "auto") and pairs:
            raise fail("index pairs need explicit collision_spheres; with collision_spheres: auto use "
                       "self_collision_pairs: auto", "self_collision_pairs")
        count = 0 if spheres == "auto" else len(spheres)
        for i, pair in enumerate(() if pairs in (None, "auto") else pairs):
            for k, index in enumerate(pair):
                if index >= count:
                    raise fail(f"sphere index {index} out of range (0 to {count - 1})",
                               f"self_collision_pairs[{i}][{k}]")
            if pair[0] == pair[1]:
                raise fail(f"expected two different spheres, got {list(pair)}", f"self_collision_pairs[{i}]")
        return self


class BuiltinRobotMapping(ScenarioModel):
    """``robot:`` as ``{name: panda, fingers: 0.04}``: a built-in robot with options."""

    expected: ClassVar[str] = "a built-in robot name or a mapping"
    name: Annotated[str, Choice(BUILTIN_ROBOTS)]
    fingers: Annotated[float, Range(FINGERS_MIN, FINGERS_MAX, unit=" m")] | None = None

    @model_validator(mode="after")
    def _fingers_need_a_hand(self) -> BuiltinRobotMapping:
        if self.fingers is not None and self.name not in FINGERED_ROBOTS:
            raise fail(f"the {self.name} has no fingers (only {', '.join(FINGERED_ROBOTS)})", "fingers")
        return self


def _robot_kind(value: Any) -> str | None:
    if isinstance(value, str):
        return "name"
    if isinstance(value, Mapping):
        return "builtin" if "name" in value and "urdf" not in value else "mapping"
    return None


RobotMapping = tagged_union({"name": Annotated[str, Choice(BUILTIN_ROBOTS)], "builtin": BuiltinRobotMapping,
                             "mapping": UrdfRobotMapping}, None, "a built-in robot name or a mapping", _robot_kind)


def robot_spec(robot: str | BuiltinRobotMapping | UrdfRobotMapping, field: str,
               base_dir: Path) -> str | BuiltinRobotSpec | UrdfRobotSpec:
    """The robot value of a validated ``robot:`` key; a URDF path is resolved against
    ``base_dir`` and the package folders.

    Raises:
        ScenarioError: The URDF file is not found.
    """
    if isinstance(robot, str):
        return robot
    if isinstance(robot, BuiltinRobotMapping):
        return BuiltinRobotSpec(robot.name, robot.fingers)
    package_dirs = tuple(base_dir / folder for folder in robot.package_dirs)
    urdf = resolve_uri(robot.urdf, base_dir, package_dirs)
    if urdf is None:
        raise ScenarioError(f"{field}.urdf", f"file not found: {robot.urdf} (a path relative to the scenario "
                            "file, absolute, or package://NAME/... found through package_dirs, "
                            "DYNFAB_PACKAGE_PATH or an installed example-robot-data / pybullet)")
    spheres = robot.collision_spheres
    pairs = robot.self_collision_pairs
    return UrdfRobotSpec(
        urdf=urdf,
        goal_link=robot.goal_link,
        collision_spheres="auto" if spheres == "auto" else tuple(
            CollisionSphereSpec(sphere.link, sphere.center, sphere.radius) for sphere in spheres),
        self_collision_pairs=pairs if pairs is not None else "auto" if spheres == "auto" else (),
        sphere_tolerance=0.01 if robot.sphere_tolerance is None else robot.sphere_tolerance,
        planar=robot.planar,
        package_dirs=package_dirs,
        joints=robot.joints,
        locked=MappingProxyType(dict(robot.locked)),
    )
