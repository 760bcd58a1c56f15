"""A fabric controller that recovers from stalls (see :mod:`dynfab.scenario.stall_recovery`).

``with_recovery(controller, scenario, robot, references)`` wraps a
:class:`~dynfab.scenario.controllers.FabricController` whose primary goal is a static
position goal; other controllers are returned unchanged.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

from dynfab.fabric.planner import FabricPlanner
from dynfab.motion.references import References
from dynfab.motion.trajectories import StaticPoint
from dynfab.robots.joint_bounds import finite_joint_bounds
from dynfab.robots.robot import Robot
from dynfab.robots.self_collision import bodies
from dynfab.scenario.controllers import FabricController
from dynfab.scenario.references import goal_axes
from dynfab.scenario.schema import Scenario
from dynfab.scenario.stall_recovery import (GlobalPlanningError, PathFollower, PathPlanner, StallMonitor,
                                            StallRecovery, rrt_path_planner)


class RecoveringController:
    """A fabric controller whose static position goal is replaced by a carrot on a global
    path while the run is stalled.

    Attributes:
        inner: the wrapped controller (it writes the references and calls the planner).
        recovery_times: when a global path was planned and followed [s] (attempts that
            found no path are not in it: the fabric went on alone).
    """

    def __init__(self, inner: FabricController, goal: np.ndarray, tolerance: float,
                 goal_point: Callable[[np.ndarray], np.ndarray],
                 spheres: Callable[[float], list[tuple[np.ndarray, float]]], footprint: float,
                 recovery: StallRecovery = StallRecovery(), path_planner: PathPlanner | None = None,
                 reach: float = np.inf) -> None:
        self.inner = inner
        self.recovery_times: list[float] = []
        self._attempts = 0
        self._goal = np.asarray(goal, dtype=float)
        self._tolerance = tolerance
        self._goal_point = goal_point
        self._spheres = spheres
        self._footprint = footprint
        self._recovery = recovery
        self._plan = path_planner or rrt_path_planner()
        self._monitor = StallMonitor(recovery, reach)
        self._follower: PathFollower | None = None
        self._lookahead = max(3 * tolerance, footprint)

    @property
    def planner(self) -> FabricPlanner:
        """The wrapped controller's planner."""
        return self.inner.planner

    def __call__(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        point = self._goal_point(q)
        if self._follower is None:
            distance = float(np.linalg.norm(point - self._goal))
            if distance > self._tolerance and self._monitor.stalled(t, distance):
                self._start_path(t, point)
        else:
            carrot, at_end = self._follower.carrot(point)
            remaining = float(np.linalg.norm(point - self._goal))
            if at_end:
                self._follow(self._goal)
            elif self._monitor.stalled(t, remaining + self._follower.length):
                self._start_path(t, point)
            else:
                self._follow(carrot)
        return self.inner(t, q, qdot)

    def _start_path(self, t: float, point: np.ndarray) -> None:
        """Plan from ``point`` to the goal (with the clearance, then without it)."""
        self._monitor.reset()
        if self._attempts >= self._recovery.attempts:
            return
        spheres = self._spheres(t)
        seed = self._attempts
        self._attempts += 1
        for margin in (self._footprint + self._recovery.clearance, self._footprint):
            try:
                waypoints = self._plan(point, self._goal, spheres, margin, seed)
            except GlobalPlanningError:
                continue
            self.recovery_times.append(t)
            self._follower = PathFollower(waypoints, self._lookahead)
            self._follow(self._follower.carrot(point)[0])
            return
        # no path: the attempt counts against the budget, the fabric goes on alone

    def _follow(self, target: np.ndarray) -> None:
        self.inner.planner.parameters.goal_position[0][:] = target
        if np.array_equal(target, self._goal):
            self._follower = None
            self._monitor.reset()


def with_recovery(controller: FabricController, scenario: Scenario, robot: Robot,
                  references: References) -> FabricController | RecoveringController:
    """``controller`` with stall recovery if the scenario asks for it and its primary goal
    is a static position goal (the planner's goal 0)."""
    goal = scenario.goals[0]
    if not scenario.recovery or goal.type != "position" or not isinstance(references.goals[0], StaticPoint):
        return controller
    axes = goal_axes(goal, robot)
    q = ca.SX.sym("q", robot.dof)
    position = robot.kinematics.position(q, goal.link or robot.goal_link, parent=goal.parent_link,
                                         offset=goal.offset)[axes]
    function = ca.Function("goal_point", [q], [position])
    goal_point = lambda q: np.array(function(q), dtype=float).ravel()  # noqa: E731
    spheres = [k for k, o in enumerate(scenario.obstacles) if o.type == "sphere"]

    def sphere_snapshot(t: float) -> list[tuple[np.ndarray, float]]:
        return [(np.asarray(references.obstacles[k].evaluate(t).position, dtype=float)[axes],
                 scenario.obstacles[k].radius) for k in spheres]

    footprint = _footprint(robot, goal.link or robot.goal_link, np.asarray(scenario.initial_state.q), goal_point,
                           axes)
    reach = np.inf if robot.base is not None or robot.planar else link_reach(robot, goal.link or robot.goal_link)
    return RecoveringController(controller, np.asarray(goal.position, dtype=float), goal.tolerance, goal_point,
                                sphere_snapshot, footprint, reach=reach)


def link_reach(robot: Robot, link: str, samples: int = 500, seed: int = 0) -> float:
    """The farthest ``link`` gets from the root over ``samples`` random configurations within
    the joint limits (unlimited joints: ±π) [m]."""
    kin = robot.kinematics
    low, high = finite_joint_bounds(kin.lower, kin.upper)
    q = ca.SX.sym("q", robot.dof)
    position = ca.Function("link_position", [q], [kin.position(q, link)]).map(samples)
    configurations = np.random.default_rng(seed).uniform(low, high, (samples, robot.dof))
    return float(np.linalg.norm(np.asarray(position(configurations.T)), axis=0).max())


def _footprint(robot: Robot, link: str, q: np.ndarray, goal_point: Callable[[np.ndarray], np.ndarray],
               axes: list[int]) -> float:
    """Reach of the goal link's rigid body around the goal point, on the goal's axes [m]:
    ``max |c_i − x| + r_i`` over the collision spheres on that body (0 without any)."""
    body_of = bodies(robot.kinematics)
    mine = [i for i, s in enumerate(robot.collision_spheres) if body_of[s.link] == body_of[link]]
    if not mine:
        return 0.0
    centres = np.asarray(robot.sphere_centers(q), dtype=float)[:, axes]
    point = goal_point(q)
    return float(max(np.linalg.norm(centres[i] - point) + robot.collision_spheres[i].radius for i in mine))
