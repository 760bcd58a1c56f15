"""Global joint-space guidance: plan a free joint-space path to a goal and time it, the
reference ``q_r(t), q̇_r(t), q̈_r(t)`` a dynamic fabric tracks (paper section IV, its
experiment 2b, applied in joint space).

A goal is a configuration (:class:`JointTarget`) or task targets
(:class:`~dynfab.motion.inverse_kinematics.PointTarget`,
:class:`~dynfab.motion.inverse_kinematics.AxisTarget`), which collision-free inverse
kinematics turns into the configuration nearest the current one (free on the spheres, else,
for goals millimetres from the scene, free on the robot's meshes:
:mod:`dynfab.motion.mesh_goal_check`). The path is planned
with OMPL among the obstacles given (:mod:`dynfab.motion.joint_planning`), against the
same spheres, shapes and self-collision pairs the fabric avoids, and timed within
``speed`` times the robot's velocity and acceleration limits
(:mod:`dynfab.motion.joint_trajectory`): the rest of the limits is the fabric's, to track
and to avoid what was not in the plan. A plan that fails is retried with the next seed
(``attempts``); :class:`GuidanceError` names why the last one failed.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from dynfab.fabric.leaves.surface_points import moving_spheres
from dynfab.geometry.shapes import Mesh, PointCloud
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.inverse_kinematics import AxisTarget, IkSettings, PointTarget, solve_ik
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.perception.surfaces import surface_clearance
from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.link_meshes import LinkMeshError
from dynfab.robots.mesh_collision import mesh_collision_model
from dynfab.motion.joint_planning import (JointPath, JointPlannerSettings, NoPathError, approach_clear,
                                          plan_joint_path, polyline_samples)
from dynfab.motion.joint_trajectory import JointTrajectory, TimingError, TimingSettings, time_path
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.robots.robot import Robot

__all__ = ["GuidanceError", "GuidanceSettings", "JointGuidance", "JointTarget", "Plan"]

#: a value within this of a joint limit counts as at the limit [rad or m]
LIMIT_SLACK = 1e-6
#: an approach shorter than this is none: the robot is at the goal [rad]
SHORTEST_APPROACH = 1e-6


@dataclass(frozen=True)
class JointTarget:
    """A goal configuration (n,) [rad or m]."""

    q: tuple[float, ...]


GoalTargets = JointTarget | Sequence[PointTarget | AxisTarget]


@dataclass(frozen=True)
class GuidanceSettings:
    """How guidance plans and how its reference is followed.

    Attributes:
        path: the joint-space planner (OMPL planner, time limit, resolution, margins).
        ik: inverse kinematics of task goals.
        ik_retry: the second inverse kinematics search when ``ik`` finds no solution
            clear of obstacles by the planner's margin: with these settings (more seeds:
            a 6-joint arm has few discrete solutions, most blocked near a grasp) and
            margin 0, the spheres merely clear (a grasp pose closer than the margin; the
            planner then escapes it and approaches it as a blocked joint goal); for a robot
            with collision meshes a solution the spheres refuse is also kept if it is free
            on the meshes by ``mesh_margin`` (:mod:`dynfab.motion.mesh_goal_check`).
        mesh_margin: clearance [m] a goal solution checked on the robot's meshes keeps
            from the exact obstacles.
        timing: how the path is timed.
        speed: fraction of the velocity limits the reference uses [-].
        acceleration: fraction of the acceleration limits the reference uses [-]: the
            fabric tracks it with a lag that grows with it, and a lag as it brakes at a
            grasp's approach overshoots into the object.
        attempts: plans tried per request, each with the next seed and twice the previous
            one's time limit (1, 2, 4 s by default) [-].
        replans: plans at most in one run after the first [-]. 10: with 4 (the value
            before), all 8 failures of training moving-sphere problems 10-16 had used them
            all.
        blocked_interval: least time between a replan for a blocked reference and the
            next check of what moves against the new one [s]: checking at once replanned
            4 times in 0.13 s on training moving-sphere bookshelf_tall/0014 as the sphere
            kept moving onto each new reference (the fabric avoids it meanwhile).
        lag_slow: tracking error ``‖q − q_r‖`` at which the reference clock starts to slow [rad].
        lag_stop: tracking error at which it stops (the reference waits for the robot) [rad].
        check_period: how often the reference ahead is checked against what moves [s].
        check_horizon: how far ahead it is checked [s].
        stall_window: time without progress after which the run has stalled [s].
        stall_rate: least mean rate of the reference's clock over ``stall_window`` while it
            runs [-].
        stall_progress: progress expected within ``stall_window``, as a fraction of the
            goal's initial joint-space distance (at least ``stall_floor``) [-].
        stall_floor: smallest progress expected within ``stall_window`` [rad].
        stall_lag_time: time the robot may stay more than ``lag_slow`` behind the running
            reference (outside an approach) before the run counts as stalled [s]: held by
            the obstacle leaves in a tight passage, the reference's clock still creeps for
            seconds before ``stall_rate`` notices (chosen on training problems 10-16).
        stall_margin: planning margin [m] a replan after a stall on the way tries first (one attempt
            of ``stall_margin_time``), before ``path.margin``: a path that keeps more
            clearance where the stalled one went through a tight passage (chosen on
            training problems 10-16).
        stall_margin_time: time limit of that attempt [s].
        goal_clearance: clearance [m] the fabric's obstacle leaves should still see at a
            goal closer to an obstacle than the planner's margin (a grasp: the spheres,
            which bulge out of the meshes, overlap what the meshes clear); the obstacle
            gets that much allowance near the goal (:meth:`JointGuidance.allowances`).
        approach_speed: fraction of the velocity and acceleration limits the approach
            (that last segment, a phase of its own after a stop) uses [-].
        approach_lag_slow, approach_lag_stop: ``lag_slow`` and ``lag_stop`` during the
            approach: it is followed closely, so that the robot does not cut into what
            the goal is close to [rad].
        approach_hold_time: time the robot may stay more than ``approach_lag_stop`` from
            the reference waiting at the approach's start before the approach starts
            from where the robot is (:meth:`JointGuidance.approach_from`) [s]: the
            obstacle leaves can hold it 0.05-0.15 rad short of a start the planner put
            at its 1 cm margin (problems 21-28, as posed: 7 of 9 failures stalled so).
        close_lag_slow, close_lag_stop: ``lag_slow`` and ``lag_stop`` on the way of a plan
            made after the robot was held short of an approach, when the straight
            approach from where it was is blocked: it had cut a corner on the way there,
            so the new way is followed more closely [rad] (chosen on problems 21-28, as
            posed: with the approach's 0.01 and 0.03 the way crawled and stalled).
        close_time: the way's last this many seconds before a grasp's approach are
            followed as closely (``close_lag_slow``, ``close_lag_stop``): where the robot
            enters the approach's start it must not cut the corner [s] (chosen on problems
            21-28, as posed: bookshelf_small/0021, 0022 and 0025).
    """

    path: JointPlannerSettings = field(default_factory=JointPlannerSettings)
    ik: IkSettings = field(default_factory=IkSettings)
    ik_retry: IkSettings = field(default_factory=lambda: IkSettings(seeds=240, time_limit=2.0))
    mesh_margin: float = 0.003
    timing: TimingSettings = field(default_factory=TimingSettings)
    speed: float = 0.5
    acceleration: float = 0.25
    attempts: int = 3
    replans: int = 10
    blocked_interval: float = 0.5
    lag_slow: float = 0.1
    lag_stop: float = 0.3
    check_period: float = 0.1
    check_horizon: float = 1.0
    stall_window: float = 2.0
    stall_rate: float = 0.25
    stall_progress: float = 0.05
    stall_floor: float = 0.02
    stall_lag_time: float = 1.0
    stall_margin: float = 0.03
    stall_margin_time: float = 0.5
    goal_clearance: float = 0.015
    approach_speed: float = 0.1
    approach_lag_slow: float = 0.01
    approach_lag_stop: float = 0.03
    approach_hold_time: float = 1.0
    close_lag_slow: float = 0.03
    close_lag_stop: float = 0.1
    close_time: float = 1.0


class GuidanceError(RuntimeError):
    """No plan: ``reason`` is ``goal_outside_limits``, ``no_ik_solution``,
    ``start_in_collision``, ``goal_in_collision``, ``no_path`` or ``timing``."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


