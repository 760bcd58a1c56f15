"""Global joint-space guidance: plan a free joint-space path to a goal and time it, the
reference ``q_r(t), q̇_r(t), q̈_r(t)`` a dynamic fabric tracks (paper section IV, its
experiment 2b, applied in joint space).

A goal is a configuration (:class:`JointTarget`) or task targets
(:class:`~dynfab.motion.inverse_kinematics.PointTarget`,
:class:`~dynfab.motion.inverse_kinematics.AxisTarget`), which collision-free inverse
kinematics turns into the configuration nearest the current one (free on the spheres, else,
for goals millimetres from the scene, free on the robot's meshes:
:mod:`dynfab.motion.mesh_goal_check`). The path is planned
with OMPL among the obstacles given (:mod:`dynfab.motion.joint_planning`; where that finds
no plan, again with a point cloud's points around the robot at the goal on a finer grid,
:mod:`dynfab.motion.cloud_focus`), against the
same spheres, shapes and self-collision pairs the fabric avoids, and timed within
``speed`` times the robot's velocity and acceleration limits
(:mod:`dynfab.motion.joint_trajectory`): the rest of the limits is the fabric's, to track
and to avoid what was not in the plan. A plan that fails is retried with the next seed
(``attempts``); :class:`GuidanceError` names why the last one failed.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.focused_cloud import FocusedCloud
from dynfab.geometry.shapes import PointCloud
from dynfab.motion.allowance_tables import AllowanceTables
from dynfab.motion.cloud_focus import FocusCache
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.goal_configuration import GoalSearch
from dynfab.motion.goal_region import room_at_the_goal, roomier_goal
from dynfab.motion.mesh_escape_plan import EscapeScene, escape_plan
from dynfab.motion.mesh_goal_check import MeshGoalCheck, endpoint_tests, robot_mesh_model
from dynfab.motion.joint_planning import (ApproachTest, JointPath, JointPlannerSettings, NoPathError, approach_clear,
                                          plan_joint_path)
from dynfab.motion.joint_trajectory import JointTrajectory, TimingError, time_path
from dynfab.motion.guidance_settings import GuidanceSettings
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.motion.placed_obstacle import any_cloud, any_moving
from dynfab.motion.plan_values import GoalTargets, GuidanceError, JointTarget, Plan
from dynfab.motion.way_speed import WaySpeed
from dynfab.robots.joint_bounds import finite_joint_bounds
from dynfab.robots.robot import Robot

__all__ = ["GoalTargets", "GuidanceError", "GuidanceSettings", "JointGuidance", "JointTarget", "Plan"]

#: an approach shorter than this is none: the robot is at the goal [rad]
SHORTEST_APPROACH = 1e-6
#: failures a plan among point clouds makes again with the clouds focused around its goal
_FOCUS_HELPS = frozenset({"start_in_collision", "goal_in_collision", "no_path"})
_ENDPOINT_FAILURES = frozenset({"start_in_collision", "goal_in_collision"})   # (its next test may find an escape)


class JointGuidance:
    """Plans joint-space references for ``robot`` (module docstring).

    Attributes:
        robot: the robot (fixed base).
        settings: the guidance settings.
        checker: the configuration checker with the obstacles of the last plan, on the
            robot's planning spheres (:attr:`~dynfab.robots.robot.Robot.planning_robot`), or
            among point clouds on its own (:meth:`set_obstacles`).
    """

    def __init__(self, robot: Robot, settings: GuidanceSettings = GuidanceSettings()) -> None:
        if robot.base is not None or robot.planar:
            raise ValueError(f"robot '{robot.name}': joint-space guidance needs a fixed-base robot in space")
        self.robot = robot
        self.settings = settings
        self._planning = ConfigurationChecker(robot.planning_robot)
        self._coarse = self._planning if robot.planning_robot is robot else ConfigurationChecker(robot)
        self.checker = self._planning
        self._tables = AllowanceTables(robot, settings)   # what the fabric's leaves may enter (on its spheres)
        self._ahead = ConfigurationChecker(robot.planning_robot)   # what moves (blocked_ahead)
        self._way_speed = WaySpeed(robot, settings)
        self._mesh_check: MeshGoalCheck | None | bool = False  # made on first use; None: no meshes
        self._focus = FocusCache(robot, settings.cloud_focus)   # the last plan's clouds around its goal
        kin = robot.kinematics
        self._lower, self._upper = finite_joint_bounds(kin.lower, kin.upper)

    @property
    def bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The joint bounds plans keep (n,) each [rad or m]: the robot's limits, ±π where a
        joint has none."""
        return self._lower, self._upper

    def goal_configuration(self, goal: GoalTargets, q: NDArray[np.float64], seed: int = 0) -> NDArray[np.float64]:
        """The configuration to plan to from ``q``
        (:meth:`~dynfab.motion.goal_configuration.GoalSearch.configuration`).

        Raises:
            GuidanceError: ``goal_outside_limits`` or ``no_ik_solution``.
        """
        return self.goal_solution(goal, q, seed)[0]

    def goal_solution(self, goal: GoalTargets, q: NDArray[np.float64],
                      seed: int = 0) -> tuple[NDArray[np.float64], bool]:
        """:meth:`goal_configuration`, and whether it reaches a target moved inside the goal's
        tolerances rather than the goal itself
        (:meth:`~dynfab.motion.goal_configuration.GoalSearch.solution`).

        Raises:
            GuidanceError: ``goal_outside_limits`` or ``no_ik_solution``.
        """
        return GoalSearch(self.robot, self.checker, self._meshes, self.settings, self.bounds).solution(goal, q, seed)

    def clear_of_obstacles(self, q: NDArray[np.float64]) -> bool:
        """Whether ``q`` keeps the planner's margin from the checker's obstacles (a plan from
        a ``q`` that does not leaves along an escape's way out:
        :func:`~dynfab.motion.joint_planning.plan_joint_path`)."""
        return self.checker.free(np.clip(q, self._lower, self._upper), self.settings.path.margin, -np.inf)

    def set_obstacles(self, obstacles: Sequence[PlacedObstacle]) -> None:
        """Check against ``obstacles`` from now on: on the robot's planning spheres, or among
        point clouds on the fabric's own. A cloud is a surface the fabric's nearest-point leaf
        can be pushed through, and a plan that its tighter spheres let pass closer to it
        drove generated-problem table_pick/0092 (points, ``--seed 3``, 81-96) through the
        table top, ``panda_link6`` 5 cm deep, where the fabric's spheres' plan reaches the
        goal."""
        clouds = any_cloud(obstacles)
        self.checker = self._coarse if clouds else self._planning
        self.checker.set_obstacles(obstacles)

    def plan(self, q: NDArray[np.float64], goal: GoalTargets, obstacles: Sequence[PlacedObstacle],
             seed: int = 0, wide: bool = False) -> Plan:
        """A timed free reference from ``q`` (at rest) to ``goal`` among ``obstacles``; if
        ``wide``, the first attempt keeps ``stall_margin`` (a replan after a stall). Among
        point clouds, where the first ``cloud_focus.whole_attempts`` attempts find no path
        (or no escape of a blocked endpoint), every attempt is made again with the clouds
        focused around the goal (:mod:`dynfab.motion.cloud_focus`); without clouds or focus
        (or after another failure) the rest of the attempts on the whole obstacles.

        Raises:
            GuidanceError: if every attempt failed (the last one's reason).
        """
        began = time.perf_counter()
        self.set_obstacles(obstacles)
        start = np.clip(np.asarray(q, dtype=float), self._lower, self._upper)
        target, moved = self.goal_solution(goal, start, seed)
        room = room_at_the_goal(goal, target, self.checker, self._meshes, self.settings, self.bounds, seed)
        if room is not None:
            target, moved = room, True
        try:
            return replace(self._plan_to(start, target, obstacles, seed, wide, began), goal_moved=moved)
        except GuidanceError as failure:
            roomier = (roomier_goal(goal, target, self._meshes(), self.settings, self.bounds, seed)
                       if failure.reason == "goal_in_collision" else None)
            if roomier is None:
                raise
        self.set_obstacles(obstacles)   # the first attempts may have left a cloud's focus
        return replace(self._plan_to(start, roomier, obstacles, seed, wide, began), goal_moved=True)

    def _plan_to(self, start: NDArray[np.float64], target: NDArray[np.float64], obstacles: Sequence[PlacedObstacle],
                 seed: int, wide: bool, began: float) -> Plan:
        """:meth:`plan`'s attempts from ``start`` to the goal configuration ``target``."""
        count = self.settings.attempts
        if any_moving(obstacles):
            count = min(count, self.settings.moving_attempts)
        tries = self._tries(seed, wide, count)
        focus = self.settings.cloud_focus
        first = len(tries)
        if focus is not None and any_cloud(obstacles):
            first = min(first, first - count + focus.whole_attempts)
        try:
            return self._attempts(start, target, tries[:first], began)
        except GuidanceError as failure:
            focused = self._focus.focused(obstacles, target) if failure.reason in _FOCUS_HELPS else None
            if focused is None:
                if first == len(tries) or failure.reason == "timing":
                    raise
                return self._attempts(start, target, tries[first:], began)
        self.checker.set_obstacles(focused)  # the endpoints' tests are then made on the focus's grid
        return self._attempts(start, target, tries, began)

    def _tries(self, seed: int, wide: bool, count: int) -> list[tuple[JointPlannerSettings, int]]:
        """The planner's settings and seed of each of ``count`` attempts: each with the next
        seed and twice the time limit, a ``wide`` one first (:meth:`plan`); ``count`` is
        ``attempts``, among moving obstacles at most ``moving_attempts``."""
        path_settings = self.settings.path
        tries = [(replace(path_settings, time_limit=path_settings.time_limit * 2**attempt), seed + attempt)
                 for attempt in range(count)]
        if wide and self.settings.stall_margin > path_settings.margin:
            tries.insert(0, (replace(path_settings, margin=self.settings.stall_margin,
                                     time_limit=self.settings.stall_margin_time), seed))
        return tries

    def _attempts(self, start: NDArray[np.float64], target: NDArray[np.float64],
                  tries: Sequence[tuple[JointPlannerSettings, int]], began: float, tight: bool = False) -> Plan:
        """The plan from ``start`` to ``target`` among the checker's obstacles: the first of
        ``tries`` (planner settings, seed) that finds one; in an attempt whose endpoint finds
        no escape, the endpoints' next tests (:meth:`_endpoint_tests`). Where no attempt
        found an escape without point clouds (or on a cloud's focus: :meth:`_tight_applies`),
        the same attempts at ``tight_margin`` (``tight``), each path kept only if clear on the
        meshes between its escapes (:meth:`_clear_on_meshes`); then, without clouds, as where
        no attempt found a path, the meshes' plan (:mod:`.mesh_escape_plan`: among primitives
        and meshes, unless ``mesh_escape.among_meshes`` is off)."""
        goal_tests, start_tests = self._endpoint_tests(target, goal=True), self._endpoint_tests(start)
        modes = list(dict.fromkeys([(goal_tests[0], start_tests[0]), (goal_tests[-1], start_tests[-1])]))
        error: GuidanceError | None = None
        checks = 0
        for settings, attempt_seed in tries:
            for approach, leave in modes:
                meshes_alone = any(test is not None and test.instead_of_spheres for test in (approach, leave))
                mode_settings = (replace(settings, escape_samples=self.settings.mesh_escape_samples) if meshes_alone
                                 else settings)
                try:
                    path = plan_joint_path(self.checker, start, target, self._lower, self._upper, mode_settings,
                                           attempt_seed, approach, leave)
                except NoPathError as failure:   # the endpoints' next tests, or the next attempt
                    error = GuidanceError(failure.reason, str(failure))
                    if failure.reason in _ENDPOINT_FAILURES:
                        continue
                    break
                checks += path.checks
                if tight and not self._clear_on_meshes(path):
                    error = GuidanceError("no_path", f"the path planned at margin {settings.margin} m comes closer "
                                                     f"than mesh_margin to the meshes")
                    break
                plan = self._plan_of(path, target, began, checks)
                if tight or path.winding <= self.settings.detour_ratio:
                    return plan
                return self._quickest(plan, start, target, mode_settings, attempt_seed, (approach, leave), began)
        assert error is not None
        if tight or error.reason not in _ENDPOINT_FAILURES | {"no_path"} or not self._tight_applies():
            raise error
        try:
            if error.reason == "no_path":
                raise error
            tightened = [(replace(s, margin=self.settings.tight_margin), k) for s, k in tries]
            return self._attempts(start, target, tightened, began, True)
        except GuidanceError:   # a goal without escape, or no path: one on the meshes (mesh_escape_plan)
            meshes = self._meshes()
            escaped = (None if meshes is None or error.reason == "start_in_collision" else escape_plan(
                EscapeScene(self.checker, meshes, self.settings, self.robot.limits, self._lower, self._upper,
                            self._approach_timed), start, target, [k for _, k in tries], began))
            if escaped is None:
                raise
            return escaped

    def _tight_applies(self) -> bool:
        """Whether a plan with no escape may be tried again at ``tight_margin`` (a robot with
        collision meshes, a margin below the planner's): without point clouds (among
        primitives since session 20: with the meshes' plan after it, it rescued development
        generated seed 14 as posed table_pick/0003 and seed 16 table_under_pick/0003), or on a
        cloud's focus, after it failed at the planner's margin (clouds read ``δ`` below their
        noisy points: points cage/0093's grasp, 12.9 mm from the true bars, had 3 free samples
        of 2000 within 0.8 rad on the focus, 43 among the primitives)."""
        clouds = [o.shape for o in self.checker.obstacles if isinstance(o.shape, PointCloud)]
        surfaces = any(isinstance(s, FocusedCloud) for s in clouds) if clouds else True
        return self.settings.tight_margin < self.settings.path.margin and surfaces and self._meshes() is not None

    def _clear_on_meshes(self, path: JointPath) -> bool:
        """Whether ``path`` between its escapes (the planned start to the planned goal), checked
        every half ``path.resolution``, keeps ``mesh_margin`` on the robot's meshes (its ends'
        own clearance where they are nearer); the escapes' segments were judged already."""
        meshes = self._meshes()
        assert meshes is not None
        inner = path.inner
        floor = min(meshes.margin, meshes.clearance(inner[0])[0], meshes.clearance(inner[-1])[0])
        return meshes.polyline_free(inner, self.settings.path.resolution / 2, floor)

    def _quickest(self, plan: Plan, start: NDArray[np.float64], target: NDArray[np.float64],
                  settings: JointPlannerSettings, seed: int, tests: tuple[ApproachTest | None, ApproachTest | None],
                  began: float) -> Plan:
        """Of ``plan``, whose way is a detour (longer than ``detour_ratio`` times the distance
        between its ends: :attr:`~dynfab.motion.joint_planning.JointPath.winding`), and the
        plans of the next ``detour_tries`` seeds with the same ``settings`` and endpoint
        ``tests`` (goal, start), the quickest (the whole reference's duration)."""
        best, checks = plan, plan.checks
        for k in range(1, self.settings.detour_tries + 1):
            try:
                path = plan_joint_path(self.checker, start, target, self._lower, self._upper, settings, seed + k,
                                       *tests)
                checks += path.checks
                candidate = self._plan_of(path, target, began, checks)
            except (NoPathError, GuidanceError):
                continue
            if candidate.trajectory.duration < best.trajectory.duration:
                best = candidate
        return replace(best, time_s=time.perf_counter() - began, checks=checks)

    def _plan_of(self, path: JointPath, target: NDArray[np.float64], began: float, checks: int) -> Plan:
        try:   # timed (:meth:`_timed`) as a plan to target
            trajectory = self._timed(path)
        except TimingError as failure:
            raise GuidanceError("timing", str(failure)) from None
        departure = float(np.linalg.norm(path.waypoints[1] - path.waypoints[0])) if path.escaped_start else 0.0
        if isinstance(trajectory, PhasedTrajectory):
            length = float(np.linalg.norm(path.waypoints[-1] - path.waypoints[-2]))
            return Plan(trajectory, target, time.perf_counter() - began, checks, length, float(trajectory.starts[-1]),
                        departure=departure)
        return Plan(trajectory, target, time.perf_counter() - began, checks, 0.0, trajectory.duration,
                    departure=departure)

    def approach_from(self, q: NDArray[np.float64], goal: NDArray[np.float64]) -> Plan | None:
        """A plan that is only an approach: the straight segment from ``q`` (the robot, held
        short of its plan's approach) to the blocked ``goal``, timed as an approach, if it
        passes the test a plan's approach to ``goal`` passes: no deeper into the last plan's
        obstacles than ``goal`` on the spheres
        (:func:`~dynfab.motion.joint_planning.approach_clear`) and on the robot's meshes, or on
        the meshes alone (the first of :meth:`_endpoint_tests`); else None. With the spheres' test alone,
        held-out as-posed bookshelf_tall/0046 (problems 41-48) had such a segment 6.9 mm into
        a can beside the grasped one on the meshes, and the robot's finger followed it."""
        began = time.perf_counter()
        start = np.clip(np.asarray(q, dtype=float), self._lower, self._upper)
        length = float(np.linalg.norm(goal - start))
        if length < SHORTEST_APPROACH or not approach_clear(self.checker, start, goal, self.settings.path,
                                                            self._endpoint_tests(goal, goal=True)[0]):
            return None
        trajectory = PhasedTrajectory((self._approach_timed(np.vstack([start, goal])),))
        return Plan(trajectory, np.asarray(goal, dtype=float), time.perf_counter() - began, 0, length, 0.0)

    def approach_allowances(self, plan: Plan, obstacles: Sequence[PlacedObstacle],
                            buffers: Sequence[float]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The allowances along ``plan``'s approach: its configurations (k, n) [rad] and each
        obstacle's at each (k, m) [m] (:meth:`AllowanceTables.approach`)."""
        return self._tables.approach(plan, obstacles, buffers, self._meshes)

    def way_allowances(self, plan: Plan, obstacles: Sequence[PlacedObstacle],
                       buffers: Sequence[float]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The allowances along ``plan``'s way, before its approach: its configurations (k, n)
        [rad] and each obstacle's at each (k, m) [m] (:meth:`AllowanceTables.way`)."""
        return self._tables.way(plan, obstacles, buffers, self._meshes)

    def allowances(self, q: NDArray[np.float64], obstacles: Sequence[PlacedObstacle],
                   buffers: Sequence[float]) -> NDArray[np.float64]:
        """How far [m] the fabric's spheres may enter each obstacle at ``q``, its leaves
        keeping ``buffers`` (:meth:`AllowanceTables.at`)."""
        return self._tables.at(q, obstacles, buffers)

    def obstacle_clearance(self, q: NDArray[np.float64], obstacle: PlacedObstacle) -> float:
        """Clearance [m] of the robot's (the fabric's) spheres at ``q`` from ``obstacle``
        alone (:meth:`AllowanceTables.obstacle_clearance`)."""
        return self._tables.obstacle_clearance(q, obstacle)

    def blocked_ahead(self, plan: Plan, tau: float, obstacles: Sequence[PlacedObstacle]) -> bool:
        """Whether the reference within ``check_horizon`` after its time ``tau`` [s] meets
        ``obstacles`` (things that moved since the plan) closer than touching."""
        if not obstacles:
            return False
        self._ahead.set_obstacles(obstacles)
        times = np.linspace(tau, tau + self.settings.check_horizon, 11)
        positions = plan.trajectory.sample(times)[0]
        return self._ahead.first_blocked(positions, 0.0, -np.inf) >= 0

    def _timed(self, path: JointPath) -> JointTrajectory | PhasedTrajectory:
        """The path timed at ``speed``; an escaped goal's last segment as a second phase at
        ``approach_speed``."""
        limits, settings = self.robot.limits, self.settings
        cruise = (settings.speed * limits.velocity, settings.acceleration * limits.acceleration)
        scale = self.speed_scale if settings.slow_clearance > 0.0 else None
        if not path.escaped_goal:
            return time_path(path.waypoints, *cruise, settings.timing, scale)
        way = time_path(path.waypoints[:-1], *cruise, settings.timing, scale)
        return PhasedTrajectory((way, self._approach_timed(path.waypoints[-2:])))

    def speed_scale(self, qs: NDArray[np.float64]) -> NDArray[np.float64]:
        """The factor of the way's velocity limits at each of ``qs`` (m, n) among the last
        plan's obstacles [-] (:mod:`dynfab.motion.way_speed`)."""
        return self._way_speed.scale(self.checker, qs)

    def _approach_timed(self, segment: NDArray[np.float64]) -> JointTrajectory:
        """A grasp's approach segment (2, n) timed at ``approach_speed`` of the limits."""
        limits, settings = self.robot.limits, self.settings
        return time_path(segment, settings.approach_speed * limits.velocity,
                         settings.approach_speed * limits.acceleration, settings.timing)

    def _endpoint_tests(self, q: NDArray[np.float64], goal: bool = False) -> tuple[ApproachTest | None, ...]:
        """The tests of a blocked endpoint's segment (of a ``goal``'s approach, else of a
        start's way out) in the order tried (:func:`~dynfab.motion.mesh_goal_check.endpoint_tests`)."""
        return endpoint_tests(q, self.checker, self._meshes, self.settings, goal)

    def _meshes(self) -> MeshGoalCheck | None:
        """The mesh check against the checker's obstacles (made once); None without meshes."""
        if self._mesh_check is False:
            model = robot_mesh_model(self.robot)
            self._mesh_check = None if model is None else MeshGoalCheck(model, self.settings.mesh_margin)
        if isinstance(self._mesh_check, MeshGoalCheck):
            self._mesh_check.set_obstacles(self.checker.obstacles)
            return self._mesh_check
        return None
