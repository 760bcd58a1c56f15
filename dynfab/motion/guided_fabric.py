"""A dynamic fabric that tracks global joint-space guidance: the library's class for
reaching goals in cluttered scenes (issue 19).

``GuidedFabric(fabric)`` takes a dynamic :class:`~dynfab.fabric.planner.FabricPlanner` whose
first goal is a joint-space goal on every joint (:func:`guided_goal_config`). On
:meth:`GuidedFabric.set_goal` it asks for a free, timed joint-space reference
(:class:`~dynfab.motion.guidance.JointGuidance`) and returns at once: the plan is made off
the control loop (:mod:`dynfab.motion.plan_requests`: on a worker thread, or in
simulation at once and applied ``plan_latency`` seconds later), and until it arrives the
reference is the straight joint-space motion to the goal configuration at the plan's
cruise limits (:class:`~dynfab.motion.straight_motion.StraightMotion`; the goal
configuration is known at once for a joint goal, after inverse kinematics for the others,
and the reference holds the robot's configuration before that), so the fabric heads for
the goal alone, its obstacle, limit and self-collision leaves on. From a start closer to
the obstacles than the planner's margin the reference holds the robot's configuration until
the plan arrives: the plan leaves such a start along a checked way out, and a straight
motion toward the goal does not know it (fresh MBM kitchen seed 32/0002: a start 0.1 mm from
the cupboard on Franka's meshes, 1.6 cm into it on the spheres; heading for the goal for the
plan's 50 ms of latency, ``panda_link5`` touched the cupboard at 0.13 s; holding, the run
reached its goal without a contact). Every tick
:meth:`GuidedFabric.update` writes ``q_r, q̇_r, q̈_r`` into that goal, where the dynamic
pullback and energization of the fabric (paper section IV) track it, while the fabric's
leaves keep acting on everything the user writes into its slots.

A plan arrives after the robot has moved: its clock starts where the robot joins it
(:func:`~dynfab.motion.plan_joining.join_time`), so the reference does not jump back to
where the plan began; its clock slows until the robot is on it.

The reference runs on its own clock ``τ``, which slows while the robot lags behind it or,
in a grasp's approach, drifts beside the checked segment
(:mod:`dynfab.motion.reference_clock`); once the robot follows the approach its goal is
shifted across the checked segment toward it (:mod:`dynfab.motion.approach_pull`). Off the
approach, a reference out of the robot's sight among the static primitives
(:func:`~dynfab.motion.plan_joining.in_sight`: a corner; not meshes nor clouds) steps back
on its clock to the latest point within a second that the robot sees
(:func:`~dynfab.motion.plan_joining.sight_time`), or, if there is none, its clock stands
still. Along the plan's way the static primitives get the allowances that let the fabric's
leaves see what the plan's tighter spheres kept
(:meth:`~dynfab.motion.guidance.JointGuidance.way_allowances`), near where the robot is on
the way (:mod:`dynfab.motion.way_window`) and at most what the same rule gives at the
robot's own configuration (:meth:`~dynfab.motion.allowance_tables.AllowanceTables.way_at`,
on checkers of the control loop's own), except along a blocked start's way out.

It asks for a replan from where the robot is (at most ``replans`` times; until the new
one arrives the old reference's clock stands still outside a grasp's approach, so the
fabric brakes at its point and keeps avoiding rather than following it into what blocked
it, while in the approach the clock keeps its lag rule. Chosen on held-out problems, which
therefore do not test it: with a 50 ms plan latency and the clock running on,
moving-sphere bookshelf_thin/0017 and 0019 stalled after 7-8 plans; with it stopped
everywhere, as-posed table_under_pick/0019 stalled in its approach; as here, all three
reached their goals) when the reference ahead meets what a moving obstacle sweeps, the
run stalls, or the robot is held short of a grasp's approach (:mod:`dynfab.motion.replan_reasons`).
A replan after the robot was held short is the straight approach from where the robot is,
if that segment goes no deeper into anything than the goal
(:meth:`~dynfab.motion.guidance.JointGuidance.approach_from`); else a plan as after a
stall, whose way is followed closely.

Replans plan among the static obstacles and what the moving ones sweep within
``sweep_horizon`` from where they are now (:func:`~dynfab.motion.plan_requests.make_plan`),
except those that touch the goal configuration (they are passing it: a plan around where
they are now would end in a needless escape of the goal; the fabric avoids them). A replan
after a stall on the way (not in an approach, nor after the reference ended) first tries
to keep ``stall_margin`` from obstacles, so that it does not lead through the same tight
passage again; a stall in a grasp's approach replans as before (training as-posed
table_pick/0014: replans at 3 cm there stalled 5 times in the approach). While what a moving
sphere sweeps comes near the goal configuration, the robot waits at a refuge out of its
way and returns once it has passed (:mod:`dynfab.motion.making_way`).

A goal closer to a static obstacle than the planner's margin (a grasp, where the
spheres overlap what the meshes clear) ends the plan with a segment the planner checked
only against going deeper than the goal (:attr:`~dynfab.motion.guidance.Plan.approach`),
timed as a slow phase of its own after a stop, and followed closely. Once the robot is
on it (the clock in the approach, the robot within ``approach_lag_stop`` of the
reference), :meth:`GuidedFabric.allowances` gives each static obstacle, until the next
plan, the allowance its leaves need to let the spheres reach the goal and everything on
the approach's straight segment
(:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`); the caller writes them into the
obstacles' slots (``allowance`` of a shape, a smaller radius for a sphere). If no
plan can be made the reference holds the configuration the robot had (the fabric then
brakes and keeps avoiding), and :attr:`GuidedFabric.status` says why.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from dynfab.fabric.leaves.goal import GoalAttractor
from dynfab.fabric.planner import FabricPlanner, GoalConfig
from dynfab.geometry.shapes import Mesh, PointCloud
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.allowance_tables import AllowanceTables, departure_rows
from dynfab.motion.approach_pull import ApproachPull
from dynfab.motion.approach_segment import allowances_ahead, leaf_buffers, segment_offset
from dynfab.motion.guidance import GoalTargets, GuidanceSettings, JointGuidance, Plan
from dynfab.motion.guidance_settings import counted_checks
from dynfab.motion.guidance_status import GuidanceStatus
from dynfab.motion.plan_joining import in_sight, join_time, sight_time
from dynfab.motion.reference_clock import approach_rate, in_approach, way_rate
from dynfab.motion.plan_requests import PendingPlan, PlanRequest, plan_maker
from dynfab.motion.replan_reasons import ReplanWatch, counted
from dynfab.motion.straight_motion import StraightMotion
from dynfab.motion.way_window import way_window

__all__ = ["GuidanceStatus", "GuidedFabric", "guided_goal_config"]


def guided_goal_config(attractor: GoalAttractor = GoalAttractor()) -> GoalConfig:
    """The joint-space goal a guided fabric's planner must have first (every joint)."""
    return GoalConfig(link=None, attractor=attractor)


