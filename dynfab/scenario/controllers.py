"""Turn a scenario into a controller ``(t, q, q̇) ↦ q̈`` for the simulator.

A controller owns its planner and, each tick, writes the scenario's current goal and
obstacle references into the planner's runtime parameters before calling it.

- ``static-fabric``: a moving goal or obstacle is seen as a position updated every tick
  (the paper's static-fabric baseline: no velocity, no acceleration).
- ``dynamic-fabric``: goals and obstacles also pass their velocity and acceleration, which
  the dynamic pullback uses (paper section IV).

The scenario's ``fabric:`` block (:mod:`dynfab.scenario.fabric_schema`) sets leaf and
root parameters of the fabric planners; the MPC ignores it.

Scenario goals become planner goals one to one, except a ``pose`` goal, which becomes two:
the position of its point (first) and the orientation of its link, with the same weight.

Sphere obstacles take the planner's sphere slots in file order; boxes, cylinders, capsules
and planes take the slots of their kind (:class:`dynfab.fabric.parameters.ShapeSlots`),
whose orientation and sizes are written once. Mesh obstacles take no slot: the planner gets
a nearest-point leaf (:mod:`dynfab.fabric.leaves.surface_points`, range and gains of the
shape obstacles'), written every tick (:mod:`dynfab.scenario.mesh_obstacles`); point clouds
(``points``) feed the same leaf.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from dynfab.fabric.leaves.orientation import FRAME_AXES, OrientationGoalConfig
from dynfab.fabric.leaves.shape_obstacle import ShapeObstacleAvoidance
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance
from dynfab.fabric.parameters import AbsentParameter, RuntimeParameters, ShapeSlots
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.motion.references import References
from dynfab.motion.trajectories import StaticPoint, Trajectory, TrajectoryPoint
from dynfab.mpc import GoalTerm, MpcConfig, MpcController, MpcProblem
from dynfab.robots.robot import Robot
from dynfab.sim.simulator import RunStopped
from dynfab.perception.surfaces import SurfaceFeed
from dynfab.scenario.mesh_obstacles import MeshObstacles, surface_leaf
from dynfab.scenario.references import goal_axes
from dynfab.scenario.schema import GoalSpec, ObstacleSpec, Scenario, ScenarioError

_FABRIC_PLANNERS = {"static-fabric": False, "dynamic-fabric": True}


class Controller(Protocol):
    """What the simulator calls once per control period."""

    def __call__(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class ObstacleSlot:
    """Where one obstacle's centre goes in the planner's parameters: row ``row`` of the
    (slots, 3) views of its kind (velocity and acceleration absent in a static planner)."""

    position: np.ndarray
    velocity: np.ndarray | AbsentParameter
    acceleration: np.ndarray | AbsentParameter
    row: int


class FabricController:
    """A fabric planner fed with the references of a scenario.

    Attributes:
        planner: the compiled planner.
        references: the obstacle trajectories and the goal trajectories, one per planner
            goal (see :func:`planner_references`).
    """

    def __init__(self, planner: FabricPlanner, references: References,
                 moving_goals: tuple[int, ...], moving_obstacles: tuple[int, ...],
                 obstacle_slots: tuple[ObstacleSlot | None, ...] | None = None,
                 meshes: MeshObstacles | None = None) -> None:
        """``obstacle_slots[k]`` is where obstacle ``k``'s centre is written (None: a mesh,
        which ``meshes`` writes each tick); ``None``: the sphere slot ``k``."""
        self.planner = planner
        self.references = references
        self._meshes = meshes
        self._moving_goals = moving_goals
        self._moving_obstacles = moving_obstacles
        params = planner.parameters
        self._slots = obstacle_slots if obstacle_slots is not None else tuple(
            ObstacleSlot(params.obstacle_position, params.obstacle_velocity, params.obstacle_acceleration, k)
            for k in range(len(references.obstacles)))
        self._write_all(0.0)

    def __call__(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        self._write(t, self._moving_goals, self._moving_obstacles)
        if self._meshes is not None:
            self._meshes.write(t, q, self.references, qdot)
        return self.planner.compute(q, qdot)

    def retarget(self, references: References, t: float) -> None:
        """Follow ``references`` from now on (a goal or obstacle moved by hand in the viewer):
        every goal and obstacle is written at time ``t`` [s] at once, and those that are not
        at rest again every tick."""
        self.references = references
        self._moving_goals = tuple(i for i, goal in enumerate(references.goals) if not isinstance(goal, StaticPoint))
        self._moving_obstacles = tuple(k for k, obstacle in enumerate(references.obstacles)
                                       if not isinstance(obstacle, StaticPoint))
        self._write_all(t)

    def _write_all(self, t: float) -> None:
        self._write(t, tuple(range(len(self.references.goals))), tuple(range(len(self.references.obstacles))))

    def _write(self, t: float, goals: tuple[int, ...], obstacles: tuple[int, ...]) -> None:
        params = self.planner.parameters
        dynamic = self.planner.config.dynamic
        for i in goals:
            point = _finite_point(self.references.goals[i], t, f"the reference of planner goal {i}")
            params.goal_position[i][:] = point.position
            if dynamic:
                params.goal_velocity[i][:] = point.velocity
                params.goal_acceleration[i][:] = point.acceleration
        for k in obstacles:
            point = _finite_point(self.references.obstacles[k], t, f"the trajectory of obstacles[{k}]")
            slot = self._slots[k]
            if slot is None:
                continue
            d = len(point.position)  # planar scenarios may give x, y only
            slot.position[slot.row, :d] = point.position
            if dynamic:
                slot.velocity[slot.row, :d] = point.velocity
                slot.acceleration[slot.row, :d] = point.acceleration


def _finite_point(trajectory: Trajectory, t: float, what: str) -> TrajectoryPoint:
    """The reference at ``t``; ends the run (:class:`RunStopped`) if it is not finite."""
    with np.errstate(all="ignore"):
        point = trajectory.evaluate(t)
    if not all(np.isfinite(v).all() for v in (point.position, point.velocity, point.acceleration)):
        raise RunStopped(f"{what} turned non-finite at t = {t:.3f} s")
    return point


def make_controller(scenario: Scenario, robot: Robot, references: References) -> Controller:
    """The controller of ``scenario.planner`` for ``robot``, planning within the velocity
    limits less the scenario's ``limits.headroom`` (scenario/limits_schema.py).

    Raises:
        ScenarioError: if the scenario asks for something this planner cannot do.
    """
    robot = replace(robot, limits=scenario.planning_limits(robot.limits))
    if scenario.planner == "mpc":
        return make_mpc_controller(scenario, robot, references)
    if scenario.planner not in _FABRIC_PLANNERS:
        raise ScenarioError("planner", f"{scenario.planner!r} is not available yet; use static-fabric, dynamic-fabric "
                            "or mpc")
    spheres = sum(obstacle.type == "sphere" for obstacle in scenario.obstacles)
    goals = tuple(config for goal in scenario.goals for config in _goal_configs(goal))
    config = replace(PlannerConfig.for_robot(robot, goals, spheres, _FABRIC_PLANNERS[scenario.planner],
                                             shape_slots_of(scenario.obstacles)),
                     control_period=scenario.dt, backend=scenario.backend)
    config = with_surface_leaf(scenario.fabric.configured(config), robot, scenario.obstacles,
                               scenario.perception == "camera")
    planner = FabricPlanner(robot, config)
    slots = place_obstacles(scenario.obstacles, planner.parameters)
    references = planner_references(scenario, references)
    moving_goals = tuple(i for i, goal in enumerate(references.goals) if not isinstance(goal, StaticPoint))
    moving_obstacles = tuple(k for k, obstacle in enumerate(scenario.obstacles) if obstacle.trajectory is not None)
    return FabricController(planner, references, moving_goals, moving_obstacles, slots,
                            mesh_obstacles(planner, robot, scenario.obstacles))


def with_surface_leaf(config: PlannerConfig, robot: Robot, obstacles: tuple[ObstacleSpec, ...],
                      perceived: bool = False) -> PlannerConfig:
    """``config`` with the nearest-point leaf of the mesh obstacles or of a camera's cloud
    (if any), whose barrier is the shape obstacles' (the default one if shapes are off)."""
    barrier = (config.shape_avoidance or ShapeObstacleAvoidance()).barrier
    leaf = surface_leaf(robot, obstacles, barrier, perceived)
    return config if leaf is None else replace(config, leaves=config.leaves + (leaf,))


