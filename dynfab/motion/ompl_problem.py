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
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from ompl import base as ob
from ompl import geometric as og

__all__ = ["solve_in_box"]


def solve_in_box(validity: Callable[[ob.State], bool], start: NDArray[np.float64], goal: NDArray[np.float64],
                 low: NDArray[np.float64], high: NDArray[np.float64], resolution: float,
                 planner: Callable[[ob.SpaceInformation], ob.Planner], time_limit: float,
                 simplify_time: float | None = None,
                 motion: Callable[[ob.State, ob.State], bool] | None = None) -> tuple[NDArray[np.float64] | None, str]:
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
    status = setup.solve(ob.timedPlannerTerminationCondition(time_limit))
    if not setup.haveExactSolutionPath():
        return None, status.asString()
    if simplify_time is None:
        setup.simplifySolution()
    else:
        setup.simplifySolution(simplify_time)
    states = setup.getSolutionPath().getStates()
    return np.array([state[0:n] for state in states], dtype=float), status.asString()


class _MotionValidator(ob.MotionValidator):
    """OMPL's motion validator calling ``motion(a, b)`` (planners that ask with two states only)."""

    def __init__(self, information: ob.SpaceInformation, motion: Callable[[ob.State, ob.State], bool]) -> None:
        super().__init__(information)
        self._motion = motion

    def checkMotion(self, a: ob.State, b: ob.State) -> bool:  # noqa: N802 (OMPL's name)
        return self._motion(a, b)


def _state(space: ob.RealVectorStateSpace, point: NDArray[np.float64]) -> ob.State:
    """An OMPL state of ``space`` holding ``point``."""
    state = space.allocState()
    for axis, value in enumerate(point):
        state[axis] = float(value)
    return state