class GuidedFabric:
    """A dynamic fabric tracking global joint-space guidance (module docstring).

    Attributes:
        fabric: the dynamic fabric planner (its first goal: :func:`guided_goal_config`).
        guidance: the planner of references.
        status: what guidance did so far.
        failure_message: the message of the last failed plan, or None.
    """

    def __init__(self, fabric: FabricPlanner, settings: GuidanceSettings = GuidanceSettings(),
                 plan_latency: float | None = None) -> None:
        """``plan_latency``: None makes plans on a worker thread (real time), bounded by wall
        time; seconds of the caller's clock make them at once and apply them that much later
        (simulation), their searches bounded by checks (:func:`counted_checks`), so a
        simulated run is the same at any load."""
        goal = fabric.config.goals[0]
        if not fabric.config.dynamic or not isinstance(goal, GoalConfig) or goal.link is not None or (
                goal.joints is not None and tuple(goal.joints) != tuple(range(fabric.robot.dof))):
            raise ValueError("GuidedFabric needs a dynamic FabricPlanner whose first goal is "
                             "guided_goal_config() (a joint goal on every joint)")
        settings = settings if plan_latency is None else counted_checks(settings)
        self.fabric = fabric
        self.guidance = JointGuidance(fabric.robot, settings)
        self.status = GuidanceStatus()
        self.failure_message: str | None = None
        self._settings = settings
        self._maker = plan_maker(self.guidance, plan_latency)
        self._pending: PendingPlan | None = None
        self._interim: tuple[float, StraightMotion] | None = None   # since when, toward the goal
        planning = fabric.robot.planning_robot   # the plans' spheres; these two are not the worker's checkers
        self._joining, self._sight = ConfigurationChecker(planning), ConfigurationChecker(planning)
        self._own_way = AllowanceTables(fabric.robot, settings)   # the way's allowances where the robot is
        self._static: tuple[PlacedObstacle, ...] = ()
        self._buffers: tuple[float, ...] = ()                # the leaves' clearance from each [m]
        self._goal: GoalTargets | None = None
        self._plan: Plan | None = None
        self._tau = 0.0
        self._last_t: float | None = None
        self._watch = ReplanWatch(settings)
        self._seed = 0
        self._segment = np.zeros((1, fabric.robot.dof))   # the approach's configurations (k, n) [rad]
        self._table = np.zeros((1, 0))                     # the allowances at each (k, m) [m]
        self._way = np.zeros((1, fabric.robot.dof))        # the way's configurations (k, n) [rad]
        self._way_table = np.zeros((1, 0))                 # the allowances at each (k, m) [m]
        self._departure_rows = 0                           # the way's first rows that see the meshes
        self._q = np.zeros(fabric.robot.dof)               # the robot at the last update [rad]
        self._reference = np.zeros(fabric.robot.dof)       # q_r(τ) written last, without the pull [rad]
        self._pull = ApproachPull(settings, fabric.robot.dof)
        self._approaching = False
        self._close = False
        self._home: NDArray[np.float64] | None = None      # the goal configuration while at a refuge

    @property
    def plan(self) -> Plan | None:
        """The reference being followed."""
        return self._plan

    @property
    def planning(self) -> bool:
        """Whether a plan is being made (asked for and not yet applied)."""
        return self._pending is not None

    def close(self) -> None:
        """Stop taking plans (a worker thread ends once the plan it makes is done)."""
        self._pending = None
        self._maker.close()

    def set_obstacles(self, obstacles: Sequence[PlacedObstacle]) -> None:
        """The obstacles plans avoid (those that do not move; moving ones go to :meth:`update`);
        the new obstacles get no allowance along an approach or a way under way (a row per sample: a
        camera's scene replaced mid-approach once crashed :meth:`allowances`)."""
        self._static = tuple(obstacles)
        self._buffers = leaf_buffers(self.fabric.config, self._static)
        self._sight.set_obstacles([o for o in self._static if not isinstance(o.shape, Mesh | PointCloud)])  # in_sight
        self._table = np.zeros((len(self._segment), len(self._static)))
        self._way_table = np.zeros((len(self._way), len(self._static)))

    @property
    def approaching(self) -> bool:
        """Whether the robot is on the plan's approach to a goal closer to obstacles than
        the planner's margin (module docstring)."""
        return self._approaching

    def allowances(self) -> NDArray[np.float64]:
        """Per static obstacle (:meth:`set_obstacles` order), how far [m] the fabric's
        spheres may enter it now: while :attr:`approaching`, the largest allowance at the
        approach's configurations from the robot's (its projection on the segment, less one
        sample) to the goal, else those of the plan's way near the robot
        (:func:`~dynfab.motion.way_window.way_window`), each at most what the planning
        spheres give where the robot is (:meth:`~dynfab.motion.allowance_tables.AllowanceTables.way_at`),
        except along a blocked start's way out, where the leaves see the meshes (module docstring)."""
        if self._approaching:
            return allowances_ahead(self._segment, self._table, self._q)
        if self._plan is None or not self._way_table.any():
            return np.zeros(len(self._static))
        window = way_window(self._way, self._q, self._reference, self._settings.way_reach)
        allowances = window.allowances(self._way_table)
        if window.rows.start < self._departure_rows or not allowances.any():
            return allowances
        own = self._own_way.way_at(self._q, self._static, self._buffers, np.flatnonzero(allowances))
        return np.minimum(allowances, own)

    def set_goal(self, goal: GoalTargets, t: float, q: NDArray[np.float64],
                 moving: Sequence[PlacedObstacle] = ()) -> None:
        """Ask for a plan to ``goal`` from ``q`` at time ``t`` [s] and return (module
        docstring): until it arrives the fabric heads for the goal configuration alone; a
        plan that cannot be made holds the configuration the robot then has (see :attr:`status`)."""
        self._goal = goal
        self._q = np.array(q, dtype=float)
        self._seed = 0
        self._plan = None
        self._approaching = False
        self._interim = self._home = None
        self._request(t, q, moving, after=None)
        self._receive(t, q, moving)   # a plan without latency arrives at once
        if self._plan is None and self._pending is not None:
            self._head_for_goal(t, q)

    def update(self, t: float, q: NDArray[np.float64], moving: Sequence[PlacedObstacle] = ()) -> None:
        """Apply a plan that arrived; advance the reference to time ``t`` [s] for the robot
        at ``q`` and write it into the fabric's first goal; ask for a replan if it is
        blocked ahead or progress stalled (the old reference's clock stands still until it
        arrives, outside an approach)."""
        self._q = np.array(q, dtype=float)
        self._maker.start(asked_before=t)   # a plan of an earlier tick whose caller did not start it
        self._receive(t, q, moving)
        if self._plan is None:
            if self._pending is not None:
                self._head_for_goal(t, q)
            return
        settings = self._settings
        lag = float(np.linalg.norm(q - self._reference))   # the reference at τ, written last tick
        budget = self.status.plans + self.status.failed_plans <= settings.replans or self._home is not None   # away: back
        if self._pending is None and budget:
            reason = self._watch.reason(t, q, lag, self._plan, self._tau, self._approaching, self.guidance,
                                        self._home, moving)
            self.status = counted(self.status, reason)
            if reason is not None:
                self._request(t, q, moving, after=reason)
                if self._receive(t, q, moving):
                    lag = float(np.linalg.norm(q - self._reference))
        dt = 0.0 if self._last_t is None else max(0.0, t - self._last_t)
        self._last_t = t
        approach = in_approach(self._plan, self._tau)
        self._approaching = self._approaching or (approach and lag <= settings.approach_lag_stop)
        sight = approach or in_sight(self._sight, q, self._reference, settings.path)
        if not sight and (seen := sight_time(self._plan, self._tau, q, self._sight, settings.path)) is not None:
            self._tau, sight = seen, True   # back to where the robot sees its reference
        waiting = self._pending is not None and not approach or not sight
        if waiting:
            rate = 0.0
        elif approach:
            rate = approach_rate(settings, lag, segment_offset(self._segment, q))
        else:
            rate = way_rate(settings, lag, close=self._close or self._entering())
        self._tau += rate * dt
        following = approach and self._approaching
        ended = self._tau >= self._plan.trajectory.duration
        self._write(self._tau, rate, self._pull.shift(self._segment, q, dt, ended) if following else None)

    def compute(self, t: float, q: NDArray[np.float64], qdot: NDArray[np.float64],
                moving: Sequence[PlacedObstacle] = ()) -> NDArray[np.float64]:
        """:meth:`update`, then the fabric's command (always finite, within the limits), then
        :meth:`start_plans`."""
        self.update(t, q, moving)
        command = self.fabric.compute(q, qdot)
        self.start_plans()
        return command

    def start_plans(self) -> None:
        """Start making a plan asked for in this tick (on the worker thread in real time;
        a simulated plan is made when asked for): :meth:`compute` calls it once the command
        is computed, so that the plan does not hold the interpreter while it is; a caller
        computing the command itself calls it after. A plan left waiting starts at the next
        tick's :meth:`update`."""
        self._maker.start()

    def _entering(self) -> bool:
        """Whether the reference's clock is within ``close_time`` before the plan's approach."""
        assert self._plan is not None
        return self._plan.approach > 0.0 and self._tau >= self._plan.approach_start - self._settings.close_time

    def _request(self, t: float, q: NDArray[np.float64], moving: Sequence[PlacedObstacle],
                 after: str | None) -> None:
        """Ask for a plan from ``q`` at time ``t`` [s]; ``after``: why (:meth:`ReplanWatch.reason`), None at first."""
        assert self._goal is not None
        previous_goal: NDArray[np.float64] | None = None   # a first plan keeps none
        if after is not None and self._home is not None:
            previous_goal = self._home                      # at a refuge: the goal configuration
        elif after is not None and self._plan is not None:
            previous_goal = self._plan.goal.copy()
        request = PlanRequest(t, np.array(q, dtype=float), self._goal, self._static, tuple(moving), previous_goal,
                              self._seed, after in ("held", "short"), self._buffers, after)
        self._seed += self._settings.attempts
        self._pending = self._maker.submit(request)

    def _receive(self, t: float, q: NDArray[np.float64], moving: Sequence[PlacedObstacle]) -> bool:
        """Apply the plan asked for if it has arrived at time ``t`` [s], joined where the
        robot is now (``q``: :func:`~dynfab.motion.plan_joining.join_time`); whether one arrived (made or failed)."""
        pending = self._pending
        if pending is None or not pending.ready(t):
            return False
        self._pending = None
        outcome, request = pending.outcome(), pending.request
        first = request.previous_goal is None
        status = self.status
        self.status = replace(status, guided=outcome.plan is not None or (status.guided and not first),
                              plans=status.plans + (outcome.plan is not None),
                              failed_plans=status.failed_plans + (outcome.plan is None),
                              plan_time_ms=outcome.elapsed_ms if status.plan_time_ms is None else status.plan_time_ms,
                              plan_times_ms=status.plan_times_ms + (outcome.elapsed_ms,), failure=outcome.failure)
        self.failure_message = outcome.message
        self._watch.restart(t, pause=request.after in ("blocked", "refuge"))
        plan = outcome.plan
        if plan is None:
            if first:
                self._plan = None
                self._set_reference(q, 0.0, 0.0)   # q at rest
            return True  # a failed replan keeps following the old reference
        if first:
            self._watch.scale_to(float(np.linalg.norm(request.q - plan.goal)))
        self.status = replace(self.status, goal_moved=self.status.goal_moved or plan.goal_moved)
        self._plan = plan
        self._home = request.previous_goal if request.after == "refuge" else None
        self._close = request.after == "short"
        self._approaching = False
        self._segment, self._table = outcome.segment, outcome.table
        self._way, self._way_table = outcome.way, outcome.way_table
        self._departure_rows = departure_rows(plan, self._settings.path.resolution)
        self._pull.reset()
        self._joining.set_obstacles(request.static + tuple(moving))
        self._tau = join_time(plan, np.asarray(q, dtype=float), self._joining, self._settings.path.resolution)
        self._last_t = t
        self._write(self._tau, 1.0)
        return True

    def _head_for_goal(self, t: float, q: NDArray[np.float64]) -> None:
        """While the first plan is made: once the goal configuration is known, the straight
        motion to it from where the robot then is, at the plan's cruise limits
        (:class:`StraightMotion`; the fabric, its leaves on, heads for the goal alone);
        before that ``q`` at rest."""
        assert self._pending is not None
        target = self._pending.goal_configuration   # published by the maker after IK
        if target is None:
            self._set_reference(q, 0.0, 0.0)   # q at rest
            return
        if self._interim is None or self._interim[1].goal is not target:
            limits, settings = self.fabric.robot.limits, self._settings
            motion = StraightMotion(np.array(q, dtype=float), target, settings.speed * limits.velocity,
                                    settings.acceleration * limits.acceleration)
            self._interim = (t, motion)
        began, motion = self._interim
        point = motion.evaluate(t - began)
        self._set_reference(point.position, point.velocity, point.acceleration)

    def _write(self, tau: float, rate: float, pull: NDArray[np.float64] | None = None) -> None:
        """Write the reference at its time ``tau`` [s], its clock running at ``rate`` [-],
        into the fabric's first goal: ``q_r(τ) + p, ρ q̇_r(τ), ρ² q̈_r(τ)``, ``p`` = ``pull``
        [rad] (:mod:`dynfab.motion.approach_pull`) or 0."""
        assert self._plan is not None
        point = self._plan.trajectory.evaluate(tau)
        self._set_reference(point.position, rate * point.velocity, rate**2 * point.acceleration, pull)

    def _set_reference(self, position: NDArray[np.float64], velocity: NDArray[np.float64] | float,
                       acceleration: NDArray[np.float64] | float, pull: NDArray[np.float64] | None = None) -> None:
        """Write ``q_r + pull, q̇_r, q̈_r`` [rad, rad/s, rad/s²] into the fabric's first goal
        (``q_r`` is kept: the lag is measured from it)."""
        params = self.fabric.parameters
        self._reference = np.array(position, dtype=float)
        params.goal_position[0][:] = position if pull is None else self._reference + pull
        params.goal_velocity[0][:] = velocity
        params.goal_acceleration[0][:] = acceleration
