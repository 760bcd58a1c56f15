"""Run a scenario in the embedded simulator and measure it (DESIGN.md sections 5 and 6)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from dynfab.scenario.controllers import Controller, make_controller
from dynfab.scenario.references import goal_axes, scenario_references
from dynfab.scenario.metrics import Metrics, clearance_over_time, compute_metrics
from dynfab.robots import load_robot, robot_from_urdf
from dynfab.geometry.sphere_fitting import SphereFitParameters
from dynfab.robots.builtin import UnknownRobotError
from dynfab.robots.collision_model import auto_collision_model
from dynfab.robots.link_meshes import LinkMeshError
from dynfab.robots.robot import CollisionSphere, Robot
from dynfab.scenario.schema import Scenario, ScenarioError, UrdfRobotSpec, validate_for_robot
from dynfab.sim import DifferentialDrive, DoubleIntegrator, Record, simulate

#: integration sub-steps per control period for a differential-drive base (arcs)
BASE_SUBSTEPS = 10


@dataclass(frozen=True)
class RunResult:
    """A finished run.

    Attributes:
        scenario: the scenario as validated for the robot.
        robot: the robot.
        record: states and commands over time.
        metrics: the run's metrics.
        goal_positions: the primary goal's task coordinates over time (T, d).
        goal_reference: the primary goal's reference over time (T, d).
        obstacle_centers: obstacle centres over time (T, m, 3).
        clearance: minimum clearance at each sample (T,) [m] (inf without obstacles).
        controller: the controller that ran (its planner, fallback count, ...).
    """

    scenario: Scenario
    robot: Robot
    record: Record
    metrics: Metrics
    goal_positions: np.ndarray
    goal_reference: np.ndarray
    obstacle_centers: np.ndarray
    clearance: np.ndarray
    controller: Controller


def robot_for(scenario: Scenario) -> Robot:
    """The robot a scenario names (built-in or its own URDF)."""
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
        return load_robot(spec)
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


def run_scenario(scenario: Scenario, progress: Callable[[int, int], None] | None = None) -> RunResult:
    """Build the robot and controller, simulate ``scenario.duration`` and compute metrics.

    Raises:
        ScenarioError: if the scenario does not fit the robot or the planner.
    """
    robot = robot_for(scenario)
    scenario = validate_for_robot(scenario, robot)
    references = scenario_references(scenario, robot)
    controller = make_controller(scenario, robot, references)
    state = scenario.initial_state
    model = DoubleIntegrator() if robot.base is None else DifferentialDrive()
    substeps = 1 if robot.base is None else BASE_SUBSTEPS
    record = simulate(controller, state.q, state.qdot, scenario.dt, scenario.duration, substeps=substeps,
                      model=model, progress=progress)
    samples = record.q.shape[0]
    goal = scenario.goals[0]
    goal_positions = _goal_coordinates(robot, scenario, record.q)
    goal_reference = references.goals[0].sample(record.t)[0]
    centres, radii = _sphere_centres(robot, record.q)
    obstacle_centers = np.zeros((samples, len(scenario.obstacles), 3))
    for k, trajectory in enumerate(references.obstacles):
        positions = trajectory.sample(record.t)[0]
        obstacle_centers[:, k, : positions.shape[1]] = positions
    obstacle_radii = np.array([o.radius for o in scenario.obstacles])
    metrics = compute_metrics(record, goal_positions, goal_reference, goal.tolerance,
                              centres, radii, obstacle_centers, obstacle_radii, planar=robot.planar,
                              path_goal=goal.type == "path")
    solve_times = getattr(controller, "solve_times", None)
    if solve_times:  # a planner that re-plans less often than it is called (MPC)
        metrics = dataclasses.replace(metrics, solver_time_ms=1e3 * float(np.mean(solve_times)))
    clearance = clearance_over_time(centres, radii, obstacle_centers, obstacle_radii, planar=robot.planar)
    return RunResult(scenario, robot, record, metrics, goal_positions, goal_reference, obstacle_centers, clearance,
                     controller)


def _goal_coordinates(robot: Robot, scenario: Scenario, qs: np.ndarray) -> np.ndarray:
    """The primary goal's coordinates (link position on its axes, or joints) per sample."""
    goal = scenario.goals[0]
    if goal.type == "joint":
        return qs.copy()
    q = ca.SX.sym("q", robot.kinematics.dof)
    position = robot.kinematics.position(q, goal.link, parent=goal.parent_link)
    return _evaluate_over(q, position[goal_axes(goal, robot)], qs)


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