def mesh_obstacles(planner: FabricPlanner, robot: Robot, obstacles: tuple[ObstacleSpec, ...]) -> MeshObstacles | None:
    """What writes the planner's nearest-point leaf each tick from the scenario's meshes and
    clouds; None without them (a camera's leaf is written by its feed)."""
    leaf = next((leaf for leaf in planner.config.leaves if isinstance(leaf, NearestSurfaceAvoidance)), None)
    indices = tuple(k for k, obstacle in enumerate(obstacles) if obstacle.type == "mesh")
    cloud_indices = tuple(k for k, obstacle in enumerate(obstacles) if obstacle.cloud is not None)
    clouds = tuple(obstacles[k].cloud for k in cloud_indices)
    if leaf is None or not (indices or clouds):
        return None
    feed = SurfaceFeed(robot, leaf, planner.parameters.leaves[leaf.name])
    return MeshObstacles(indices, tuple(obstacles[k] for k in indices), feed, planner.config.dynamic, clouds,
                         cloud_indices)  # type: ignore[arg-type]


def shape_slots_of(obstacles: tuple[ObstacleSpec, ...]) -> ShapeSlots:
    """One planner slot per box, cylinder, capsule and plane of ``obstacles``."""
    kinds = [obstacle.type for obstacle in obstacles]
    return ShapeSlots(box=kinds.count("box"), cylinder=kinds.count("cylinder"), capsule=kinds.count("capsule"),
                      plane=kinds.count("plane"))


