"""Timed joint-space references played one after the other: a plan's way to the free
configuration near a grasp goal, then its slow approach to the goal (global guidance).

With phases of durations ``T_1, …, T_m`` (each at rest at both ends) starting at
``t_j = T_1 + … + T_{j−1}``, the reference at ``t ∈ [t_j, t_j + T_j)`` is phase ``j``'s at
``t − t_j``; before 0 it is the first phase's start, after the last end at rest there.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.joint_trajectory import JointTrajectory
from dynfab.motion.trajectories import Samples, Trajectory

__all__ = ["PhasedTrajectory"]


class PhasedTrajectory(Trajectory):
    """Joint trajectories in sequence (module docstring).

    Attributes:
        phases: the trajectories, each starting where the previous one ends.
        starts: the time each phase starts at [s].
        duration: the time of all of them [s].
        waypoints: the polylines they were timed along, joined (k, n) [rad].
    """

    def __init__(self, phases: Sequence[JointTrajectory]) -> None:
        if not phases:
            raise ValueError("PhasedTrajectory needs at least one phase")
        self.phases = tuple(phases)
        durations = np.array([phase.duration for phase in self.phases])
        self.starts = np.concatenate([[0.0], np.cumsum(durations)[:-1]])
        self.duration = float(durations.sum())
        self.waypoints = np.vstack([self.phases[0].waypoints[:1]] + [phase.waypoints[1:] for phase in self.phases])

    @property
    def dimension(self) -> int:
        return self.phases[0].dimension

    @property
    def end(self) -> NDArray[np.float64]:
        """The final configuration [rad]."""
        return self.phases[-1].end

    def _sample(self, times: np.ndarray) -> Samples:
        index = np.clip(np.searchsorted(self.starts, times, side="right") - 1, 0, len(self.phases) - 1)
        n = self.dimension
        position, velocity, acceleration = (np.zeros((times.size, n)) for _ in range(3))
        for j, phase in enumerate(self.phases):
            rows = index == j
            if rows.any():
                p, v, a = phase.sample(times[rows] - self.starts[j])
                position[rows], velocity[rows], acceleration[rows] = p, v, a
        return position, velocity, acceleration
