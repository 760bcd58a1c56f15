"""The values global guidance hands out (:mod:`dynfab.motion.guidance`): a joint-space goal,
a timed plan, and the error of a plan that cannot be made."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.inverse_kinematics import AxisTarget, PointTarget
from dynfab.motion.joint_trajectory import JointTrajectory
from dynfab.motion.phased_trajectory import PhasedTrajectory

__all__ = ["GoalTargets", "GuidanceError", "JointTarget", "Plan"]


@dataclass(frozen=True)
class JointTarget:
    """A goal configuration (n,) [rad or m], reached within ``tolerance`` of it (the
    Euclidean norm over the joints; 0: exactly; :meth:`JointGuidance.plan` may then plan to
    a roomier configuration inside half of it)."""

    q: tuple[float, ...]
    tolerance: float = 0.0


GoalTargets = JointTarget | Sequence[PointTarget | AxisTarget]


class GuidanceError(RuntimeError):
    """No plan: ``reason`` is ``goal_outside_limits``, ``no_ik_solution``,
    ``start_in_collision``, ``goal_in_collision``, ``no_path``, ``timing`` or
    ``mesh_escape_budget`` (:mod:`dynfab.motion.mesh_escape_plan`)."""

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
        goal_moved: ``goal`` reaches a target moved inside the goal's tolerance, not the
            goal itself (:mod:`dynfab.motion.goal_region`).
        departure: joint-space length of the first segment, a blocked start's way out, which
            the planner checked on the robot's meshes only against going deeper than the
            start (:func:`~dynfab.motion.mesh_goal_check.endpoint_tests`); 0 if the start
            was free [rad].
    """

    trajectory: JointTrajectory | PhasedTrajectory
    goal: NDArray[np.float64]
    time_s: float
    checks: int
    approach: float = 0.0
    approach_start: float = 0.0
    goal_moved: bool = False
    departure: float = 0.0
