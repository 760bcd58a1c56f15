"""The goal and obstacle references of a run, as trajectories over time."""

from __future__ import annotations

from dataclasses import dataclass

from dynfab.motion.trajectories import Trajectory


@dataclass(frozen=True)
class References:
    """Where the goals and obstacles of a scenario are over time.

    Attributes:
        goals: per goal, its trajectory in the goal's coordinates (a static goal is a
            trajectory at rest).
        obstacles: per obstacle, its centre's trajectory, 3-D.
    """

    goals: tuple[Trajectory, ...]
    obstacles: tuple[Trajectory, ...]
