"""Run a scenario in the embedded simulator and measure it (docs/design.md sections 5 and 6)."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from dynfab.geometry.orientation import direction_angle, rotation_angle
from dynfab.motion.references import References
from dynfab.robots.mesh_sweep import MeshSweep, sweep_meshes
from dynfab.scenario.camera_controller import make_camera_controller
from dynfab.scenario.controllers import Controller
from dynfab.scenario.guided_controller import make_scenario_controller
from dynfab.scenario.outcome import with_outcome
from dynfab.scenario.path_end import path_end_refusal
from dynfab.scenario.exact_metrics import mesh_model_for, obstacle_shapes, with_mesh_metrics
from dynfab.scenario.references import goal_axes, scenario_references
from dynfab.scenario.metrics import (Metrics, clearance_over_time, compute_metrics, shape_clearance_over_time,
                                     with_contacts)
from dynfab.scenario.start_state import check_start_collisions
from dynfab.robots import load_robot, robot_from_urdf
from dynfab.geometry.sphere_fitting import SphereFitParameters
from dynfab.robots.builtin import UnknownRobotError
from dynfab.robots.collision_model import auto_collision_model
from dynfab.robots.limits import LimitsError
from dynfab.robots.link_meshes import LinkMeshError
from dynfab.robots.robot import CollisionSphere, Robot
from dynfab.scenario.schema import Scenario, ScenarioError, UrdfRobotSpec, load_scenario, validate_for_robot
from dynfab.sim import Record, motion_model_for, simulate

if TYPE_CHECKING:
    from dynfab.robots.mesh_collision import MeshCollisionModel
    from dynfab.sim.mujoco_sim import Contact, StepObserver

#: integration sub-steps per control period for a differential-drive base (arcs)
BASE_SUBSTEPS = 10
_ORIENTED = ("pose", "axis")


@dataclass(frozen=True)
class RunResult:
    """A finished run.

    Attributes:
        scenario: the scenario as validated for the robot.
        robot: the robot.
        record: states and commands over time.
        metrics: the run's metrics.
        goal_positions: the primary goal's task coordinates over time (T, d): the goal
            point on its axes (the link origin for an axis goal), or the joints.
        goal_reference: the primary goal's reference over time (T, d) (an axis goal has
            no position target: its ``goal_positions``).
        obstacle_centers: obstacle centres over time (T, m, 3) (a plane: its point).
        clearance: minimum clearance at each sample (T,) [m] (inf without obstacles).
        controller: the controller that ran (its planner, fallback count, ...); None for
            a replayed recording.
        mesh_sweep: the collision-mesh distances of the run (contacts, minima); None for
            robots measured by spheres (see scenario/exact_metrics.py).
        contacts: under MuJoCo, every contact that began (robot with an obstacle or with
            itself); empty for the kinematic simulator.
        stop_reason: why the run ended early (the state diverged, the
            planner returned a non-finite command), in one line; None otherwise.
    """

    scenario: Scenario
    robot: Robot
    record: Record
    metrics: Metrics
    goal_positions: np.ndarray
    goal_reference: np.ndarray
    obstacle_centers: np.ndarray
    clearance: np.ndarray
    controller: Controller | None
    mesh_sweep: MeshSweep | None = None
    contacts: tuple[Contact, ...] = ()
    stop_reason: str | None = None


def robot_for(scenario: Scenario) -> Robot:
    """The robot a scenario names (built-in or its own URDF), with the scenario's limits."""
    robot = _described_robot(scenario)
    overrides = scenario.limits
    try:
        limits = robot.limits.overridden(overrides.velocity, overrides.acceleration, overrides.jerk)
    except LimitsError as error:
        field, _, problem = str(error).partition(": ")
        raise ScenarioError(field, problem) from None
    return dataclasses.replace(robot, limits=limits)


def _described_robot(scenario: Scenario) -> Robot:
    """The robot as its description gives it."""
    spec = scenario.robot
    if isinstance(spec, UrdfRobotSpec):
        try:
            spheres, pairs = _collision_model(spec)
            return robot_from_urdf(
                spec.urdf, spec.goal_link, spheres,
                self_collision_pairs=pairs, planar=spec.planar,
                joints=spec.joints, locked=dict(spec.locked), package_dirs=spec.package_dirs)
        except LinkMeshError as error:
            raise ScenarioError("robot.collision_spheres", str(error).splitlines()[0]) from error
        except (OSError, ValueError) as error:
            message = str(error).splitlines()[0]
            key, _, rest = message.partition(": ")
            if key in ("joints", "locked"):  # Kinematics names the key it refuses
                raise ScenarioError(f"robot.{key}", rest) from error
            raise ScenarioError("robot.urdf", message) from error
    try:
        return load_robot(spec) if isinstance(spec, str) else load_robot(spec.name, fingers=spec.fingers)
    except UnknownRobotError as error:
        raise ScenarioError("robot", str(error)) from error


