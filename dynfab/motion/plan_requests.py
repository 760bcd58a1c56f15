"""Plans made off the control loop: a guided fabric asks for a plan and keeps commanding
the robot while it is made (issue 19: the robot never waits for a plan).

A :class:`PlanRequest` holds everything a plan needs, captured when it is asked for (the
robot's configuration, the goal, the obstacles, the seed), so the plan does not depend on
when it is made. :func:`make_plan` turns it into a :class:`PlanOutcome`: the goal
configuration (inverse kinematics for task goals; a replan keeps the one the robot was
heading for while a plan to it can be made), published on the
:class:`PendingPlan` as soon as it is known (the fabric can head for it while the path is
planned), then the path and its timing (:meth:`JointGuidance.plan`), and the static
obstacles' allowances along a grasp's approach.

Two ways to make it:

- :class:`BackgroundPlans` (real time, the library's default): one worker thread, started
  once the tick that asked for the plan has computed its command; a plan arrives as soon as
  it is made. OMPL's ``solve`` lets the control thread run between its
  calls of the Python validity check (measured: ``docs/guides/guidance.md``), so a control
  tick waits at most Python's switch interval (``sys.getswitchinterval()``, 5 ms by
  default) for the interpreter.
- :class:`DelayedPlans` (simulation): the plan is made at once in the caller's thread and
  handed over ``latency`` seconds of the caller's clock later, so a simulated run is
  reproducible whatever the machine's load.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.guidance import GoalTargets, GuidanceError, JointGuidance, JointTarget, Plan
from dynfab.motion.making_way import refuge_plan
from dynfab.motion.swept_obstacles import swept_clear_of

__all__ = ["BackgroundPlans", "DelayedPlans", "PendingPlan", "PlanMaker", "PlanOutcome", "PlanRequest", "make_plan",
           "plan_maker"]


@dataclass(frozen=True)
class PlanRequest:
    """What a plan is made from, captured when it is asked for.

    Attributes:
        t: the caller's time of the request [s].
        q: the robot's configuration then (n,) [rad].
        goal: the goal (a joint goal or task targets).
        static: the obstacles that do not move.
        moving: the moving ones where they were at ``t``, with their velocities (left out
            of a first plan; a replan avoids what they sweep soon, :func:`make_plan`).
        previous_goal: the goal configuration of the plan being followed (n,) [rad], or
            None (a first plan): moving obstacles that touch it are passing the goal and
            are left out.
        seed: the first planning seed [-].
        wide: keep the stall margin first (a replan after a stall on the way).
        buffers: per static obstacle, the clearance its fabric leaves keep [m].
        after: why the plan is asked for (``held``, ``short``, ``stalled``, ``blocked``,
            ``refuge``, ``return``), None at first; after ``refuge`` the plan is to a refuge
            from what the moving obstacles sweep (:mod:`dynfab.motion.making_way`); after ``short`` the straight approach from ``q`` to ``previous_goal`` is
            tried first (:meth:`~dynfab.motion.guidance.JointGuidance.approach_from`). A
            replan of task goals plans to ``previous_goal`` first, and solves inverse
            kinematics again only if no plan to it can be made.
    """

    t: float
    q: NDArray[np.float64]
    goal: GoalTargets
    static: tuple[PlacedObstacle, ...]
    moving: tuple[PlacedObstacle, ...]
    previous_goal: NDArray[np.float64] | None
    seed: int
    wide: bool
    buffers: tuple[float, ...]
    after: str | None = None


@dataclass(frozen=True)
class PlanOutcome:
    """A finished request.

    Attributes:
        plan: the timed reference, or None if no plan could be made.
        failure: why not (:class:`GuidanceError` reasons), or None.
        message: the error's message, or None.
        elapsed_ms: wall time of making it (IK, path, timing, allowances) [ms].
        segment: the approach's configurations (k, n) [rad] (the goal alone without one).
        table: per configuration of ``segment`` and static obstacle, how far [m] the
            fabric's spheres may enter it there (k, m) (zeros without an approach;
            :meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`).
        way: the configurations of the plan's way, before its approach (k, n) [rad].
        way_table: the same for ``way`` (k, m)
            (:meth:`~dynfab.motion.guidance.JointGuidance.way_allowances`).
    """

    plan: Plan | None
    failure: str | None
    message: str | None
    elapsed_ms: float
    segment: NDArray[np.float64]
    table: NDArray[np.float64]
    way: NDArray[np.float64]
    way_table: NDArray[np.float64]


class PendingPlan:
    """A plan being made: its request, the goal configuration once known, the outcome once
    done (a future of a worker thread's, or an outcome made already with the time it may
    be taken at).

    Attributes:
        request: what the plan is made from.
        goal_configuration: the plan's goal configuration (n,) [rad] once known, else None;
            None throughout for a start closer to the obstacles than the planner's margin
            (the robot then waits for the plan, whose way out leaves them).
    """

    def __init__(self, request: PlanRequest) -> None:
        self.request = request
        self.goal_configuration: NDArray[np.float64] | None = None
        self._ready_at = np.inf
        self._outcome: PlanOutcome | None = None
        self._future: Future[PlanOutcome] | None = None

    def publish(self, q: NDArray[np.float64]) -> None:
        """Record the goal configuration ``q`` (by the maker, once)."""
        self.goal_configuration = q

    def run_on(self, executor: ThreadPoolExecutor, guidance: JointGuidance) -> None:
        """Make the plan on ``executor``'s thread."""
        self._future = executor.submit(make_plan, guidance, self.request, self.publish)

    def run_now(self, guidance: JointGuidance, ready_at: float) -> None:
        """Make the plan now; it may be taken from the caller's time ``ready_at`` [s] on."""
        self._outcome = make_plan(guidance, self.request, self.publish)
        self._ready_at = ready_at

    def ready(self, t: float) -> bool:
        """Whether the outcome may be taken at the caller's time ``t`` [s]."""
        if self._future is not None:
            return self._future.done()
        return self._outcome is not None and t >= self._ready_at

    def outcome(self) -> PlanOutcome:
        """The outcome (call once :meth:`ready`)."""
        if self._future is not None:
            return self._future.result()
        assert self._outcome is not None
        return self._outcome


def make_plan(guidance: JointGuidance, request: PlanRequest,
              publish: Callable[[NDArray[np.float64]], None] = lambda q: None) -> PlanOutcome:
    """Plan for ``request`` with ``guidance`` (module docstring); ``publish`` gets the goal
    configuration as soon as it is known. Never raises for a plan that cannot be made.
    After ``refuge``: the plan to a refuge (:func:`~dynfab.motion.making_way.refuge_plan`).

    A replan avoids each moving sphere as the capsule it sweeps over ``sweep_horizon``
    (:func:`~dynfab.motion.swept_obstacles.swept_obstacle`), so that the new reference
    leaves its line rather than running ahead of it, unless that capsule touches the robot
    now or at the goal configuration (the sphere itself then,
    :func:`~dynfab.motion.swept_obstacles.swept_clear_of`); the plan around the spheres where they are
    instead if none around the capsules can be made or it is shorter
    (:func:`_swept_plan`)."""
    began = time.perf_counter()
    none = np.zeros((1, len(request.static)))
    if request.after == "refuge":
        try:
            plan = refuge_plan(guidance, request.q, request.static, request.moving, request.seed)
        except GuidanceError as error:
            return PlanOutcome(None, error.reason, str(error), _ms_since(began), request.q[None], none,
                               request.q[None], none)
        return PlanOutcome(plan, None, None, _ms_since(began), plan.goal[None], none, plan.goal[None], none)
    frozen = swept = ()
    if request.previous_goal is not None:   # what moves and touches the goal configuration is passing it
        margin = guidance.settings.path.margin
        frozen = tuple(o for o in request.moving if guidance.obstacle_clearance(request.previous_goal, o) >= margin)
        ends = (request.q, request.previous_goal)   # a plan must not start nor end in a capsule
        swept = tuple(swept_clear_of(o, guidance.settings.sweep_horizon, ends, guidance.obstacle_clearance, margin)
                      for o in frozen)
    try:
        plan = _swept_plan(guidance, request, swept, frozen, publish)
    except GuidanceError as error:
        return PlanOutcome(None, error.reason, str(error), _ms_since(began), request.q[None], none, request.q[None],
                           none)
    way, way_table = guidance.way_allowances(plan, request.static, request.buffers)
    segment, table = ((plan.goal[None], none) if plan.approach <= 0 else
                      guidance.approach_allowances(plan, request.static, request.buffers))
    return PlanOutcome(plan, None, None, _ms_since(began), segment, table, way, way_table)


def _swept_plan(guidance: JointGuidance, request: PlanRequest, swept: tuple[PlacedObstacle, ...],
                frozen: tuple[PlacedObstacle, ...], publish: Callable[[NDArray[np.float64]], None]) -> Plan:
    """The plan of ``request`` around the static obstacles and the moving ones as ``swept``,
    unless none can be made or it takes more than ``sweep_detour`` times as long as the
    plan around them as ``frozen`` (where they are), then that one.

    Raises:
        GuidanceError: if no plan can be made either way.
    """
    try:
        plan = _plan_among(guidance, request, request.static + swept, publish)
    except GuidanceError:
        if swept == frozen:
            raise
        return _plan_among(guidance, request, request.static + frozen, publish)
    if swept == frozen:
        return plan
    try:
        direct = _plan_among(guidance, request, request.static + frozen, publish)
    except GuidanceError:
        return plan
    detour = guidance.settings.sweep_detour
    return direct if plan.trajectory.duration > detour * direct.trajectory.duration else plan


def _plan_among(guidance: JointGuidance, request: PlanRequest, obstacles: tuple[PlacedObstacle, ...],
                publish: Callable[[NDArray[np.float64]], None]) -> Plan:
    """The plan of ``request`` among ``obstacles`` (:func:`make_plan`).

    Raises:
        GuidanceError: if no plan can be made.
    """
    guidance.set_obstacles(obstacles)
    plan = None
    if request.after == "short" and request.previous_goal is not None:   # held short of an approach
        plan = guidance.approach_from(request.q, request.previous_goal)
    if plan is None and request.previous_goal is not None and not isinstance(request.goal, JointTarget):
        plan = _replan_to(guidance, request, obstacles, publish)
    if plan is None:
        target, moved = guidance.goal_solution(request.goal, request.q, request.seed)
        if guidance.clear_of_obstacles(request.q):   # else the robot waits for the plan's way out
            publish(target)
        tolerance = request.goal.tolerance if isinstance(request.goal, JointTarget) else 0.0
        plan = guidance.plan(request.q, JointTarget(tuple(target), tolerance), obstacles, seed=request.seed,
                             wide=request.wide)
        plan = replace(plan, goal_moved=plan.goal_moved or moved)   # a task goal's target, moved before planning
    return plan


def _replan_to(guidance: JointGuidance, request: PlanRequest, obstacles: tuple[PlacedObstacle, ...],
               publish: Callable[[NDArray[np.float64]], None]) -> Plan | None:
    """A replan of task goals to the goal configuration the robot was heading for
    (``request.previous_goal``), or None if none can be made (then inverse kinematics
    looks for another). Solving them again from where the robot is held can pick a
    configuration far from it whose plan does not fit in the run (MBM table_bars/0008:
    5.5 rad away, a 17 s plan, after a stall 0.59 rad from the goal)."""
    assert request.previous_goal is not None
    publish(request.previous_goal)
    try:
        return guidance.plan(request.q, JointTarget(tuple(request.previous_goal)), obstacles, seed=request.seed,
                             wide=request.wide)
    except GuidanceError:
        return None


def _ms_since(began: float) -> float:
    return 1e3 * (time.perf_counter() - began)


class BackgroundPlans:
    """Makes plans on one worker thread, in the order asked (module docstring). A plan asked
    for waits until :meth:`start`: the caller starts it once its tick's command is computed,
    so that the worker does not hold the interpreter while the command is computed; the
    worker thread itself is started with this object, not in a tick (module docstring)."""

    def __init__(self, guidance: JointGuidance) -> None:
        self._guidance = guidance
        self._executor: ThreadPoolExecutor | None = None
        self._waiting: PendingPlan | None = None
        self._start_worker()

    def _start_worker(self) -> None:
        """Start the worker thread now, not in a tick: ``Thread.start`` waits until the new
        thread runs, 10-30 ms at load 13 on the 2-core machine."""
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="dynfab-plan")
        self._executor.submit(lambda: None).result()

    def submit(self, request: PlanRequest) -> PendingPlan:
        """Ask for a plan for ``request``; returns at once, the plan made from :meth:`start` on."""
        self._waiting = PendingPlan(request)
        return self._waiting

    def start(self, asked_before: float = math.inf) -> None:
        """Start making the plan asked for last, if it waits and was asked for before the
        caller's time ``asked_before`` [s] (any time by default)."""
        if self._waiting is None or self._waiting.request.t >= asked_before:
            return
        if self._executor is None:   # closed, and asked again
            self._start_worker()
        assert self._executor is not None
        self._waiting.run_on(self._executor, self._guidance)
        self._waiting = None

    def close(self) -> None:
        """Drop a plan not started; let the worker thread end once the plan it makes is done."""
        self._waiting = None
        if self._executor is not None:
            self._executor.shutdown(wait=False)
            self._executor = None


class DelayedPlans:
    """Makes each plan at once and hands it over ``latency`` seconds of the caller's clock
    later (module docstring).

    Attributes:
        latency: time between a request and its plan's arrival [s] (≥ 0).
    """

    def __init__(self, guidance: JointGuidance, latency: float) -> None:
        if not np.isfinite(latency) or latency < 0.0:
            raise ValueError(f"plan_latency must be a finite number >= 0 s, got {latency}")
        self._guidance = guidance
        self.latency = float(latency)

    def submit(self, request: PlanRequest) -> PendingPlan:
        """Make the plan for ``request`` now; it is ready ``latency`` after ``request.t``."""
        pending = PendingPlan(request)
        pending.run_now(self._guidance, request.t + self.latency - 1e-9)   # whole ticks land on a tick
        return pending

    def start(self, asked_before: float = math.inf) -> None:
        """Nothing waits: a plan is made when it is asked for."""

    def close(self) -> None:
        """Nothing runs in the background."""


PlanMaker = BackgroundPlans | DelayedPlans


def plan_maker(guidance: JointGuidance, latency: float | None) -> PlanMaker:
    """:class:`BackgroundPlans` for ``latency`` None (real time), else :class:`DelayedPlans`."""
    return BackgroundPlans(guidance) if latency is None else DelayedPlans(guidance, latency)

