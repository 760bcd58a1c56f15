"""One OMPL geometric planning problem in a box of R^n (OMPL 2.0's nanobind API): the
state space and its bounds, a plain Python callable as state validity checker, the
checking resolution, a planner, solve, simplify. Used by the task-space paths of
:mod:`dynfab.motion.global_planning` and the joint-space paths of
:mod:`dynfab.motion.joint_planning`.

States are allocated with ``space.allocState()`` and written and read by index
(``copyFromReals`` / ``copyToReals`` are broken in the 2.0 bindings).

The planner stops at a time limit checked in its own loop: ``solve(seconds)`` would, for
limits of 1 s or more, start a thread that checks the limit every hundredth of it and
join it at the end, up to 10 ms (40 ms for 4 s) after the path was found (measured: a
free straight problem took 6.5 ms median through it, 0.1 ms with the in-loop check).

With a :class:`CheckBudget` the search, and the simplification, also stop once they have
checked that many configurations (``checks()`` counts them), whichever comes first. A
search stopped by its budget, not its time, depends on the seed only: the same on any
machine at any load.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from ompl import base as ob
from ompl import geometric as og

__all__ = ["CheckBudget", "solve_in_box"]


@dataclass(frozen=True)
class CheckBudget:
    """Configuration checks a search and a simplification may make (besides their time).

    Attributes:
        checks: counts the configurations checked so far [-].
        search: most checks OMPL's search may make [-].
        simplify: most checks the simplifier may make [-].
    """

    checks: Callable[[], int]
    search: int
    simplify: int


def solve_in_box(validity: Callable[[ob.State], bool], start: NDArray[np.float64], goal: NDArray[np.float64],
                 low: NDArray[np.float64], high: NDArray[np.float64], resolution: float,
                 planner: Callable[[ob.SpaceInformation], ob.Planner], time_limit: float,
                 simplify_time: float | None = None,
                 motion: Callable[[ob.State, ob.State], bool] | None = None,
                 budget: CheckBudget | None = None) -> tuple[NDArray[np.float64] | None, str]:
    """Plan from ``start`` to ``goal`` (n,) within ``[low, high]``.

    Args:
        validity: OMPL's state validity callback.
        start, goal: valid states (n,).
        low, high: the bounds (n,).
        resolution: motion-check step as a fraction of the space's largest extent.
        planner: makes the planner for the space information (e.g. ``og.RRTConnect``).
        time_limit: planning time [s].
        simplify_time: time for OMPL's simplifier [s]; ``None``: until it converges.
        motion: checks a straight motion between two states, the first valid (replaces
            OMPL's checks of the states ``resolution`` apart along it); ``None``: OMPL's.
        budget: also stop the search and the simplification after that many checks;
            ``None``: time alone (``simplify_time`` ``None``: the simplifier runs until it
            converges, whatever the budget).

    Returns:
        The simplified path's states (k, n), or ``None`` without an exact solution; and
        the planner status as text.
    """
    n = start.size
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for axis in range(n):
        bounds.setLow(axis, float(low[axis]))
        bounds.setHigh(axis, float(high[axis]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    setup.setStateValidityChecker(validity)
    information = setup.getSpaceInformation()
    information.setStateValidityCheckingResolution(resolution)
    if motion is not None:
        information.setMotionValidator(_MotionValidator(information, motion))
    setup.setStartAndGoalStates(_state(space, start), _state(space, goal))
    setup.setPlanner(planner(information))
    if budget is None:
        status = setup.solve(ob.timedPlannerTerminationCondition(time_limit))
    else:
        status = setup.solve(_budgeted(time_limit, budget.checks, budget.search))
    if not setup.haveExactSolutionPath():
        return None, status.asString()
    if simplify_time is None:
        setup.simplifySolution()
    elif budget is None:
        setup.simplifySolution(simplify_time)
    else:
        setup.simplifySolution(_budgeted(simplify_time, budget.checks, budget.simplify))
    states = setup.getSolutionPath().getStates()
    return np.array([state[0:n] for state in states], dtype=float), status.asString()


class _MotionValidator(ob.MotionValidator):
    """OMPL's motion validator calling ``motion(a, b)`` (planners that ask with two states only)."""

    def __init__(self, information: ob.SpaceInformation, motion: Callable[[ob.State, ob.State], bool]) -> None:
        super().__init__(information)
        self._motion = motion

    def checkMotion(self, a: ob.State, b: ob.State) -> bool:  # noqa: N802 (OMPL's name)
        return self._motion(a, b)


def _budgeted(seconds: float, checks: Callable[[], int], most: int) -> ob.PlannerTerminationCondition:
    """Stop once ``seconds`` [s] have passed or ``most`` more configurations are checked
    (evaluated in the planner's own loop, as the time limit above)."""
    deadline, last = time.perf_counter() + seconds, checks() + most
    return ob.PlannerTerminationCondition(lambda: checks() >= last or time.perf_counter() >= deadline)


def _state(space: ob.RealVectorStateSpace, point: NDArray[np.float64]) -> ob.State:
    """An OMPL state of ``space`` holding ``point``."""
    state = space.allocState()
    for axis, value in enumerate(point):
        state[axis] = float(value)
    return state