def _collision_model(spec: UrdfRobotSpec) -> tuple[tuple[CollisionSphere, ...], tuple[tuple[int, int], ...]]:
    """The spheres and pairs a URDF robot spec names, fitting / selecting (cached) for ``auto``."""
    explicit = None if spec.collision_spheres == "auto" else tuple(
        CollisionSphere(s.link, s.center, s.radius) for s in spec.collision_spheres)
    if explicit is not None and spec.self_collision_pairs != "auto":
        return explicit, spec.self_collision_pairs  # type: ignore[return-value]
    model = auto_collision_model(spec.urdf, joints=spec.joints, locked=dict(spec.locked),
                                 package_dirs=spec.package_dirs,
                                 parameters=SphereFitParameters(tolerance=spec.sphere_tolerance),
                                 spheres=explicit)
    pairs = model.self_collision_pairs if spec.self_collision_pairs == "auto" else spec.self_collision_pairs
    return model.spheres, pairs  # type: ignore[return-value]


def run_scenario(scenario: Scenario, progress: Callable[[int, int], None] | None = None,
                 observer: StepObserver | None = None) -> RunResult:
    """Build the robot and controller, check the start state, simulate
    ``scenario.duration`` (kinematic, or MuJoCo: scenario/mujoco_runner.py) and compute
    metrics; MuJoCo's contacts count as collisions (metric ``contacts``: how many began).

    ``observer`` (MuJoCo only) is called with ``(t, data)`` after each control period.

    Raises:
        ScenarioError: if the scenario does not fit the robot or the planner, or the start
            state is outside the joint limits or in collision (scenario/start_state.py).
    """
    robot = robot_for(scenario)
    scenario = validate_for_robot(scenario, robot)
    state = scenario.initial_state
    references = scenario_references(scenario, robot)
    mesh_model = mesh_model_for(robot)
    start_centres = obstacle_centres(references, np.zeros(1))
    check_start_collisions(state.q, robot, mesh_model, obstacle_shapes(scenario.obstacles, start_centres))
    if scenario.perception == "camera":
        controller = make_camera_controller(scenario, robot)
    else:
        controller = make_scenario_controller(scenario, robot, references)
    contacts: tuple[Contact, ...] = ()
    stop_reason = None
    if scenario.simulation.simulator == "mujoco":
        from dynfab.scenario.mujoco_runner import run_mujoco

        physics = run_mujoco(scenario, robot, controller, lambda times: obstacle_centres(references, times),
                             mesh_model, progress, observer)
        record, contacts, stop_reason = physics.record, physics.contacts, physics.stop_reason
    else:
        model = motion_model_for(robot.base is not None)
        substeps = 1 if robot.base is None else BASE_SUBSTEPS
        record = simulate(controller, state.q, state.qdot, scenario.dt, scenario.duration, substeps=substeps,
                          model=model, progress=progress)
        stop_reason = record.stop_reason
    return measure_run(scenario, robot, references, record, controller, mesh_model, contacts, stop_reason)


def run(scenario: Scenario | str | os.PathLike[str],
        progress: Callable[[int, int], None] | None = None) -> RunResult:
    """Run a scenario (a :class:`Scenario`, or the path of a scenario file: loaded with
    :func:`~dynfab.scenario.schema.load_scenario`) as ``dynfab run`` does, and measure it.

    Raises:
        ScenarioError: the file or the scenario is invalid (the message names the field).
        OSError: the file cannot be read.
    """
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    return run_scenario(scenario, progress)


