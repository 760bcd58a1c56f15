"""Guidance for the end of a path goal (issue 19, item 1).

A path goal's reference is followed by the scenario's own fabric, as without guidance:
the path is the task (a seam, a sweep), so no global plan replaces it. What guidance adds
is the *end*: a path that comes to rest at a known time ``T`` (a ``spline``, or an ``rrt``
path, which is a spline through the RRT's waypoints) ends at a point ``P_N``, and once
``t ≥ T`` reaching ``P_N`` is a static goal like any other. From the first control tick
with ``t ≥ T`` on, :class:`PathEndController` hands the robot to the guided controller
(:class:`~dynfab.scenario.guided_controller.GuidedController`), whose goal is ``P_N`` for
the path goal's point (its link, offset, axes and parent frame) together with the targets
of the scenario's other goals (an axis goal keeps its axis): collision-free inverse
kinematics, a joint-space plan, tracked by the dynamic fabric. If no plan can be made the
path's fabric goes on holding ``P_N``, and the metrics say why (``failure``).

The handover happens at ``T`` whether or not the hand is already within tolerance of
``P_N`` (then the plan is a short straight segment): so ``guided: true`` in the metrics
says that the end was guided, never depending on how closely the path was followed.

A path whose end comes when the run ends (or later) is not guided. Other paths are not
guided either (:func:`path_end_refusal`): a ``circle`` is periodic and a
``linear`` or ``polynomial`` path never stops, so they have no end to plan to; an
``expression`` path may stop, but whether and where cannot be known from its text. A goal
that moves has no fixed configuration to plan to: a plan to where it is now is out of date
as it is made, and following the reference is the dynamic fabric's own task (the paper's
experiment 2a).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.fabric.planner import FabricPlanner
from dynfab.motion.references import References
from dynfab.motion.spline_trajectory import SplineTrajectory
from dynfab.motion.guided_fabric import GuidanceStatus
from dynfab.scenario.controllers import Controller
from dynfab.scenario.goal_schema import ENDING_PATHS
from dynfab.scenario.schema import GoalSpec, Scenario

if TYPE_CHECKING:
    from dynfab.scenario.guided_controller import GuidedController

__all__ = ["PathEndController", "path_end_refusal", "path_end_time"]

_NO_END = {
    "circle": "a circle path is periodic: it has no end to plan to",
    "linear": "a linear path never stops: it has no end to plan to",
    "polynomial": "a polynomial path never stops: it has no end to plan to",
    "expression": "an expression path may not stop, and where it would cannot be known from its text",
}


def path_end_refusal(goal: GoalSpec, run_duration: float) -> str | None:
    """Why the end of path goal ``goal`` cannot be guided in a run of ``run_duration`` [s],
    or None if it can (module docstring): its path has no end, or ends when the run does."""
    assert goal.type == "path" and goal.trajectory is not None
    kind = str(goal.trajectory.get("type"))
    if kind not in ENDING_PATHS:
        return _NO_END[kind]
    end = float(goal.trajectory["duration"])
    return None if end < run_duration else f"the path ends at {end:g} s, not before the run does ({run_duration:g} s)"


def path_end_time(scenario: Scenario, references: References) -> float:
    """``T`` [s]: when the last of the scenario's path goals has come to rest at its end
    (every one of them a :class:`SplineTrajectory`: :func:`path_end_refusal` is None)."""
    ends = [references.goals[i] for i, goal in enumerate(scenario.goals) if goal.type == "path"]
    assert ends and all(isinstance(end, SplineTrajectory) for end in ends)
    return max(end.duration for end in ends)  # type: ignore[attr-defined]


class PathEndController:
    """The path's fabric until the path has ended, then guidance to its end (module docstring).

    Attributes:
        path: the scenario's own controller, following the path (and the fallback of
            ``guided`` if it cannot plan).
        guided: the guided controller whose goal is the path's end; it plans at its
            first call.
        end_time: ``T`` [s], when the handover happens.
    """

    def __init__(self, path: Controller, guided: GuidedController, end_time: float) -> None:
        self.path = path
        self.guided = guided
        self.end_time = end_time
        self._ended = False

    @property
    def ended(self) -> bool:
        """Whether the path's time is over and guidance has taken the robot."""
        return self._ended

    @property
    def planner(self) -> FabricPlanner:
        """The fabric in use: the path's until the handover, then the guided controller's."""
        return self.guided.planner if self._ended else self.path.planner  # type: ignore[attr-defined]

    @property
    def status(self) -> GuidanceStatus:
        """What guidance did (nothing before the handover)."""
        return self.guided.status

    @property
    def fallback(self) -> Controller | None:
        """The path's controller if guidance could not plan to the end; None otherwise."""
        return self.guided.fallback

    @property
    def fallback_count(self) -> int:
        """Non-finite fabric outputs replaced by the safe action, in both fabrics."""
        return self.path.planner.fallback_count + self.guided.inner.planner.fallback_count  # type: ignore[attr-defined]

    @property
    def recovery_times(self) -> list[float]:
        """Stall-recovery paths of the path's controller [s] (none: a path goal is not recovered)."""
        return list(getattr(self.path, "recovery_times", []))

    def __call__(self, t: float, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> NDArray[np.float64]:
        self._ended = self._ended or t >= self.end_time
        return self.guided(t, q, qdot) if self._ended else self.path(t, q, qdot)