@dataclass(frozen=True)
class Plan:
    """A timed reference to a goal configuration.

    Attributes:
        trajectory: ``q_r`` from its start at time 0 (rest at both ends); with an approach,
            two phases (:class:`PhasedTrajectory`), at rest between them.
        goal: the goal configuration [rad].
        time_s: wall time of inverse kinematics, planning and timing [s].
        checks: configurations checked [-].
        approach: joint-space length of the last segment, which the planner checked only
            against going deeper than the goal itself (the goal was closer to obstacles
            than its margin); 0 if the goal was free [rad].
        approach_start: when the approach begins on the reference's clock [s] (its
            duration without one).
    """

    trajectory: JointTrajectory | PhasedTrajectory
    goal: NDArray[np.float64]
    time_s: float
    checks: int
    approach: float = 0.0
    approach_start: float = 0.0


class JointGuidance:
    """Plans joint-space references for ``robot`` (module docstring).

    Attributes:
        robot: the robot (fixed base).
        settings: the guidance settings.
        checker: the configuration checker with the obstacles of the last plan.
    """

    def __init__(self, robot: Robot, settings: GuidanceSettings = GuidanceSettings()) -> None:
        if robot.base is not None or robot.planar:
            raise ValueError(f"robot '{robot.name}': joint-space guidance needs a fixed-base robot in space")
        self.robot = robot
        self.settings = settings
        self.checker = ConfigurationChecker(robot)
        self._single = ConfigurationChecker(robot)  # one obstacle at a time (allowances)
        self._ahead = ConfigurationChecker(robot)   # what moves (blocked_ahead)
        self._mesh_check: MeshGoalCheck | None | bool = False  # made on first use; None: no meshes
        self._leaf_spheres = list(moving_spheres(robot))  # those a nearest-point leaf acts on
        self._leaf_radii = np.asarray(robot.sphere_radii, dtype=float)[self._leaf_spheres]
        kin = robot.kinematics
        self._lower = np.where(np.isfinite(kin.lower), kin.lower, -np.pi)
        self._upper = np.where(np.isfinite(kin.upper), kin.upper, np.pi)

    def goal_configuration(self, goal: GoalTargets, q: NDArray[np.float64], seed: int = 0) -> NDArray[np.float64]:
        """The configuration to plan to: a joint goal (clipped into the limits when within
        :data:`LIMIT_SLACK`), or the collision-free IK solution nearest ``q`` (clear by the
        planner's margin, else by ``ik_retry`` merely free on the spheres or free on the
        meshes).

        Raises:
            GuidanceError: ``goal_outside_limits`` or ``no_ik_solution``.
        """
        if isinstance(goal, JointTarget):
            target = np.asarray(goal.q, dtype=float)
            outside = np.flatnonzero((target < self._lower - LIMIT_SLACK) | (target > self._upper + LIMIT_SLACK))
            if outside.size:
                names = self.robot.kinematics.joint_names
                j = int(outside[0])
                raise GuidanceError("goal_outside_limits", f"the goal puts {names[j]} at {target[j]:.6g}, outside "
                                    f"its limits [{self._lower[j]:.6g}, {self._upper[j]:.6g}]")
            return np.clip(target, self._lower, self._upper)
        margin, self_margin = self.settings.path.margin, self.settings.path.self_margin
        result = solve_ik(self.robot, list(goal), q, lambda x: self.checker.free(x, margin, self_margin),
                          self._ik_settings(seed), self._lower, self._upper)
        if result.q is None:
            meshes = self._meshes()

            def free(x: NDArray[np.float64]) -> bool:
                return self.checker.free(x, 0.0, self_margin) or (meshes is not None and meshes.free(x))

            result = solve_ik(self.robot, list(goal), q, free, replace(self.settings.ik_retry, seed=seed),
                              self._lower, self._upper)
        if result.q is None:
            found = (f"{result.converged} solutions within the limits, all in collision" if result.converged
                     else "no solution within the joint limits")
            raise GuidanceError("no_ik_solution", f"inverse kinematics: {found} ({result.seeds} seeds)")
        return result.q

    def plan(self, q: NDArray[np.float64], goal: GoalTargets, obstacles: Sequence[PlacedObstacle],
             seed: int = 0, wide: bool = False) -> Plan:
        """A timed free reference from ``q`` (at rest) to ``goal`` among ``obstacles``; if
        ``wide``, the first attempt keeps ``stall_margin`` (a replan after a stall).

        Raises:
            GuidanceError: if every attempt failed (the last one's reason).
        """
        began = time.perf_counter()
        self.checker.set_obstacles(obstacles)
        start = np.clip(np.asarray(q, dtype=float), self._lower, self._upper)
        target = self.goal_configuration(goal, start, seed)
        approach = self._mesh_approach()
        error: GuidanceError | None = None
        checks = 0
        path_settings = self.settings.path
        tries = [(replace(path_settings, time_limit=path_settings.time_limit * 2**attempt), seed + attempt)
                 for attempt in range(self.settings.attempts)]
        if wide and self.settings.stall_margin > path_settings.margin:
            tries.insert(0, (replace(path_settings, margin=self.settings.stall_margin,
                                     time_limit=self.settings.stall_margin_time), seed))
        for settings, attempt_seed in tries:
            try:
                path = plan_joint_path(self.checker, start, target, self._lower, self._upper, settings, attempt_seed,
                                       approach)
            except NoPathError as failure:
                error = GuidanceError(failure.reason, str(failure))
                if failure.reason != "no_path" and settings.margin == path_settings.margin:
                    break
                continue
            checks += path.checks
            try:
                trajectory = self._timed(path)
            except TimingError as failure:
                raise GuidanceError("timing", str(failure)) from None
            if isinstance(trajectory, PhasedTrajectory):
                approach = float(np.linalg.norm(path.waypoints[-1] - path.waypoints[-2]))
                return Plan(trajectory, target, time.perf_counter() - began, checks, approach,
                            float(trajectory.starts[-1]))
            return Plan(trajectory, target, time.perf_counter() - began, checks, 0.0, trajectory.duration)
        assert error is not None
        raise error

    def approach_from(self, q: NDArray[np.float64], goal: NDArray[np.float64]) -> Plan | None:
        """A plan that is only an approach: the straight segment from ``q`` (the robot, held
        short of its plan's approach) to the blocked ``goal``, timed as an approach, if it
        goes no deeper into the last plan's obstacles than ``goal`` does
        (:func:`~dynfab.motion.joint_planning.approach_clear`); else None."""
        began = time.perf_counter()
        start = np.clip(np.asarray(q, dtype=float), self._lower, self._upper)
        length = float(np.linalg.norm(goal - start))
        if length < SHORTEST_APPROACH or not approach_clear(self.checker, start, goal, self.settings.path):
            return None
        trajectory = PhasedTrajectory((self._approach_timed(np.vstack([start, goal])),))
        return Plan(trajectory, np.asarray(goal, dtype=float), time.perf_counter() - began, 0, length, 0.0)

    def approach_allowances(self, plan: Plan, obstacles: Sequence[PlacedObstacle],
                            buffers: Sequence[float]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`allowances` along ``plan``'s approach: its configurations every
        ``path.resolution`` from its start to the goal (k, n) [rad] and the allowances of
        ``obstacles`` at each (k, m) [m]. The straight approach may pass closer to an
        obstacle than the goal is (a table under a grasp), where the leaves would hold the
        robot short of the goal (problems 21-28, as posed: table_pick); what it may pass
        matters only until the robot is past it (:meth:`GuidedFabric.allowances`)."""
        if not isinstance(plan.trajectory, PhasedTrajectory):
            raise ValueError("approach_allowances: the plan has no approach")
        segment = polyline_samples(plan.trajectory.phases[-1].waypoints, self.settings.path.resolution)
        clearances = np.empty((len(segment), len(obstacles)))
        for k, obstacle in enumerate(obstacles):
            self._single.set_obstacles((obstacle,))
            clearances[:, k] = self._single.batch(segment)[:, 0]
        return segment, np.maximum(0.0, np.asarray(buffers, dtype=float) + self.settings.goal_clearance - clearances)

    def allowances(self, q: NDArray[np.float64], obstacles: Sequence[PlacedObstacle],
                   buffers: Sequence[float]) -> NDArray[np.float64]:
        """How far [m] the fabric's spheres may enter each obstacle so that its leaves,
        which keep ``buffers[k]`` of clearance, still see ``goal_clearance`` at ``q``:
        ``a_k = max(0, buffer_k + goal_clearance − c_k(q))``, with ``c_k`` the clearance of
        the robot's spheres from obstacle ``k`` alone."""
        if not obstacles:
            return np.zeros(0)
        clearances = np.array([self.obstacle_clearance(q, obstacle) for obstacle in obstacles])
        return np.maximum(0.0, np.asarray(buffers, dtype=float) + self.settings.goal_clearance - clearances)

    def obstacle_clearance(self, q: NDArray[np.float64], obstacle: PlacedObstacle) -> float:
        """Clearance [m] of the robot's spheres at ``q`` from ``obstacle`` alone: the
        checker's, or for a mesh or a point cloud what the fabric's nearest-point leaf sees
        (:func:`~dynfab.perception.surfaces.surface_clearance` of the spheres a joint moves:
        exact for a mesh, where the checker's grid reads up to ``h√3`` less)."""
        if isinstance(obstacle.shape, Mesh | PointCloud):
            centres = np.asarray(self.robot.sphere_centers(q))[self._leaf_spheres]
            return surface_clearance(centres, self._leaf_radii, obstacle.shape, obstacle.placement)
        self._single.set_obstacles((obstacle,))
        return self._single.clearances(q)[0]

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
        if not path.escaped_goal:
            return time_path(path.waypoints, *cruise, settings.timing)
        way = time_path(path.waypoints[:-1], *cruise, settings.timing)
        return PhasedTrajectory((way, self._approach_timed(path.waypoints[-2:])))

    def _approach_timed(self, segment: NDArray[np.float64]) -> JointTrajectory:
        """A grasp's approach segment (2, n) timed at ``approach_speed`` of the limits."""
        limits, settings = self.robot.limits, self.settings
        return time_path(segment, settings.approach_speed * limits.velocity,
                         settings.approach_speed * limits.acceleration, settings.timing)

    def _mesh_approach(self) -> Callable[[NDArray[np.float64], NDArray[np.float64]], bool] | None:
        """Among meshes or point clouds, the check of an escaped goal's approach on the robot's
        meshes: no deeper than the goal is on them, nor closer than ``mesh_margin`` where it
        is farther (:meth:`MeshGoalCheck.segment_free`, every half ``path.resolution``; the
        robot's meshes are read on first use); else None."""
        if not any(isinstance(o.shape, Mesh | PointCloud) for o in self.checker.obstacles):
            return None
        step = self.settings.path.resolution / 2
        goal_floor: float | None = None   # measured once, when a goal turns out blocked

        def approach(free: NDArray[np.float64], goal: NDArray[np.float64]) -> bool:
            nonlocal goal_floor
            meshes = self._meshes()
            if meshes is None:  # a robot without meshes: the spheres' test alone
                return True
            if goal_floor is None:
                goal_floor = min(meshes.margin, meshes.clearance(goal)[0])
            return meshes.segment_free(free, goal, step, goal_floor)

        return approach

    def _meshes(self) -> MeshGoalCheck | None:
        """The mesh check of goal solutions against the checker's obstacles, made on first
        use; None for a robot without collision meshes (or whose meshes cannot be read)."""
        if self._mesh_check is False:
            robot = self.robot
            try:
                model = mesh_collision_model(robot.kinematics, robot.default_q, builtin_collision_meshes(robot))
            except LinkMeshError:
                model = None
            self._mesh_check = None if model is None else MeshGoalCheck(model, self.settings.mesh_margin)
        if isinstance(self._mesh_check, MeshGoalCheck):
            self._mesh_check.set_obstacles(self.checker.obstacles)
            return self._mesh_check
        return None

    def _ik_settings(self, seed: int) -> IkSettings:
        return replace(self.settings.ik, seed=seed)