def measure_run(scenario: Scenario, robot: Robot, references: References, record: Record,
                controller: Controller | None, mesh_model: MeshCollisionModel | None,
                contacts: tuple[Contact, ...] = (), stop_reason: str | None = None) -> RunResult:
    """The result of a run of ``scenario`` (validated for ``robot``) that produced
    ``record``: goal and obstacle tracks, clearance and metrics (``controller`` None for a
    replayed recording: no solver times)."""
    goal = scenario.goals[0]
    goal_positions = _goal_coordinates(robot, scenario, record.q)
    goal_reference = goal_positions if goal.type == "axis" else references.goals[0].sample(record.t)[0]
    orientation_errors = _orientation_errors(robot, scenario, references, record.q, record.t)
    centres, radii = _sphere_centres(robot, record.q)
    obstacle_centers = obstacle_centres(references, record.t)
    spheres = [k for k, o in enumerate(scenario.obstacles) if o.type == "sphere"]
    shapes = [k for k, o in enumerate(scenario.obstacles) if o.type != "sphere"]
    sphere_centres = obstacle_centers[:, spheres]
    sphere_radii = np.array([scenario.obstacles[k].radius for k in spheres])
    shape_clearance = shape_clearance_over_time(
        centres, radii, [scenario.obstacles[k].shape for k in shapes],
        [scenario.obstacles[k].orientation for k in shapes], obstacle_centers[:, shapes], planar=robot.planar)
    metrics = compute_metrics(record, goal_positions, goal_reference, goal.tolerance,
                              centres, radii, sphere_centres, sphere_radii, planar=robot.planar,
                              path_goal=goal.type == "path", shape_clearance=shape_clearance,
                              end_required=goal.type == "path" and path_end_refusal(goal, scenario.duration) is None,
                              orientation_errors=orientation_errors,
                              angle_tolerance=goal.angle_tolerance if goal.type in _ORIENTED else None)
    metrics = dataclasses.replace(metrics, max_velocity_ratio=robot.limits.velocity_ratio(record.qdot),
                                  max_acceleration_ratio=robot.limits.acceleration_ratio(record.qddot))
    solve_times = None if controller is None else getattr(controller, "solve_times", None)
    if solve_times:  # a planner that re-plans less often than it is called (MPC)
        metrics = dataclasses.replace(metrics, solver_time_ms=1e3 * float(np.mean(solve_times)))
    mesh_sweep = None
    if mesh_model is not None:
        shapes = obstacle_shapes(scenario.obstacles, obstacle_centers, lowered=True)  # a cloud less its δ
        mesh_sweep = sweep_meshes(mesh_model, record.q, shapes)
        metrics = with_mesh_metrics(metrics, mesh_sweep)
    if scenario.simulation.simulator == "mujoco":
        metrics = with_contacts(metrics, contacts)
    metrics = with_outcome(metrics, controller, goal_positions, goal_reference)
    clearance = np.minimum(clearance_over_time(centres, radii, sphere_centres, sphere_radii, planar=robot.planar),
                           shape_clearance)
    return RunResult(scenario, robot, record, metrics, goal_positions, goal_reference, obstacle_centers, clearance,
                     controller, mesh_sweep, contacts, stop_reason)


def obstacle_centres(references: References, times: np.ndarray) -> np.ndarray:
    """Obstacle centres at ``times``, shape (T, m, 3) [m] (planar ones get z = 0)."""
    centres = np.zeros((len(times), len(references.obstacles), 3))
    for k, trajectory in enumerate(references.obstacles):
        positions = trajectory.sample(times)[0]
        centres[:, k, : positions.shape[1]] = positions
    return centres


def _goal_coordinates(robot: Robot, scenario: Scenario, qs: np.ndarray) -> np.ndarray:
    """The primary goal's coordinates (link position on its axes, or joints) per sample."""
    goal = scenario.goals[0]
    if goal.type == "joint":
        return qs.copy()
    q = ca.SX.sym("q", robot.kinematics.dof)
    position = robot.kinematics.position(q, goal.link, parent=goal.parent_link, offset=goal.offset)
    return _evaluate_over(q, position[goal_axes(goal, robot)], qs)


def _orientation_errors(robot: Robot, scenario: Scenario, references: References, qs: np.ndarray,
                        times: np.ndarray) -> np.ndarray | None:
    """Orientation error over time [rad] of the primary pose or axis goal, else of the
    first one; None without such goals."""
    index = next((i for i, goal in enumerate(scenario.goals) if goal.type in _ORIENTED), None)
    if index is None:
        return None
    goal = scenario.goals[index]
    q = ca.SX.sym("q", robot.kinematics.dof)
    rows = _evaluate_over(q, ca.reshape(robot.kinematics.rotation(q, goal.link).T, 9, 1), qs)
    rotations = rows.reshape(-1, 3, 3)
    targets = references.orientation(index).sample(times)[0]
    if goal.type == "axis":
        return direction_angle(rotations @ np.asarray(goal.axis), targets)
    return rotation_angle(rotations, np.swapaxes(targets.reshape(-1, 3, 3), 1, 2))


def link_path(robot: Robot, link: str, qs: np.ndarray) -> np.ndarray:
    """Positions (T, 3) [m] of ``link``'s origin at the configurations ``qs`` (T, n)."""
    q = ca.SX.sym("q", robot.kinematics.dof)
    return _evaluate_over(q, robot.kinematics.position(q, link), qs)


def _sphere_centres(robot: Robot, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = ca.SX.sym("q", robot.kinematics.dof)
    k = len(robot.collision_spheres)
    if k == 0:
        return np.zeros((qs.shape[0], 0, 3)), np.zeros(0)
    flat = _evaluate_over(q, ca.reshape(robot.sphere_centers(q).T, 3 * k, 1), qs)
    return flat.reshape(qs.shape[0], k, 3), robot.sphere_radii


def _evaluate_over(q: ca.SX, expression: ca.SX, qs: np.ndarray) -> np.ndarray:
    """Evaluate ``expression(q)`` at every row of ``qs`` in one mapped call."""
    function = ca.Function("f", [q], [expression]).map(qs.shape[0])
    return np.array(function(qs.T)).T
