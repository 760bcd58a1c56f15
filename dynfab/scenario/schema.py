"""Scenario files: load and validate the YAML contract of DESIGN.md section 5.

A scenario names a robot, a planner, the control period ``dt`` [s], the simulated
``duration`` [s], the initial state, one or more weighted goals and the obstacles.
Parsing never evaluates text as code (``yaml.safe_load`` only). Every violation raises
:class:`ScenarioError` with a one-line message that starts with the field path, e.g.
``goal[0].position: expected 3 numbers, got 2``.

Checks that need the robot (number of joints, planar or not, link names) live in
:func:`validate_for_robot`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Literal, cast

import yaml

from dynfab.describe import describe
from dynfab.geometry.orientation import unit_vector
from dynfab.geometry.shapes import (
    IDENTITY_QUATERNION,
    Box,
    Capsule,
    Cylinder,
    Plane,
    Shape,
    ShapeError,
    Sphere,
    quaternion_from_normal,
    quaternion_from_rpy,
    unit_quaternion,
)
from dynfab.robots.mesh_paths import resolve_uri

if TYPE_CHECKING:
    from dynfab.robots.robot import Robot

BUILTIN_ROBOTS: tuple[str, ...] = ("panda", "point", "boxer", "boxer-panda")
PLANNERS: tuple[str, ...] = ("static-fabric", "dynamic-fabric", "mpc")
TRAJECTORY_TYPES: tuple[str, ...] = ("linear", "circle", "polynomial", "expression", "spline", "rrt")
OBSTACLE_TYPES: tuple[str, ...] = ("sphere", "box", "cylinder", "capsule", "plane")
GoalType = Literal["position", "joint", "path", "pose", "axis"]
ObstacleType = Literal["sphere", "box", "cylinder", "capsule", "plane"]
_GOAL_TYPES: tuple[str, ...] = ("position", "joint", "path", "pose", "axis")
_WORKSPACE_KEYS = ("link", "parent_link", "axes", "tolerance", "weight", "offset")
_POSE_KEYS = ("link", "offset", "orientation", "rpy", "tolerance", "angle_tolerance", "weight")
_AXIS_KEYS = ("link", "angle_tolerance", "weight", "angular_velocity")
#: default ``angle_tolerance`` of pose and axis goals [rad]
DEFAULT_ANGLE_TOLERANCE = 0.1


class ScenarioError(ValueError):
    """An invalid scenario; the message is one line ``<field>: <problem>``.

    Attributes:
        field: Path of the offending field, e.g. ``goal[0].position``.
        problem: What is wrong with it.
    """

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(f"{field}: {problem}")


@dataclass(frozen=True)
class InitialState:
    """Initial joint state.

    Attributes:
        q: Joint positions [rad or m], base pose (x, y, yaw) first for mobile bases.
        qdot: Velocity coordinates: joint velocities [rad/s or m/s], or for a robot on a
            differential-drive base ``(v, ω, arm rates...)`` (forward speed [m/s], yaw
            rate [rad/s]); ``None`` when the file omits them, and zeros of the robot's
            size after :func:`validate_for_robot`.
    """

    q: tuple[float, ...]
    qdot: tuple[float, ...] | None


@dataclass(frozen=True)
class GoalSpec:
    """One weighted sub-goal; the first goal of a scenario is the primary one.

    Attributes:
        type: ``position`` (a workspace point for ``link``), ``joint`` (a configuration),
            ``path`` (``link`` follows the reference ``trajectory``), ``pose`` (a point
            and an orientation for ``link``) or ``axis`` (a link axis along a world
            direction).
        link: Goal link; None means the robot's goal link (see :func:`validate_for_robot`).
            Always None for joint goals.
        position: Target point [m] in the ``parent_link`` frame (one number per axis of
            ``axes`` if given, else x, y for planar robots and x, y, z otherwise), or the
            target configuration for joint goals. None for path goals.
        tolerance: Reached when ||x_link - x_goal|| < tolerance [m] (joint goals: [rad];
            unused by axis goals).
        weight: Relative weight of this goal (> 0).
        parent_link: Frame in which the target is expressed; None is the robot root.
        axes: The workspace axes constrained by the goal, a subset of ``"xyz"``; None: all.
        trajectory: Reference of a path goal, a read-only mapping with a ``type`` among
            :data:`TRAJECTORY_TYPES`; None for the other goal types.
        offset: The goal point on ``link``, in the link frame [m] (a tool centre point);
            position, path and pose goals.
        orientation: Target rotation of ``link`` in the world as a unit quaternion
            ``(w, x, y, z)`` (pose goals; ``rpy`` in the file is converted); else None.
        angle_tolerance: Pose and axis goals: reached when the orientation error is
            below this [rad].
        axis: Axis goals: the unit axis in the link frame; else None.
        direction: Axis goals: the unit world direction the axis should point along at
            t = 0; else None.
        angular_velocity: Axis goals: the direction turns at this angular velocity
            [rad/s] (world frame); None: at rest.
    """

    type: GoalType
    link: str | None = None
    position: tuple[float, ...] | None = None
    tolerance: float = 0.05
    weight: float = 1.0
    parent_link: str | None = None
    axes: str | None = None
    trajectory: Mapping[str, Any] | None = None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    orientation: tuple[float, float, float, float] | None = None
    angle_tolerance: float = DEFAULT_ANGLE_TOLERANCE
    axis: tuple[float, float, float] | None = None
    direction: tuple[float, float, float] | None = None
    angular_velocity: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class ObstacleSpec:
    """An obstacle shape, static (``position``) or moving (``trajectory`` of its centre;
    its orientation stays).

    Attributes:
        type: One of :data:`OBSTACLE_TYPES`.
        radius: Radius of a sphere, cylinder or capsule [m] (> 0); 0 for a box or plane.
        position: Centre [m] (a plane: its ``point``), 2 numbers (planar robots only) or 3;
            None if moving.
        trajectory: Read-only mapping of the centre's motion, with a ``type`` among
            :data:`TRAJECTORY_TYPES`; None if static.
        size: A box's full edge lengths (lx, ly, lz) [m]; None for other shapes.
        length: A cylinder's full length or a capsule's segment length, along the shape's z
            axis [m]; None for other shapes.
        orientation: Unit quaternion (w, x, y, z) of the shape frame (normalised from the
            file); a plane's takes +z onto its ``normal``.
        normal: A plane's unit normal, pointing out of the solid half-space; None otherwise.
    """

    type: ObstacleType
    radius: float = 0.0
    position: tuple[float, ...] | None = None
    trajectory: Mapping[str, Any] | None = None
    size: tuple[float, float, float] | None = None
    length: float | None = None
    orientation: tuple[float, float, float, float] = IDENTITY_QUATERNION
    normal: tuple[float, float, float] | None = None

    @property
    def shape(self) -> Shape:
        """The obstacle's geometry in its own frame."""
        if self.type == "sphere":
            return Sphere(self.radius)
        if self.type == "box":
            return Box(self.size)
        if self.type == "cylinder":
            return Cylinder(self.radius, self.length)
        if self.type == "capsule":
            return Capsule(self.radius, self.length)
        return Plane()


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