def place_obstacles(obstacles: tuple[ObstacleSpec, ...],
                    params: RuntimeParameters) -> tuple[ObstacleSlot | None, ...]:
    """Give each obstacle the next slot of its kind and write its radius, or its
    orientation and sizes; returns where each one's centre goes (None: a mesh or a point
    cloud, no slot)."""
    used = dict.fromkeys(("sphere", "box", "cylinder", "capsule", "plane"), 0)
    slots: list[ObstacleSlot | None] = []
    for obstacle in obstacles:
        if obstacle.type in ("mesh", "points"):
            slots.append(None)
            continue
        row = used[obstacle.type]
        used[obstacle.type] += 1
        if obstacle.type == "sphere":
            params.obstacle_radius[row] = obstacle.radius
            slots.append(ObstacleSlot(params.obstacle_position, params.obstacle_velocity,
                                      params.obstacle_acceleration, row))
            continue
        views = params.shape_views(obstacle.type)
        views.orientation[row] = obstacle.orientation
        views.dimensions[row] = obstacle.shape.dimensions
        slots.append(ObstacleSlot(views.position, views.velocity, views.acceleration, row))
    return tuple(slots)


def planner_references(scenario: Scenario, references: References) -> References:
    """The references in planner-goal order: a pose goal's position, then its orientation."""
    goals: list[Trajectory] = []
    for i, goal in enumerate(scenario.goals):
        goals.append(references.goals[i])
        if goal.type == "pose":
            goals.append(references.orientation(i))
    return References(tuple(goals), references.obstacles)


def _goal_configs(goal: GoalSpec) -> tuple[GoalConfig | OrientationGoalConfig, ...]:
    if goal.type == "joint":
        return (GoalConfig(link=None, weight=goal.weight),)
    if goal.type == "axis":
        return (OrientationGoalConfig(link=goal.link, link_axes=(goal.axis,), weight=goal.weight),)
    position = GoalConfig(link=goal.link, offset=goal.offset, axes=goal.axes, parent_link=goal.parent_link,
                          weight=goal.weight)
    if goal.type == "pose":
        return (position, OrientationGoalConfig(link=goal.link, link_axes=FRAME_AXES, weight=goal.weight))
    return (position,)


def make_mpc_controller(scenario: Scenario, robot: Robot, references: References,
                        config: MpcConfig | None = None) -> MpcController:
    """The MPC baseline for a scenario validated for ``robot``.

    Args:
        scenario: the scenario (goals, obstacle radii).
        robot: any robot: holonomic (double-integrator model) or on a differential-drive
            base (unicycle model, :mod:`dynfab.mpc.model`).
        references: the scenario's goal and obstacle trajectories.
        config: horizon, weights and solver; the benchmark's defaults if ``None``.
    """
    for k, obstacle in enumerate(scenario.obstacles):
        if obstacle.type != "sphere":
            raise ScenarioError(f"{obstacle.name(k)}.type", f"the mpc planner avoids spheres only, got {obstacle.type!r}; "
                                "use static-fabric or dynamic-fabric")
    goals = tuple(term for goal in scenario.goals for term in _goal_terms(goal, robot))
    problem = MpcProblem(robot, goals, len(scenario.obstacles), config or MpcConfig())
    return MpcController(problem, planner_references(scenario, references),
                         np.array([o.radius for o in scenario.obstacles]), control_period=scenario.dt)


def _goal_terms(goal: GoalSpec, robot: Robot) -> tuple[GoalTerm, ...]:
    """The MPC's goal terms of a scenario goal, in the order of :func:`planner_references`."""
    if goal.type == "joint":
        return (GoalTerm(link=None, weight=goal.weight),)
    link = goal.link or robot.goal_link
    if goal.type == "axis":
        return (GoalTerm(link=link, weight=goal.weight, link_axes=(goal.axis,)),)
    position = GoalTerm(link=link, axes=tuple(goal_axes(goal, robot)), parent_link=goal.parent_link,
                        weight=goal.weight, offset=goal.offset)
    if goal.type == "pose":
        return (position, GoalTerm(link=link, weight=goal.weight, link_axes=FRAME_AXES))
    return (position,)
