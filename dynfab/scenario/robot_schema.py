"""The ``robot:`` key of a scenario: a built-in name or a URDF as it ships, with its
active and locked joints, package folders and collision model (spheres and pairs, or
``auto``)."""

from __future__ import annotations

from collections.abc import Mapping
import dataclasses
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Literal

from dynfab.describe import describe
from dynfab.robots.mesh_paths import resolve_uri
from dynfab.scenario import fields
from dynfab.scenario.fields import ScenarioError


BUILTIN_ROBOTS: tuple[str, ...] = ("panda", "point", "boxer", "boxer-panda")


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


def parse_robot(value: object, field: str, base_dir: Path) -> str | UrdfRobotSpec:
    """Parse ``robot``: a built-in name or a URDF description mapping."""
    if isinstance(value, str):
        return fields.choice(value, field, BUILTIN_ROBOTS)
    data = fields.mapping(value, field, "a built-in robot name or a mapping")
    fields.check_keys(
        data,
        field,
        required=("urdf", "goal_link"),
        optional=("collision_spheres", "self_collision_pairs", "planar", "package_dirs", "joints",
                  "locked", "sphere_tolerance"),
    )
    package_dirs = tuple(base_dir / fields.text(d, f"{field}.package_dirs[{i}]")
                         for i, d in enumerate(fields.sequence(data.get("package_dirs", []), f"{field}.package_dirs")))
    uri = fields.text(data["urdf"], f"{field}.urdf")
    urdf = resolve_uri(uri, base_dir, package_dirs)
    if urdf is None:
        raise ScenarioError(f"{field}.urdf", f"file not found: {uri} (a path relative to the scenario "
                            "file, absolute, or package://NAME/... found through package_dirs, "
                            "DYNFAB_PACKAGE_PATH or an installed example-robot-data / pybullet)")
    joints = None
    if "joints" in data:
        joints = tuple(fields.text(j, f"{field}.joints[{i}]")
                       for i, j in enumerate(fields.sequence(data["joints"], f"{field}.joints")))
    locked_data = fields.mapping(data.get("locked", {}), f"{field}.locked")
    locked = {str(name): fields.number(value, f"{field}.locked.{name}") for name, value in locked_data.items()}
    spheres = _spheres(data.get("collision_spheres", []), f"{field}.collision_spheres")
    pairs = _pairs(data.get("self_collision_pairs", "auto" if spheres == "auto" else []),
                   f"{field}.self_collision_pairs", spheres)
    tolerance = 0.01
    if "sphere_tolerance" in data:
        if spheres != "auto":
            raise ScenarioError(f"{field}.sphere_tolerance", "only applies to collision_spheres: auto")
        tolerance = fields.positive(data["sphere_tolerance"], f"{field}.sphere_tolerance")
    planar = data.get("planar", False)
    if not isinstance(planar, bool):
        raise ScenarioError(f"{field}.planar", f"expected true or false, got {describe(planar)}")
    return UrdfRobotSpec(
        urdf=urdf,
        goal_link=fields.text(data["goal_link"], f"{field}.goal_link"),
        collision_spheres=spheres,
        self_collision_pairs=pairs,
        sphere_tolerance=tolerance,
        planar=planar,
        package_dirs=package_dirs,
        joints=joints,
        locked=MappingProxyType(locked),
    )


def _spheres(value: object, field: str) -> tuple[CollisionSphereSpec, ...] | Literal["auto"]:
    """Parse ``collision_spheres``: ``auto`` or a list of spheres."""
    if value == "auto":
        return "auto"
    if isinstance(value, str):
        raise ScenarioError(field, f"expected auto or a list of {{link, center, radius}}, got {value!r}")
    return tuple(_collision_sphere(sphere, f"{field}[{i}]") for i, sphere in enumerate(fields.sequence(value, field)))


def _pairs(value: object, field: str, spheres: tuple[CollisionSphereSpec, ...] | Literal["auto"]
           ) -> tuple[tuple[int, int], ...] | Literal["auto"]:
    """Parse ``self_collision_pairs``: ``auto`` or index pairs into explicit spheres."""
    if value == "auto":
        return "auto"
    if isinstance(value, str):
        raise ScenarioError(field, f"expected auto or a list of [i, j] sphere index pairs, got {value!r}")
    pairs = fields.sequence(value, field)
    if spheres == "auto" and pairs:
        raise ScenarioError(field, "index pairs need explicit collision_spheres; with "
                            "collision_spheres: auto use self_collision_pairs: auto")
    count = 0 if spheres == "auto" else len(spheres)
    return tuple(_sphere_pair(pair, f"{field}[{i}]", count) for i, pair in enumerate(pairs))


def _collision_sphere(value: object, field: str) -> CollisionSphereSpec:
    """Parse one ``{link, center, radius}`` collision sphere."""
    data = fields.mapping(value, field)
    fields.check_keys(data, field, required=("link", "center", "radius"))
    x, y, z = fields.vector(data["center"], f"{field}.center", (3,))
    return CollisionSphereSpec(
        link=fields.text(data["link"], f"{field}.link"),
        center=(x, y, z),
        radius=fields.positive(data["radius"], f"{field}.radius"),
    )


def _sphere_pair(value: object, field: str, n_spheres: int) -> tuple[int, int]:
    """Parse a self-collision pair ``[i, j]`` of distinct collision-sphere indices."""
    pair = fields.sequence(value, field)
    if len(pair) != 2:
        raise ScenarioError(field, f"expected 2 sphere indices, got {len(pair)}")
    indices = []
    for k, index in enumerate(pair):
        if isinstance(index, bool) or not isinstance(index, int):
            raise ScenarioError(f"{field}[{k}]", f"expected an integer, got {describe(index)}")
        if not 0 <= index < n_spheres:
            raise ScenarioError(
                f"{field}[{k}]", f"sphere index {index} out of range (0 to {n_spheres - 1})"
            )
        indices.append(index)
    if indices[0] == indices[1]:
        raise ScenarioError(field, f"expected two different spheres, got {indices}")
    return indices[0], indices[1]