@dataclass(frozen=True)
class Scenario:
    """A validated scenario file.

    Attributes:
        robot: A name from :data:`BUILTIN_ROBOTS` or a URDF robot description.
        planner: One of :data:`PLANNERS`.
        dt: Control period [s] (> 0).
        duration: Simulated time [s] (>= dt).
        initial_state: Initial joint positions and velocities.
        goals: One or more goals; the first is the primary goal.
        obstacles: Obstacles: spheres, boxes, cylinders, capsules, planes (possibly none).
        path: The file the scenario was loaded from; None if built from a mapping.
    """

    robot: str | UrdfRobotSpec
    planner: str
    dt: float
    duration: float
    initial_state: InitialState
    goals: tuple[GoalSpec, ...]
    obstacles: tuple[ObstacleSpec, ...]
    path: Path | None = None


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario YAML file.

    Args:
        path: Scenario file; a URDF path inside it is relative to the file's directory.

    Returns:
        The scenario, with ``path`` set to the file.

    Raises:
        ScenarioError: If the file cannot be read, is not valid YAML or breaks the contract.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ScenarioError(str(path), f"cannot read file ({error.strerror})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise ScenarioError(str(path), _yaml_problem(error)) from None
    scenario = scenario_from_dict(data, path.parent)
    return dataclasses.replace(scenario, path=path)


def scenario_from_dict(data: object, base_dir: str | Path = ".") -> Scenario:
    """Validate a parsed scenario mapping.

    Args:
        data: The parsed YAML document.
        base_dir: Directory against which a relative URDF path is resolved.

    Returns:
        The scenario (``path`` is None).

    Raises:
        ScenarioError: On the first violation of the contract.
    """
    root = _mapping(data, "scenario")
    _check_keys(
        root,
        "",
        required=("robot", "planner", "dt", "duration", "initial_state", "goal"),
        optional=("obstacles",),
    )
    dt = _positive(root["dt"], "dt")
    duration = _positive(root["duration"], "duration")
    if duration < dt:
        raise ScenarioError("duration", f"must be at least dt = {dt:g} s, got {duration:g}")
    goals = _list(root["goal"], "goal")
    if not goals:
        raise ScenarioError("goal", "expected at least one goal, got an empty list")
    obstacles = _list(root.get("obstacles", []), "obstacles")
    return Scenario(
        robot=_robot(root["robot"], "robot", Path(base_dir)),
        planner=_choice(root["planner"], "planner", PLANNERS),
        dt=dt,
        duration=duration,
        initial_state=_initial_state(root["initial_state"], "initial_state"),
        goals=tuple(_goal(goal, f"goal[{i}]") for i, goal in enumerate(goals)),
        obstacles=tuple(_obstacle(obs, f"obstacles[{i}]") for i, obs in enumerate(obstacles)),
    )


def validate_for_robot(scenario: Scenario, robot: Robot) -> Scenario:
    """Check the robot-dependent shapes and names, and fill in default goal links.

    Checks: ``initial_state.q`` has ``robot.kinematics.dof`` entries and ``qdot`` one per
    velocity coordinate (``dof``, or ``dof − 1`` on a differential-drive base; omitted:
    zeros); goal
    positions have 2 numbers for planar robots and 3 otherwise (or one per axis of
    ``axes``, which must not contain z for planar robots); joint goals have ``dof``
    entries; obstacle positions have 3 numbers (planar robots: 2 or 3; a plane's normal
    must then have an x or y part: planar robots see shapes at the height of their
    centre); every link named by the scenario exists.

    Args:
        scenario: A scenario from :func:`load_scenario` or :func:`scenario_from_dict`.
        robot: The robot it runs on (uses ``kinematics.dof``, ``kinematics.link_names``,
            ``planar`` and ``goal_link``).

    Returns:
        The scenario with every ``link=None`` of position and path goals replaced by
        ``robot.goal_link``.

    Raises:
        ScenarioError: Naming the first field that does not fit the robot.
    """
    dof = robot.kinematics.dof
    velocities = dof - 1 if robot.base is not None else dof
    links = tuple(robot.kinematics.link_names)
    state = scenario.initial_state
    joints = robot.kinematics.joint_names
    _check_length(state.q, "initial_state.q", (dof,), f" (one per joint: {', '.join(joints)})")
    if state.qdot is None:
        state = dataclasses.replace(state, qdot=(0.0,) * velocities)
    velocity_names = ("v", "omega") + joints[3:] if robot.base is not None else joints
    _check_length(state.qdot, "initial_state.qdot", (velocities,),
                  f" (one per velocity: {', '.join(velocity_names)})")
    if isinstance(scenario.robot, UrdfRobotSpec):
        _check_link(scenario.robot.goal_link, "robot.goal_link", links)
        explicit = scenario.robot.collision_spheres
        for i, sphere in enumerate(() if explicit == "auto" else explicit):
            _check_link(sphere.link, f"robot.collision_spheres[{i}].link", links)
    goals = tuple(
        _goal_for_robot(goal, f"goal[{i}]", robot, links)
        for i, goal in enumerate(scenario.goals)
    )
    obstacle_lengths = (2, 3) if robot.planar else (3,)
    for i, obstacle in enumerate(scenario.obstacles):
        if obstacle.position is not None:
            key = "point" if obstacle.type == "plane" else "position"
            _check_length(obstacle.position, f"obstacles[{i}].{key}", obstacle_lengths)
        if robot.planar and obstacle.normal is not None and math.hypot(*obstacle.normal[:2]) < 1e-9:
            raise ScenarioError(f"obstacles[{i}].normal", "a planar robot moves in the xy-plane, which a "
                                f"horizontal plane never bounds; use a wall (normal with an x or y part), "
                                f"got {list(obstacle.normal)}")
    return dataclasses.replace(scenario, goals=goals, initial_state=state)


def _goal_for_robot(
    goal: GoalSpec, field: str, robot: Robot, links: tuple[str, ...]
) -> GoalSpec:
    """Check one goal against the robot and resolve its default link."""
    position = goal.position or ()
    if goal.type == "joint":
        _check_length(position, f"{field}.position", (robot.kinematics.dof,),
                      f" (one per joint: {', '.join(robot.kinematics.joint_names)})")
        return goal
    link = robot.goal_link if goal.link is None else goal.link
    _check_link(link, f"{field}.link", links)
    if robot.planar and goal.type in ("pose", "axis"):
        raise ScenarioError(f"{field}.type", f"{goal.type} goals need a robot in space; this robot is planar")
    if goal.parent_link is not None:
        _check_link(goal.parent_link, f"{field}.parent_link", links)
    if robot.planar and goal.axes is not None and "z" in goal.axes:
        raise ScenarioError(f"{field}.axes", f"planar robot has no z axis, got {goal.axes!r}")
    if goal.type == "position" and goal.axes is None:
        _check_length(position, f"{field}.position", (2 if robot.planar else 3,))
    return dataclasses.replace(goal, link=link)


def _check_link(link: str, field: str, links: tuple[str, ...]) -> None:
    """Raise unless ``link`` is one of the robot's links."""
    if link not in links:
        raise ScenarioError(field, f"unknown link {link!r} (robot links: {', '.join(links)})")


def _check_length(values: Sequence[float], field: str, lengths: tuple[int, ...], which: str = "") -> None:
    """Raise unless ``values`` has one of the allowed ``lengths``; ``which`` says what they are."""
    if len(values) not in lengths:
        expected = " or ".join(str(n) for n in lengths)
        raise ScenarioError(field, f"expected {expected} numbers{which}, got {len(values)}")


def _robot(value: object, field: str, base_dir: Path) -> str | UrdfRobotSpec:
    """Parse ``robot``: a built-in name or a URDF description mapping."""
    if isinstance(value, str):
        return _choice(value, field, BUILTIN_ROBOTS)
    data = _mapping(value, field, "a built-in robot name or a mapping")
    _check_keys(
        data,
        field,
        required=("urdf", "goal_link"),
        optional=("collision_spheres", "self_collision_pairs", "planar", "package_dirs", "joints",
                  "locked", "sphere_tolerance"),
    )
    package_dirs = tuple(base_dir / _string(d, f"{field}.package_dirs[{i}]")
                         for i, d in enumerate(_list(data.get("package_dirs", []), f"{field}.package_dirs")))
    uri = _string(data["urdf"], f"{field}.urdf")
    urdf = resolve_uri(uri, base_dir, package_dirs)
    if urdf is None:
        raise ScenarioError(f"{field}.urdf", f"file not found: {uri} (a path relative to the scenario "
                            "file, absolute, or package://NAME/... found through package_dirs, "
                            "DYNFAB_PACKAGE_PATH or an installed example-robot-data / pybullet)")
    joints = None
    if "joints" in data:
        joints = tuple(_string(j, f"{field}.joints[{i}]")
                       for i, j in enumerate(_list(data["joints"], f"{field}.joints")))
    locked_data = _mapping(data.get("locked", {}), f"{field}.locked")
    locked = {str(name): _number(value, f"{field}.locked.{name}") for name, value in locked_data.items()}
    spheres = _spheres(data.get("collision_spheres", []), f"{field}.collision_spheres")
    pairs = _pairs(data.get("self_collision_pairs", "auto" if spheres == "auto" else []),
                   f"{field}.self_collision_pairs", spheres)
    tolerance = 0.01
    if "sphere_tolerance" in data:
        if spheres != "auto":
            raise ScenarioError(f"{field}.sphere_tolerance", "only applies to collision_spheres: auto")
        tolerance = _positive(data["sphere_tolerance"], f"{field}.sphere_tolerance")
    planar = data.get("planar", False)
    if not isinstance(planar, bool):
        raise ScenarioError(f"{field}.planar", f"expected true or false, got {describe(planar)}")
    return UrdfRobotSpec(
        urdf=urdf,
        goal_link=_string(data["goal_link"], f"{field}.goal_link"),
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
    return tuple(_collision_sphere(sphere, f"{field}[{i}]") for i, sphere in enumerate(_list(value, field)))


def _pairs(value: object, field: str, spheres: tuple[CollisionSphereSpec, ...] | Literal["auto"]
           ) -> tuple[tuple[int, int], ...] | Literal["auto"]:
    """Parse ``self_collision_pairs``: ``auto`` or index pairs into explicit spheres."""
    if value == "auto":
        return "auto"
    if isinstance(value, str):
        raise ScenarioError(field, f"expected auto or a list of [i, j] sphere index pairs, got {value!r}")
    pairs = _list(value, field)
    if spheres == "auto" and pairs:
        raise ScenarioError(field, "index pairs need explicit collision_spheres; with "
                            "collision_spheres: auto use self_collision_pairs: auto")
    count = 0 if spheres == "auto" else len(spheres)
    return tuple(_sphere_pair(pair, f"{field}[{i}]", count) for i, pair in enumerate(pairs))


def _collision_sphere(value: object, field: str) -> CollisionSphereSpec:
    """Parse one ``{link, center, radius}`` collision sphere."""
    data = _mapping(value, field)
    _check_keys(data, field, required=("link", "center", "radius"))
    x, y, z = _vector(data["center"], f"{field}.center", (3,))
    return CollisionSphereSpec(
        link=_string(data["link"], f"{field}.link"),
        center=(x, y, z),
        radius=_positive(data["radius"], f"{field}.radius"),
    )


def _sphere_pair(value: object, field: str, n_spheres: int) -> tuple[int, int]:
    """Parse a self-collision pair ``[i, j]`` of distinct collision-sphere indices."""
    pair = _list(value, field)
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


def _initial_state(value: object, field: str) -> InitialState:
    """Parse ``initial_state``; ``qdot`` defaults to zeros."""
    data = _mapping(value, field)
    _check_keys(data, field, required=("q",), optional=("qdot",))
    q = _vector(data["q"], f"{field}.q")
    if "qdot" not in data:
        return InitialState(q=q, qdot=None)
    return InitialState(q=q, qdot=_vector(data["qdot"], f"{field}.qdot"))


def _goal(value: object, field: str) -> GoalSpec:
    """Parse one entry of ``goal``; the allowed keys depend on its ``type``."""
    data = _mapping(value, field)
    if "type" not in data:
        raise ScenarioError(f"{field}.type", "missing required key")
    goal_type = cast(GoalType, _choice(data["type"], f"{field}.type", _GOAL_TYPES))
    if goal_type == "joint":
        _check_keys(data, field, ("type", "position"), ("tolerance", "weight"))
    elif goal_type == "pose":
        return _pose_goal(data, field)
    elif goal_type == "axis":
        return _axis_goal(data, field)
    else:
        target = "position" if goal_type == "position" else "trajectory"
        _check_keys(data, field, ("type", target), _WORKSPACE_KEYS)
    axes = _axes(data["axes"], f"{field}.axes") if "axes" in data else None
    position: tuple[float, ...] | None = None
    trajectory: Mapping[str, Any] | None = None
    if goal_type == "joint":
        position = _vector(data["position"], f"{field}.position")
    elif goal_type == "position":
        position = _goal_position(data["position"], f"{field}.position", axes)
    else:
        trajectory = _trajectory(data["trajectory"], f"{field}.trajectory")
    return GoalSpec(
        type=goal_type,
        link=_optional_string(data, "link", field),
        position=position,
        tolerance=_positive(data.get("tolerance", 0.05), f"{field}.tolerance"),
        weight=_positive(data.get("weight", 1.0), f"{field}.weight"),
        parent_link=_optional_string(data, "parent_link", field),
        axes=axes,
        trajectory=trajectory,
        offset=_offset(data, field),
    )


def _pose_goal(data: Mapping[str, Any], field: str) -> GoalSpec:
    """Parse a ``pose`` goal: a point on the link and a rotation (quaternion or rpy)."""
    _check_keys(data, field, ("type", "position"), _POSE_KEYS)
    if ("orientation" in data) == ("rpy" in data):
        raise ScenarioError(field, "expected exactly one of 'orientation' [w, x, y, z] or 'rpy' [roll, pitch, yaw]")
    try:
        if "orientation" in data:
            orientation = unit_quaternion(_vector(data["orientation"], f"{field}.orientation", (4,)))
        else:
            orientation = quaternion_from_rpy(_vector(data["rpy"], f"{field}.rpy", (3,)))
    except ShapeError as error:
        key = "orientation" if "orientation" in data else "rpy"
        raise ScenarioError(f"{field}.{key}", str(error)) from None
    return GoalSpec(
        type="pose",
        link=_optional_string(data, "link", field),
        position=_vector(data["position"], f"{field}.position", (3,)),
        tolerance=_positive(data.get("tolerance", 0.05), f"{field}.tolerance"),
        weight=_positive(data.get("weight", 1.0), f"{field}.weight"),
        offset=_offset(data, field),
        orientation=orientation,
        angle_tolerance=_angle_tolerance(data, field),
    )


def _axis_goal(data: Mapping[str, Any], field: str) -> GoalSpec:
    """Parse an ``axis`` goal: a link axis that should point along a world direction."""
    _check_keys(data, field, ("type", "axis", "direction"), _AXIS_KEYS)
    angular_velocity = None
    if "angular_velocity" in data:
        x, y, z = _vector(data["angular_velocity"], f"{field}.angular_velocity", (3,))
        angular_velocity = (x, y, z)
    return GoalSpec(
        type="axis",
        link=_optional_string(data, "link", field),
        weight=_positive(data.get("weight", 1.0), f"{field}.weight"),
        axis=_unit(data["axis"], f"{field}.axis"),
        direction=_unit(data["direction"], f"{field}.direction"),
        angle_tolerance=_angle_tolerance(data, field),
        angular_velocity=angular_velocity,
    )


def _offset(data: Mapping[str, Any], field: str) -> tuple[float, float, float]:
    """``offset``: a point in the link frame [m], the origin if absent."""
    if "offset" not in data:
        return (0.0, 0.0, 0.0)
    x, y, z = _vector(data["offset"], f"{field}.offset", (3,))
    return (x, y, z)


def _unit(value: object, field: str) -> tuple[float, float, float]:
    """A non-zero 3-vector, normalised."""
    vector = _vector(value, field, (3,))
    try:
        return unit_vector(vector)
    except ValueError:
        raise ScenarioError(field, "expected a non-zero direction, got [0, 0, 0]") from None


def _angle_tolerance(data: Mapping[str, Any], field: str) -> float:
    """``angle_tolerance`` in (0, π] [rad]."""
    tolerance = _positive(data.get("angle_tolerance", DEFAULT_ANGLE_TOLERANCE), f"{field}.angle_tolerance")
    if tolerance > math.pi:
        raise ScenarioError(f"{field}.angle_tolerance", f"expected at most pi rad, got {tolerance:g}")
    return tolerance


def _goal_position(value: object, field: str, axes: str | None) -> tuple[float, ...]:
    """Parse a goal point: one number per axis of ``axes``, else 2 or 3 numbers."""
    if axes is None:
        return _vector(value, field, (2, 3))
    position = _vector(value, field)
    if len(position) != len(axes):
        raise ScenarioError(
            field, f"expected {len(axes)} numbers (one per axis of {axes!r}), got {len(position)}"
        )
    return position


def _axes(value: object, field: str) -> str:
    """Parse ``axes``: distinct letters of ``xyz`` in that order, e.g. ``xy``."""
    axes = _string(value, field)
    if axes not in ("x", "y", "z", "xy", "xz", "yz", "xyz"):
        raise ScenarioError(
            field, f"expected distinct axes among x, y, z in that order (e.g. 'xy'), got {axes!r}"
        )
    return axes


#: Keys of each obstacle type besides ``type``: (required, optional); every type also
#: takes exactly one of its placement key (``position``, a plane's ``point``) or ``trajectory``.
_OBSTACLE_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "sphere": (("radius",), ()),
    "box": (("size",), ("orientation",)),
    "cylinder": (("radius", "length"), ("orientation",)),
    "capsule": (("radius", "length"), ("orientation",)),
    "plane": (("normal",), ()),
}


def _obstacle(value: object, field: str) -> ObstacleSpec:
    """Parse one entry of ``obstacles``; the allowed keys depend on its ``type``."""
    data = _mapping(value, field)
    if "type" not in data:
        raise ScenarioError(f"{field}.type", "missing required key")
    kind = cast(ObstacleType, _choice(data["type"], f"{field}.type", OBSTACLE_TYPES))
    placement = "point" if kind == "plane" else "position"
    required, optional = _OBSTACLE_KEYS[kind]
    _check_keys(data, field, ("type",) + required, optional + (placement, "trajectory"))
    if (placement in data) == ("trajectory" in data):
        raise ScenarioError(
            field, f"expected exactly one of '{placement}' (static) or 'trajectory' (moving)"
        )
    moving = "trajectory" in data
    normal = _normal(data["normal"], f"{field}.normal") if kind == "plane" else None
    orientation = _orientation(data["orientation"], f"{field}.orientation") if "orientation" in data \
        else IDENTITY_QUATERNION
    return ObstacleSpec(
        type=kind,
        radius=_positive(data["radius"], f"{field}.radius") if "radius" in data else 0.0,
        position=None if moving else _vector(data[placement], f"{field}.{placement}", (2, 3)),
        trajectory=_trajectory(data["trajectory"], f"{field}.trajectory") if moving else None,
        size=_size(data["size"], f"{field}.size") if kind == "box" else None,
        length=_positive(data["length"], f"{field}.length") if "length" in data else None,
        orientation=quaternion_from_normal(normal) if normal is not None else orientation,
        normal=normal,
    )


def _size(value: object, field: str) -> tuple[float, float, float]:
    """Parse a box's edge lengths: 3 positive numbers [m]."""
    numbers = _vector(value, field, (3,))
    lx, ly, lz = (_positive(number, f"{field}[{i}]") for i, number in enumerate(numbers))
    return lx, ly, lz


def _orientation(value: object, field: str) -> tuple[float, float, float, float]:
    """Parse a quaternion [w, x, y, z]; a non-unit one is normalised, a zero one rejected."""
    numbers = _vector(value, field, (4,))
    try:
        return unit_quaternion(numbers)
    except ShapeError:
        raise ScenarioError(field, f"expected a non-zero quaternion [w, x, y, z], got {list(numbers)}") from None


def _normal(value: object, field: str) -> tuple[float, float, float]:
    """Parse a plane's normal: 3 numbers, not all zero; returned unit length."""
    numbers = _vector(value, field, (3,))
    length = math.hypot(*numbers)
    if length < 1e-9:
        raise ScenarioError(field, f"expected a non-zero vector, got {list(numbers)}")
    x, y, z = (number / length for number in numbers)
    return x, y, z


def _trajectory(value: object, field: str) -> Mapping[str, Any]:
    """Check a trajectory is a mapping with a known ``type``; return it read-only."""
    data = _mapping(value, field)
    if "type" not in data:
        raise ScenarioError(f"{field}.type", "missing required key")
    _choice(data["type"], f"{field}.type", TRAJECTORY_TYPES)
    return cast(Mapping[str, Any], _freeze(data))


def _freeze(value: object) -> object:
    """Return a read-only deep copy: mappings become MappingProxyType, lists tuples."""
    if isinstance(value, Mapping):
        return MappingProxyType({key: _freeze(item) for key, item in value.items()})
    if isinstance(value, list | tuple):
        return tuple(_freeze(item) for item in value)
    return value


def _mapping(value: object, field: str, expected: str = "a mapping") -> Mapping[str, Any]:
    """Return ``value`` if it is a mapping with string keys."""
    if not isinstance(value, Mapping):
        raise ScenarioError(field or "scenario", f"expected {expected}, got {describe(value)}")
    for key in value:
        if not isinstance(key, str):
            raise ScenarioError(field or "scenario", f"keys must be text, got {describe(key)}")
    return value


def _check_keys(
    data: Mapping[str, Any], field: str, required: Iterable[str], optional: Iterable[str] = ()
) -> None:
    """Raise on the first unknown key, then on the first missing required key."""
    required = tuple(required)
    allowed = required + tuple(optional)
    for key in data:
        if key not in allowed:
            raise ScenarioError(_join(field, key), f"unknown key (allowed: {', '.join(allowed)})")
    for key in required:
        if key not in data:
            raise ScenarioError(_join(field, key), "missing required key")


def _join(field: str, key: str) -> str:
    """Field path of ``key`` inside ``field`` (the top level has an empty path)."""
    return f"{field}.{key}" if field else key


def _list(value: object, field: str) -> list[Any]:
    """Return ``value`` if it is a list."""
    if not isinstance(value, list | tuple):
        raise ScenarioError(field, f"expected a list, got {describe(value)}")
    return list(value)


def _string(value: object, field: str) -> str:
    """Return ``value`` if it is a non-empty string."""
    if not isinstance(value, str) or not value:
        raise ScenarioError(field, f"expected a non-empty text, got {describe(value)}")
    return value


def _optional_string(data: Mapping[str, Any], key: str, field: str) -> str | None:
    """Return ``data[key]`` as a non-empty string, or None if absent."""
    return _string(data[key], f"{field}.{key}") if key in data else None


def _choice(value: object, field: str, options: tuple[str, ...]) -> str:
    """Return ``value`` if it is one of ``options``."""
    if not isinstance(value, str) or value not in options:
        raise ScenarioError(field, f"expected one of {', '.join(options)}; got {describe(value)}")
    return value


def _number(value: object, field: str) -> float:
    """Return ``value`` as a finite float (booleans are not numbers)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        hint = ""
        if isinstance(value, str) and _is_float_text(value):
            hint = " (YAML reads 1e-3 as text: write 1.0e-3)"
        raise ScenarioError(field, f"expected a number, got {describe(value)}{hint}")
    number = float(value)
    if not math.isfinite(number):
        raise ScenarioError(field, f"expected a finite number, got {number}")
    return number


def _is_float_text(text: str) -> bool:
    """True if ``text`` spells a float (e.g. ``1e-3``, which YAML 1.1 keeps as text)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _positive(value: object, field: str) -> float:
    """Return ``value`` as a finite float > 0."""
    number = _number(value, field)
    if number <= 0.0:
        raise ScenarioError(field, f"must be positive, got {number:g}")
    return number


def _vector(value: object, field: str, lengths: tuple[int, ...] | None = None) -> tuple[float, ...]:
    """Return a non-empty list of finite numbers, optionally of one of ``lengths``."""
    items = _list(value, field)
    if not items:
        raise ScenarioError(field, "expected numbers, got an empty list")
    if lengths is not None:
        _check_length(items, field, lengths)
    return tuple(_number(item, f"{field}[{i}]") for i, item in enumerate(items))


def _yaml_problem(error: yaml.YAMLError) -> str:
    """One-line description of a YAML syntax error."""
    if isinstance(error, yaml.MarkedYAMLError) and error.problem_mark is not None:
        mark = error.problem_mark
        problem = error.problem or error.context or "syntax error"
        return f"invalid YAML: {problem} (line {mark.line + 1}, column {mark.column + 1})"
    return "invalid YAML: " + " ".join(str(error).split())
