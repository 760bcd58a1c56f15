"""Collision-free joint-space paths with OMPL (global guidance, issue 19).

A configuration is *free* when the checker (:mod:`dynfab.motion.configuration_checker`)
gives ``c_obs ≥ margin`` and ``c_self ≥ self_margin``, and it lies within the joint
limits (the state space's bounds). OMPL's planner (RRT-Connect by default) connects the
start to the goal through free configurations, checking straight motions every
``resolution`` radians (joint-space Euclidean), and its simplifier shortens the result
(vertex reduction and shortcuts). The finished polyline is checked again every
``resolution / 2`` as a whole, in one batched call.

Endpoints that are not free (a start pressed against an object, a grasp goal a few
millimetres from it, where the spheres already overlap what the meshes clear) are
handled as manipulation planners handle grasps: the nearest free configuration within
``escape_radius`` (random samples of growing radius; if none qualifies, as many again out to
``escape_far_radius``) from which the straight segment to
the real endpoint goes no deeper into obstacles (and into the robot itself) than the
endpoint does, ``escape_slack`` aside, becomes the planned endpoint; the segment is
appended (prepended for the start), and the fabric tracks it. A caller may ask more of
either endpoint's segment, or judge it otherwise (:class:`ApproachTest`: guidance checks it
on the robot's meshes, :mod:`dynfab.motion.mesh_goal_check`; for an endpoint free on the
meshes that test replaces the spheres', which read the segment from their bulges, 1-2 cm
out of the meshes at the hand: they refuse segments into a grasp that the meshes clear, and
accept some that the meshes find millimetres inside a board).

An endpoint whose own self-collision spheres overlap (``c_self < self_margin`` at it: the
spheres of a folded wrist overlap where the meshes are apart) lowers ``self_margin`` for
the whole plan to that overlap less ``escape_slack``, by at most ``self_tolerance``:

    self_margin' = max(min(self_margin, c_self(start) − slack, c_self(goal) − slack),
                       self_margin − self_tolerance)

Without it no configuration near such a goal is free (the overlap changes slowly with the
joints) and the goal cannot be escaped.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from dynfab.motion.ompl_problem import CheckBudget, solve_in_box
from dynfab.motion.configuration_checker import ConfigurationChecker

__all__ = ["WALL_FACTOR", "ApproachTest", "JointPath", "JointPlannerSettings", "NoPathError", "approach_clear",
           "plan_joint_path"]

PlannerName = Literal["RRTConnect", "RRT", "KPIECE1", "BKPIECE1", "PRM"]
_PLANNERS: dict[str, type] = {"RRTConnect": og.RRTConnect, "RRT": og.RRT, "KPIECE1": og.KPIECE1,
                              "BKPIECE1": og.BKPIECE1, "PRM": og.PRM}
_MAX_SEED = 2**31 - 2
#: planners whose motions are checked with two states only (KPIECE's need the last valid
#: state of a blocked motion and keep OMPL's own motion validator over the state callback)
_TWO_STATE_MOTIONS = frozenset({"RRTConnect", "RRT", "PRM"})


@dataclass(frozen=True)
class JointPlannerSettings:
    """How joint-space paths are planned.

    Attributes:
        planner: OMPL geometric planner.
        time_limit: planning time per attempt [s].
        resolution: longest joint-space step between checked configurations [rad].
        margin: clearance kept between the robot's spheres and obstacles [m].
        self_margin: clearance kept between the spheres of self-collision pairs [m].
        simplify_time: time given to OMPL's path simplifier [s].
        escape_radius: farthest a free endpoint is looked for around a blocked one [rad].
        escape_far_radius: farthest it is looked for when nothing within ``escape_radius``
            qualifies [rad] (``escape_samples`` more, from ``escape_radius`` out; no farther
            search if not above it). 0.8: training mesh problem table_bars/0004 (seed 0),
            a goal under a shelf free on the meshes, found none within 0.4 rad.
        escape_samples: samples tried per endpoint and radius [-].
        escape_slack: how much deeper [m] than the blocked endpoint itself the straight
            segment from the free configuration to it may reach into obstacles (or into
            the robot, for self-collision pairs).
        self_tolerance: largest self-overlap [m] an endpoint's own may lower ``self_margin``
            by (module docstring). 1 cm: the Panda's spheres stick out of its meshes by up
            to 1 cm at the hand; training problem as-posed bookshelf_small/0009, whose goal
            overlaps link5 and link7 by 3.5 mm on the spheres (free on the meshes), needs it.
        step: longest motion the planner adds to its trees at once (OMPL's ``range``;
            planners without one ignore it) [rad]. OMPL's default, a fifth of the joint
            space's diagonal (1.9 rad on the Panda), failed 5 of 9 plans into MBM's cage
            (problems 9-11, 3 seeds, 1 s each); 0.7 failed none, with a mean of 0.2 s.
        check_rate: None: ``time_limit`` and ``simplify_time`` are wall times. A rate
            [configurations/s]: they are budgets of checks instead, ``round(t · check_rate)``
            for a time ``t`` (the search and the simplifier stop at their budget; a search
            then depends on its seed only, not on the machine's load), with
            :data:`WALL_FACTOR` ``· t`` of wall time as a safety net (a machine that checks
            more than ten times slower than the rate, e.g. without a C compiler, stops by
            time). The simulators plan this way (:func:`counted_checks`).
    """

    planner: PlannerName = "RRTConnect"
    time_limit: float = 1.0
    resolution: float = 0.03
    margin: float = 0.01
    self_margin: float = 0.0
    simplify_time: float = 0.05
    escape_radius: float = 0.4
    escape_far_radius: float = 0.8
    escape_samples: int = 400
    escape_slack: float = 0.002
    step: float = 0.7
    self_tolerance: float = 0.01
    check_rate: float | None = None


#: With a ``check_rate``, the wall time a search or a simplification is given, as a multiple
#: of the time its budget of checks stands for [-].
WALL_FACTOR = 10.0


@dataclass(frozen=True)
class JointPath:
    """A planned joint-space polyline.

    Attributes:
        waypoints: configurations (k, n) from the start to the goal [rad].
        planning_time_s: wall time of planning and simplifying [s].
        checks: configurations checked [-].
        escaped_start: the start was blocked; ``waypoints[1]`` is the free one near it.
        escaped_goal: the goal was blocked; ``waypoints[-2]`` is the free one near it.
    """

    waypoints: NDArray[np.float64]
    planning_time_s: float
    checks: int
    escaped_start: bool
    escaped_goal: bool

    @property
    def inner(self) -> NDArray[np.float64]:
        """The planned way between the escapes (the free start to the free goal) (m, n) [rad]."""
        return self.waypoints[int(self.escaped_start):len(self.waypoints) - int(self.escaped_goal)]

    @property
    def winding(self) -> float:
        """How many times longer :attr:`inner` is than the straight distance between its
        ends [-] (1 for a straight way; 1 where its ends coincide)."""
        inner = self.inner
        length = float(np.sum(np.linalg.norm(np.diff(inner, axis=0), axis=1)))
        distance = float(np.linalg.norm(inner[-1] - inner[0]))
        return length / distance if distance > 0.0 else 1.0


@dataclass(frozen=True)
class ApproachTest:
    """A caller's test of a blocked endpoint's segment: the straight segment from a free
    configuration to the goal (its approach), or from the start to a free configuration.

    Attributes:
        accepts: ``(free, endpoint) ↦`` whether the segment between them may be the
            endpoint's (the same segment either way: it is straight).
        instead_of_spheres: whether ``accepts`` replaces the spheres' test (the segment goes
            no deeper into the checker's obstacles than the goal, module docstring) rather
            than adding to it.
    """

    accepts: Callable[[NDArray[np.float64], NDArray[np.float64]], bool]
    instead_of_spheres: bool = False


class NoPathError(RuntimeError):
    """No path was found; ``reason`` is ``start_in_collision``, ``goal_in_collision`` or
    ``no_path``."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


class _Validity:
    """OMPL's state validity callback, counting checks, and the motion validator that checks
    a whole straight motion in one compiled call (:meth:`ConfigurationChecker.motion_free`)."""

    def __init__(self, checker: ConfigurationChecker, settings: JointPlannerSettings, n: int) -> None:
        self._checker = checker
        self._free = checker.free  # bound once: OMPL calls __call__ for every configuration
        self._motion_free = checker.motion_free
        self._margin = settings.margin
        self._self_margin = settings.self_margin
        self._step = settings.resolution
        self._n = n
        self.count = 0
        self.motion_check = settings.planner in _TWO_STATE_MOTIONS

    def motion(self, a: ob.State, b: ob.State) -> bool:
        """Whether the straight motion from ``a`` (free) to ``b`` is free."""
        n = self._n
        free, checked = self._motion_free(np.array(a[0:n]), np.array(b[0:n]), self._step, self._margin,
                                          self._self_margin)
        self.count += checked
        return free

    def free(self, q: NDArray[np.float64]) -> bool:
        self.count += 1
        return self._checker.free(q, self._margin, self._self_margin)

    def __call__(self, state: ob.State) -> bool:
        self.count += 1
        return self._free(state[0:self._n], self._margin, self._self_margin)


def plan_joint_path(checker: ConfigurationChecker, start: NDArray[np.float64], goal: NDArray[np.float64],
                    lower: NDArray[np.float64], upper: NDArray[np.float64],
                    settings: JointPlannerSettings = JointPlannerSettings(), seed: int = 0,
                    goal_approach: ApproachTest | None = None, start_leave: ApproachTest | None = None) -> JointPath:
    """A free polyline from ``start`` to ``goal`` (module docstring).

    Args:
        checker: the configuration checker with the obstacles set.
        start: start configuration (n,) within ``[lower, upper]`` [rad].
        goal: goal configuration (n,) within ``[lower, upper]`` [rad].
        lower: lower joint bounds (n,) [rad].
        upper: upper joint bounds (n,) [rad].
        settings: planner, time limit, resolution, margins.
        seed: random seed (OMPL's sampler and the endpoint escape).
        goal_approach: the caller's test of a blocked goal's approach, beside or instead of
            the spheres' (:class:`ApproachTest`); None: the spheres' alone.
        start_leave: the same for a blocked start's segment to the free configuration.

    Raises:
        NoPathError: an endpoint is blocked with no free configuration near it, or no
            path was found in time.
    """
    began = time.perf_counter()
    n = start.size
    settings = _tolerating_endpoint_overlap(checker, start, goal, settings)
    validity = _Validity(checker, settings, n)
    rng = np.random.default_rng(seed)
    planned_start = _free_near(start, validity, checker, lower, upper, settings, rng, "start", start_leave)
    planned_goal = _free_near(goal, validity, checker, lower, upper, settings, rng, "goal", goal_approach)
    if np.linalg.norm(planned_goal - planned_start) < 1e-9:
        middle = np.array([planned_start])
    else:
        middle = _ompl_path(validity, planned_start, planned_goal, lower, upper, settings, seed)
    waypoints = [middle]
    if planned_start is not start:
        waypoints.insert(0, start[None])
    if planned_goal is not goal:
        waypoints.append(goal[None])
    return JointPath(np.vstack(waypoints), time.perf_counter() - began, validity.count,
                     planned_start is not start, planned_goal is not goal)


def _tolerating_endpoint_overlap(checker: ConfigurationChecker, start: NDArray[np.float64],
                                 goal: NDArray[np.float64], settings: JointPlannerSettings) -> JointPlannerSettings:
    """``settings`` with ``self_margin`` lowered to the endpoints' own self-overlap (module docstring)."""
    lowest = min(checker.clearances(start)[1], checker.clearances(goal)[1]) - settings.escape_slack
    if lowest >= settings.self_margin:
        return settings
    return replace(settings, self_margin=max(lowest, settings.self_margin - settings.self_tolerance))


def polyline_samples(waypoints: NDArray[np.float64], step: float) -> NDArray[np.float64]:
    """Configurations along a polyline no farther than ``step`` apart [rad], both ends included."""
    samples = [waypoints[:1]]
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        fractions = np.arange(1, count + 1)[:, None] / count
        samples.append(a + fractions * (b - a))
    return np.vstack(samples)


def _free_near(q: NDArray[np.float64], validity: _Validity, checker: ConfigurationChecker,
               lower: NDArray[np.float64], upper: NDArray[np.float64], settings: JointPlannerSettings,
               rng: np.random.Generator, name: str,
               approach: ApproachTest | None = None) -> NDArray[np.float64]:
    """``q`` itself if free, else the free sample nearest it within ``escape_radius`` (else
    ``escape_far_radius``) whose straight segment to ``q`` goes no deeper than ``q`` (and that
    ``approach`` accepts, if given), or that ``approach`` alone accepts if it replaces that
    test (module docstring)."""
    if validity.free(q):
        return q
    count = settings.escape_samples
    near, far = settings.escape_radius, max(settings.escape_radius, settings.escape_far_radius)
    rounds = [near * (np.arange(1, count + 1) / count)]
    if far > near:
        rounds.append(near + (far - near) * (np.arange(1, count + 1) / count))
    for radii in rounds:  # nearest first: radii grow
        directions = rng.normal(size=(count, q.size))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        for candidate in np.clip(q + radii[:, None] * directions, lower, upper):
            if validity.free(candidate) and _segment_accepted(checker, candidate, q, settings, approach):
                return candidate
    reason = f"{name}_in_collision"
    raise NoPathError(reason, f"the {name} is in collision on the collision spheres and no free configuration "
                              f"lies within {far} rad of it")


def _segment_accepted(checker: ConfigurationChecker, free: NDArray[np.float64], end: NDArray[np.float64],
                      settings: JointPlannerSettings, approach: ApproachTest | None) -> bool:
    """Whether the straight segment from ``free`` to the blocked ``end`` may be its approach:
    the spheres' test and ``approach``'s, or ``approach``'s alone (:class:`ApproachTest`)."""
    if approach is None:
        return _no_deeper(checker, free, end, settings)
    if approach.instead_of_spheres:
        return approach.accepts(free, end)
    return _no_deeper(checker, free, end, settings) and approach.accepts(free, end)


def approach_clear(checker: ConfigurationChecker, q: NDArray[np.float64], goal: NDArray[np.float64],
                   settings: JointPlannerSettings = JointPlannerSettings(),
                   approach: ApproachTest | None = None) -> bool:
    """Whether the straight segment from ``q`` to a blocked ``goal`` goes no deeper into the
    checker's obstacles (and into the robot) than ``goal`` does, ``escape_slack`` aside: the
    test of an escaped endpoint's segment (module docstring), with ``self_margin`` lowered
    to the endpoints' own self-overlap as a plan between them would; with the caller's
    ``approach`` test as a plan's escaped goal has it (added to the spheres' test, or in its
    place: :class:`ApproachTest`)."""
    return _segment_accepted(checker, q, goal, _tolerating_endpoint_overlap(checker, q, goal, settings), approach)


def _no_deeper(checker: ConfigurationChecker, q: NDArray[np.float64], end: NDArray[np.float64],
               settings: JointPlannerSettings) -> bool:
    """Whether the straight segment from ``q`` to ``end`` stays at clearances at least
    ``min(margin, c(end)) − escape_slack`` (obstacles and self-collision pairs alike)."""
    obstacle, itself = checker.clearances(end)
    deep = min(settings.margin, obstacle) - settings.escape_slack
    deep_self = min(settings.self_margin, itself) - settings.escape_slack
    return checker.motion_free(q, end, settings.resolution, deep, deep_self)[0]


def _planner(name: PlannerName, step: float, information: ob.SpaceInformation) -> ob.Planner:
    """OMPL's planner ``name`` for ``information``, its range set to ``step`` where it has one."""
    planner = _PLANNERS[name](information)
    if hasattr(planner, "setRange"):
        planner.setRange(step)
    return planner


def _ompl_path(validity: _Validity, start: NDArray[np.float64], goal: NDArray[np.float64],
               lower: NDArray[np.float64], upper: NDArray[np.float64], settings: JointPlannerSettings,
               seed: int) -> NDArray[np.float64]:
    extent = float(np.linalg.norm(upper - lower))
    previous_log_level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)  # reseeding after the first sample logs an error; the seed still takes
    try:
        ou.RNG.setSeed(seed % _MAX_SEED + 1)
        rate, wall = settings.check_rate, (1.0 if settings.check_rate is None else WALL_FACTOR)
        budget = None if rate is None else CheckBudget(lambda: validity.count, round(settings.time_limit * rate),
                                                       round(settings.simplify_time * rate))
        waypoints, status = solve_in_box(validity, start, goal, lower, upper, settings.resolution / extent,
                                         partial(_planner, settings.planner, settings.step), wall * settings.time_limit,
                                         wall * settings.simplify_time,
                                         validity.motion if validity.motion_check else None, budget)
    finally:
        ou.setLogLevel(previous_log_level)
    if waypoints is None:
        limit = (f"{settings.time_limit} s" if settings.check_rate is None
                 else f"{round(settings.time_limit * settings.check_rate)} checks")
        raise NoPathError("no_path", f"no collision-free joint-space path found within {limit} "
                                     f"({settings.planner}: {status}, {validity.count} configurations checked)")
    return waypoints
