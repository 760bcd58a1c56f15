"""The goal and obstacle references of a run, as trajectories over time."""

from __future__ import annotations

from dataclasses import dataclass

from dynfab.motion.trajectories import Trajectory


@dataclass(frozen=True)
class References:
    """Where the goals and obstacles of a scenario are over time.

    Attributes:
        goals: per goal, the trajectory of its first task in the goal's coordinates (a
            static goal is a trajectory at rest): the point of a position, path or pose
            goal, the configuration of a joint goal, the direction of an axis goal.
        obstacles: per obstacle, its centre's trajectory, 3-D.
        orientations: per goal, the orientation reference of a pose or axis goal (stacked
            unit target directions: the columns of the target rotation, or the axis
            direction), None for the other goals; empty when no goal has one.
    """

    goals: tuple[Trajectory, ...]
    obstacles: tuple[Trajectory, ...]
    orientations: tuple[Trajectory | None, ...] = ()

    def orientation(self, index: int) -> Trajectory | None:
        """The orientation reference of goal ``index`` (None if it has none)."""
        return self.orientations[index] if index < len(self.orientations) else None
