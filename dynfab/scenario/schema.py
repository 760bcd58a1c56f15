"""Scenario files: load and validate the YAML contract of docs/design.md section 5.

A scenario names a robot, a planner, the control period ``dt`` [s], the simulated
``duration`` [s], the initial state, one or more weighted goals and the obstacles.
The file is read under the limits of :mod:`dynfab.scenario.yaml_loader` (size, encoding,
nesting, aliases, duplicate keys; never code), then validated by the pydantic model
:class:`ScenarioDocument` (whose JSON Schema ``dynfab schema`` prints), with the
documented range of every number (:mod:`dynfab.scenario.ranges`). Every violation raises
:class:`ScenarioError` with a one-line message that starts with the field path, e.g.
``goal[0].position: expected 3 numbers, got 2``.

Checks that need the robot (number of joints, planar or not, link names) live in
:func:`validate_for_robot`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

from pydantic import Field, ValidationError, model_validator

from dynfab.fabric.backends import BACKENDS, default_backend
from dynfab.perception.camera_spec import CameraSpec
from dynfab.perception.workspace import robot_workspace
from dynfab.scenario import fields
from dynfab.scenario.camera_schema import PERCEPTION, CameraMapping
from dynfab.scenario.fabric_schema import FabricMapping, FabricSpec
from dynfab.scenario.fields import TRAJECTORY_TYPES, ScenarioError
from dynfab.scenario.goal_schema import DEFAULT_ANGLE_TOLERANCE, GoalMapping, GoalSpec, GoalType, goal_spec
from dynfab.scenario.joint_limits import check_within_limits, clipped_to_limits
from dynfab.scenario.limits_schema import LimitsMapping, LimitsSpec
from dynfab.scenario.model_errors import scenario_error
from dynfab.scenario.model_types import Choice, Flag, Items, Range, ScenarioModel, fail
from dynfab.scenario.obstacle_schema import OBSTACLE_TYPES, ObstacleMapping, ObstacleSpec, ObstacleType
from dynfab.scenario.mujoco_obstacles import check_mujoco_obstacles
from dynfab.scenario.scene_files import obstacle_specs
from dynfab.scenario.ranges import (
    MAX_DT,
    MAX_DURATION,
    MAX_GOALS,
    MAX_JOINT_VALUE,
    MAX_OBSTACLES,
    MAX_SPEED,
    MAX_STEPS,
)
from dynfab.scenario.robot_schema import (BUILTIN_ROBOTS, BuiltinRobotSpec, CollisionSphereSpec, RobotMapping,
                                         UrdfRobotSpec, robot_spec)
from dynfab.scenario.simulation_schema import CONTROL, DELAY, NOISE, SIMULATOR, Simulation
from dynfab.scenario.yaml_loader import load_yaml_file

if TYPE_CHECKING:
    from dynfab.robots.limits import MotionLimits
    from dynfab.robots.robot import Robot

__all__ = ["BUILTIN_ROBOTS", "BuiltinRobotSpec", "DEFAULT_ANGLE_TOLERANCE", "OBSTACLE_TYPES", "PLANNERS", "TRAJECTORY_TYPES",
           "CollisionSphereSpec", "FabricSpec", "GoalSpec", "GoalType", "InitialState", "ObstacleSpec", "ObstacleType",
           "Scenario", "ScenarioDocument", "ScenarioError", "Simulation", "UrdfRobotSpec", "load_scenario",
           "scenario_from_dict", "validate_for_robot"]


PLANNERS: tuple[str, ...] = ("static-fabric", "dynamic-fabric", "mpc")


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
class Scenario:
    """A validated scenario file.

    Attributes:
        robot: A name from :data:`BUILTIN_ROBOTS`, one with options (the Panda's finger
            opening: :class:`BuiltinRobotSpec`) or a URDF robot description.
        planner: One of :data:`PLANNERS`.
        dt: Control period [s] (> 0).
        duration: Simulated time [s] (>= dt).
        initial_state: Initial joint positions and velocities.
        goals: One or more goals; the first is the primary goal.
        obstacles: Obstacles: spheres, boxes, cylinders, capsules, planes (possibly none).
        path: The file the scenario was loaded from; None if built from a mapping.
        limits: Overrides of the robot's velocity, acceleration and jerk limits.
        simulation: The simulator (kinematic or MuJoCo) and, under MuJoCo, the control
            mode, observation delay and noise.
        recovery: Recover from stalls by following a global path
            (scenario/stall_recovery.py) where guidance does not apply or failed;
            ``recovery: false`` turns it off.
        guidance: Plan a global joint-space reference that a dynamic fabric tracks
            (scenario/guided_controller.py); ``guidance: false`` runs the fabric alone.
        backend: How a fabric planner is evaluated: ``"c"`` (compiled C, cached; the
            default unless ``$DYNFAB_BACKEND`` says ``vm``) or ``"vm"`` (CasADi's virtual
            machine; :mod:`dynfab.fabric.backends`).
        fabric: Leaf and root parameters of a fabric planner (``fabric:``,
            :mod:`dynfab.scenario.fabric_schema`); the planner's defaults where unset.
        camera: A depth camera rendered by MuJoCo (``camera:``,
            :mod:`dynfab.scenario.camera_schema`), or None.
        perception: ``truth`` (the planner is given the obstacles) or ``camera`` (it knows
            the scene only through the camera; the obstacles stay in the physics and metrics).
        camera_workspace_margin: ``camera.workspace_margin`` [m]: the camera keeps only the
            points within the robot's reach plus this margin; None keeps every point.
    """

    robot: str | BuiltinRobotSpec | UrdfRobotSpec
    planner: str
    dt: float
    duration: float
    initial_state: InitialState
    goals: tuple[GoalSpec, ...]
    obstacles: tuple[ObstacleSpec, ...]
    path: Path | None = None
    limits: LimitsSpec = LimitsSpec()
    simulation: Simulation = Simulation()
    recovery: bool = True
    backend: str = field(default_factory=default_backend)
    fabric: FabricSpec = FabricSpec()
    guidance: bool = True
    camera: CameraSpec | None = None
    perception: str = "truth"
    camera_workspace_margin: float | None = None

    def planning_limits(self, limits: MotionLimits) -> MotionLimits:
        """``limits`` as a planner (and a base's wheel drive) works with them here: every
        velocity limit less the headroom under this scenario's simulator
        (:mod:`dynfab.scenario.limits_schema`)."""
        return limits.with_headroom(self.limits.headroom_for(self.simulation.simulator))


JointValues = Annotated[tuple[Annotated[float, Range(-MAX_JOINT_VALUE, MAX_JOINT_VALUE)], ...], Items(max_items=64)]
Velocities = Annotated[tuple[Annotated[float, Range(-MAX_SPEED, MAX_SPEED)], ...], Items(max_items=64)]


class InitialStateMapping(ScenarioModel):
    """``initial_state: {q: [...] [rad or m], qdot: [...] [rad/s or m/s]}`` (``qdot`` optional)."""

    q: JointValues
    qdot: Velocities | None = None


class ScenarioDocument(ScenarioModel):
    """A scenario file (docs/design.md section 5); every number has its documented range
    (:mod:`dynfab.scenario.ranges`), ``duration / dt`` is at most ``MAX_STEPS``."""

    model_config = {"title": "dynfab scenario"}
    robot: RobotMapping
    planner: Annotated[str, Choice(PLANNERS)]
    dt: Annotated[float, Range(0.0, MAX_DT, open_lower=True, unit=" s")]
    duration: Annotated[float, Range(0.0, MAX_DURATION, open_lower=True, unit=" s")]
    initial_state: InitialStateMapping
    goal: Annotated[tuple[GoalMapping, ...], Items(what="goals", allow_empty=True, max_items=MAX_GOALS)]
    obstacles: Annotated[tuple[ObstacleMapping, ...],
                         Items(what="obstacles", allow_empty=True, max_items=MAX_OBSTACLES)] = ()
    limits: LimitsMapping = LimitsMapping()
    simulator: Annotated[str, SIMULATOR] = "kinematic"
    control: Annotated[str, CONTROL] = "torque"
    delay: Annotated[float, DELAY] = 0.0
    noise: Annotated[float, NOISE] = 0.0
    recovery: Annotated[bool, Flag()] = True
    guidance: Annotated[bool, Flag()] = True
    backend: Annotated[str, Choice(BACKENDS)] = Field(default_factory=default_backend)
    fabric: FabricMapping = FabricMapping()
    camera: CameraMapping | None = None
    perception: Annotated[str, PERCEPTION] = "truth"

    @model_validator(mode="after")
    def _consistent(self) -> ScenarioDocument:
        if self.duration < self.dt:
            raise fail(f"must be at least dt = {self.dt:g} s, got {self.duration:g}", "duration")
        if self.duration / self.dt > MAX_STEPS:
            raise fail(f"{self.duration:g} s at dt = {self.dt:g} s is {self.duration / self.dt:.3g} control steps, "
                       f"more than {MAX_STEPS}", "duration")
        if not self.goal:
            raise fail("expected at least one goal, got an empty list", "goal")
        if self.simulator != "mujoco":
            for key in ("control", "delay", "noise"):
                if key in self.model_fields_set:
                    raise fail("applies to simulator: mujoco only (the kinematic simulator follows the planner "
                               "exactly)", key)
            if self.camera is not None:
                raise fail("applies to simulator: mujoco only (MuJoCo renders the camera's depth images)", "camera")
        if self.perception == "camera":
            if self.camera is None:
                raise fail("camera needs a camera: block (position, look_at, ...)", "perception")
            if self.planner == "mpc":
                raise fail("camera needs a fabric planner (the mpc planner avoids spheres only), got planner: mpc",
                           "perception")
        return self

    def scenario(self, base_dir: Path) -> Scenario:
        """The scenario value; a URDF path, a mesh or a scene file is resolved against
        ``base_dir``; a URDF scene becomes one obstacle per collision geometry
        (:mod:`dynfab.scenario.scene_files`).

        Raises:
            ScenarioError: The URDF file is not found, a mesh or scene file is bad, or MuJoCo
                cannot simulate an obstacle (:mod:`dynfab.scenario.mujoco_obstacles`).
        """
        entries = [tuple(dataclasses.replace(spec, source=f"obstacles[{k}]")
                         for spec in obstacle_specs(obstacle, base_dir, f"obstacles[{k}]"))
                   for k, obstacle in enumerate(self.obstacles)]
        if self.simulator == "mujoco":
            check_mujoco_obstacles(entries, self.perception)
        return Scenario(
            robot=robot_spec(self.robot, "robot", base_dir),
            planner=self.planner,
            dt=self.dt,
            duration=self.duration,
            initial_state=InitialState(self.initial_state.q, self.initial_state.qdot),
            goals=tuple(goal_spec(goal) for goal in self.goal),
            obstacles=tuple(spec for specs in entries for spec in specs),
            limits=self.limits.spec(),
            simulation=Simulation(self.simulator, self.control, self.delay, self.noise),
            recovery=self.recovery,
            guidance=self.guidance,
            backend=self.backend,
            fabric=self.fabric.spec(),
            camera=None if self.camera is None else self.camera.spec(),
            perception=self.perception,
            camera_workspace_margin=None if self.camera is None else self.camera.workspace_margin,
        )


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
    scenario = scenario_from_dict(load_yaml_file(path), path.parent)
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
    try:
        document = ScenarioDocument.model_validate(data)
    except ValidationError as error:
        raise scenario_error(error) from None
    return document.scenario(Path(base_dir))


def validate_for_robot(scenario: Scenario, robot: Robot) -> Scenario:
    """Check the robot-dependent shapes and names, and fill in default goal links.

    Checks: ``initial_state.q`` has ``robot.kinematics.dof`` entries within the joint
    limits (:mod:`dynfab.scenario.joint_limits`) and ``qdot`` one per
    velocity coordinate (``dof``, or ``dof − 1`` on a differential-drive base; omitted:
    zeros); goal
    positions have 2 numbers for planar robots and 3 otherwise (or one per axis of
    ``axes``, which must not contain z for planar robots); joint goals have ``dof``
    entries within the joint limits; obstacle positions have 3 numbers (planar robots: 2 or 3; a plane's normal
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
    fields.check_length(state.q, "initial_state.q", (dof,), f" (one per joint: {', '.join(joints)})")
    check_within_limits(state.q, robot, "initial_state.q")
    state = dataclasses.replace(state, q=clipped_to_limits(state.q, robot))
    if state.qdot is None:
        state = dataclasses.replace(state, qdot=(0.0,) * velocities)
    velocity_names = ("v", "omega") + joints[3:] if robot.base is not None else joints
    fields.check_length(state.qdot, "initial_state.qdot", (velocities,),
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
        name = obstacle.name(i)
        if obstacle.position is not None:
            key = "point" if obstacle.type == "plane" else "position"
            fields.check_length(obstacle.position, f"{name}.{key}", obstacle_lengths)
        if robot.planar and obstacle.type in ("mesh", "points"):
            raise ScenarioError(f"{name}.type", f"a planar robot moves in the xy-plane; {obstacle.type} obstacles "
                                "are 3-D "
                                "(use spheres, boxes, cylinders or planes)")
        if robot.planar and obstacle.normal is not None and math.hypot(*obstacle.normal[:2]) < 1e-9:
            raise ScenarioError(f"{name}.normal", "a planar robot moves in the xy-plane, which a "
                                f"horizontal plane never bounds; use a wall (normal with an x or y part), "
                                f"got {list(obstacle.normal)}")
    if scenario.camera_workspace_margin is not None:
        try:
            robot_workspace(robot, scenario.camera_workspace_margin)
        except ValueError as error:
            raise ScenarioError("camera.workspace_margin", f"{error}; leave workspace_margin out") from None
    return dataclasses.replace(scenario, goals=goals, initial_state=state)


def _goal_for_robot(
    goal: GoalSpec, field: str, robot: Robot, links: tuple[str, ...]
) -> GoalSpec:
    """Check one goal against the robot and resolve its default link."""
    position = goal.position or ()
    if goal.type == "joint":
        fields.check_length(position, f"{field}.position", (robot.kinematics.dof,),
                            f" (one per joint: {', '.join(robot.kinematics.joint_names)})")
        check_within_limits(position, robot, f"{field}.position")
        return dataclasses.replace(goal, position=clipped_to_limits(position, robot))
    link = robot.goal_link if goal.link is None else goal.link
    _check_link(link, f"{field}.link", links)
    if robot.planar and goal.type in ("pose", "axis"):
        raise ScenarioError(f"{field}.type", f"{goal.type} goals need a robot in space; this robot is planar")
    if goal.parent_link is not None:
        _check_link(goal.parent_link, f"{field}.parent_link", links)
    if robot.planar and goal.axes is not None and "z" in goal.axes:
        raise ScenarioError(f"{field}.axes", f"planar robot has no z axis, got {goal.axes!r}")
    if goal.type == "position" and goal.axes is None:
        fields.check_length(position, f"{field}.position", (2 if robot.planar else 3,))
    return dataclasses.replace(goal, link=link)


def _check_link(link: str, field: str, links: tuple[str, ...]) -> None:
    """Raise unless ``link`` is one of the robot's links."""
    if link not in links:
        raise ScenarioError(field, f"unknown link {link!r} (robot links: {', '.join(links)})")
