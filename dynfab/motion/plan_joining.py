"""Where a robot that moved while its plan was made joins that plan (issue 19: plans made
off the control loop arrive late)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.guidance import Plan

__all__ = ["JOIN_CANDIDATES", "JOIN_SAMPLE_PERIOD", "join_time"]

#: how finely a plan arriving late is searched for the point where the robot joins it [s]
JOIN_SAMPLE_PERIOD = 0.02
#: nearest points of a plan whose straight segment from the robot is checked when it joins [-]
JOIN_CANDIDATES = 8


def join_time(plan: Plan, q: NDArray[np.float64], checker: ConfigurationChecker, resolution: float) -> float:
    """Where on ``plan``'s clock [s] the robot at ``q`` joins it: of the reference's points
    before any approach, sampled every :data:`JOIN_SAMPLE_PERIOD`, the nearest to ``q`` whose
    straight segment from ``q`` (checked every ``resolution`` rad) touches none of
    ``checker``'s obstacles (the nearest of all if none is free; the fabric's leaves then
    keep the robot clear and the clock waits for it)."""
    end = min(plan.approach_start, plan.trajectory.duration)
    times = np.linspace(0.0, end, max(2, int(np.ceil(end / JOIN_SAMPLE_PERIOD)) + 1))
    positions = plan.trajectory.sample(times)[0]
    order = np.argsort(np.linalg.norm(positions - q, axis=1), kind="stable")
    for k in order[:JOIN_CANDIDATES]:
        if checker.motion_free(q, positions[k], resolution, 0.0, -np.inf)[0]:
            return float(times[k])
    return float(times[order[0]])
