"""What global guidance did so far in a run: :class:`GuidanceStatus`, kept by
:class:`~dynfab.motion.guided_fabric.GuidedFabric` and reported in a run's metrics."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["GuidanceStatus"]


@dataclass(frozen=True)
class GuidanceStatus:
    """What guidance did so far.

    Attributes:
        guided: a plan was made and is being followed.
        plans: plans made (the first included; an attempt that found none is not one) [-].
        failed_plans: plans asked for that found none (the first or a replan) [-].
        plan_time_ms: wall time of the first plan [ms]; None before it.
        plan_times_ms: wall time of every plan [ms].
        replans_blocked: replans because the reference ahead was blocked [-].
        replans_stalled: replans because progress stalled [-].
        refuges: plans to a refuge from what moves through the goal (:mod:`dynfab.motion.making_way`) [-].
        goal_moved: a plan followed so far reaches a target moved inside the goal's
            tolerance, not the goal itself (:attr:`~dynfab.motion.plan_values.Plan.goal_moved`;
            a replan to the same goal configuration does not say it again).
        failure: why the last plan failed (:class:`~dynfab.motion.guidance.GuidanceError`
            reasons); None if it did not.
    """

    guided: bool = False
    plans: int = 0
    failed_plans: int = 0
    plan_time_ms: float | None = None
    plan_times_ms: tuple[float, ...] = ()
    replans_blocked: int = 0
    replans_stalled: int = 0
    refuges: int = 0
    goal_moved: bool = False
    failure: str | None = None
