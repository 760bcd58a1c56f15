"""Stall recovery: when a fabric stops making progress toward a static position goal, plan
a global path for the goal point and lead the fabric along it.

Fabrics are local: a robot can settle in front of obstacles (a differential-drive base
cannot sidestep) and never reach a goal that a way leads to. Recovery works like the
paper's Experiment 2b, only triggered automatically:

1. **Stall.** Each tick the distance ``d(t)`` of the goal point to the goal is compared
   with the best distance so far; the run has stalled when, with the goal not reached,
   ``d`` has not come

       Δ = min(f · min(d₀, reach), Δ_max)

   below its best for ``window`` seconds, with ``d₀`` the goal's initial distance and
   ``reach`` the robot's (the farthest its goal link gets from the root; unbounded on a
   mobile base), so that the test means the same for a 30 cm arm and a 1 m one (defaults
   ``f = 0.25``, ``Δ_max = 0.2 m``, 3 s: a robot still moving toward its goal improves
   that easily, one stuck, circling or oscillating does not).
2. **Path.** OMPL's RRT-Connect (:func:`dynfab.motion.global_planning.plan_path`) plans a
   polyline for the goal point, in the goal's coordinates, from where it is to the goal,
   around the scenario's spheres where they are now (moving ones as snapshots), keeping
   ``footprint + clearance`` from each: the footprint is the robot body's reach around
   the goal point (for a mobile base, its whole outline; for an arm, the goal link's
   spheres). A sphere the start or goal point is already closer to is shrunk just enough
   to let the path start and end.
3. **Follow.** The fabric's goal becomes a carrot on the path, ``lookahead`` ahead of the
   goal point's projection on it; the goal point's projection only moves forward. When the
   carrot reaches the path's end, the original goal is back. A new stall while following
   plans again with the next seed, up to ``attempts`` paths in a run.

Only static position goals are recovered (a path goal already has a reference to follow;
joint and orientation goals have no point to plan for).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from dynfab.motion.global_planning import GlobalPlanningError, plan_path

#: ``(start, goal, spheres, margin, seed) -> waypoints (k, d)``; raises GlobalPlanningError.
PathPlanner = Callable[[np.ndarray, np.ndarray, list[tuple[np.ndarray, float]], float, int], np.ndarray]


@dataclass(frozen=True)
class StallRecovery:
    """When a run counts as stalled and how the path is followed.

    Attributes:
        window: time over which progress is measured [s].
        progress_fraction: ``f``, the progress expected within ``window`` as a fraction of
            the smaller of the goal's initial distance and the robot's reach [-].
        max_progress: ``Δ_max``, the most progress ever expected within ``window`` [m].
        clearance: kept between the footprint and each sphere by the path [m].
        attempts: global paths planned at most in one run [-].
    """

    window: float = 3.0
    progress_fraction: float = 0.25
    max_progress: float = 0.2
    clearance: float = 0.15
    attempts: int = 3

    def progress(self, initial_distance: float, reach: float) -> float:
        """``Δ`` of the module docstring [m]."""
        return min(self.progress_fraction * min(initial_distance, reach), self.max_progress)


class StallMonitor:
    """Tells whether a distance stopped improving (module docstring)."""

    def __init__(self, recovery: StallRecovery, reach: float = np.inf) -> None:
        """``reach``: the robot's [m] (``inf`` on a mobile base)."""
        self._recovery = recovery
        self._reach = reach
        self._needed: float | None = None
        self._best = np.inf
        self._best_time = 0.0

    def reset(self) -> None:
        """Forget the best distance (after a path was planned, progress is measured anew)."""
        self._best = np.inf

    def stalled(self, t: float, distance: float) -> bool:
        """Record the distance at ``t`` [s]; True if it has not come ``Δ`` (set by the first
        distance recorded) below its best for ``window`` seconds."""
        if self._needed is None:
            self._needed = self._recovery.progress(distance, self._reach)
        if distance < self._best - self._needed or not np.isfinite(self._best):
            self._best, self._best_time = distance, t
        return t - self._best_time >= self._recovery.window


class PathFollower:
    """A carrot ``lookahead`` ahead along a polyline, moving forward only.

    Attributes:
        waypoints: the polyline (k, d) [m].
        lookahead: arc length between the projection and the carrot [m].
    """

    def __init__(self, waypoints: np.ndarray, lookahead: float) -> None:
        self.waypoints = np.asarray(waypoints, dtype=float)
        self.lookahead = lookahead
        segments = np.diff(self.waypoints, axis=0)
        self._lengths = np.linalg.norm(segments, axis=1)
        self._arc = np.concatenate([[0.0], np.cumsum(self._lengths)])
        self._progress = 0.0

    @property
    def length(self) -> float:
        """Total arc length [m]."""
        return float(self._arc[-1])

    def carrot(self, point: np.ndarray) -> tuple[np.ndarray, bool]:
        """The carrot for the goal point at ``point``, and whether it is the path's end."""
        self._progress = max(self._progress, self._projection(point))
        target = min(self._progress + self.lookahead, self.length)
        return self._at(target), target >= self.length

    def _projection(self, point: np.ndarray) -> float:
        best, best_distance = 0.0, np.inf
        for k, length in enumerate(self._lengths):
            start = self.waypoints[k]
            direction = self.waypoints[k + 1] - start
            u = 0.0 if length == 0 else float(np.clip(np.dot(point - start, direction) / length**2, 0.0, 1.0))
            distance = float(np.linalg.norm(start + u * direction - point))
            if distance < best_distance:
                best, best_distance = self._arc[k] + u * length, distance
        return best

    def _at(self, arc: float) -> np.ndarray:
        k = int(np.clip(np.searchsorted(self._arc, arc, side="right") - 1, 0, len(self._lengths) - 1))
        length = self._lengths[k]
        u = 0.0 if length == 0 else (arc - self._arc[k]) / length
        return self.waypoints[k] + min(u, 1.0) * (self.waypoints[k + 1] - self.waypoints[k])


def rrt_path_planner(bounds_margin: float = 1.0, time_limit: float = 1.0) -> PathPlanner:
    """A :data:`PathPlanner` on OMPL's RRT-Connect in the box around start, goal and spheres
    grown by ``bounds_margin`` [m]; spheres that the start or goal point already violate
    are shrunk to let the path start and end."""

    def plan(start: np.ndarray, goal: np.ndarray, spheres: list[tuple[np.ndarray, float]],
             margin: float, seed: int) -> np.ndarray:
        fitted = []
        for centre, radius in spheres:
            room = min(float(np.linalg.norm(start - centre)), float(np.linalg.norm(goal - centre))) - margin - 1e-3
            fitted.append((centre, min(radius, room)))
        fitted = [(c, r) for c, r in fitted if r > 0]
        points = np.vstack([start, goal] + [c for c, _ in fitted])
        extent = max((r for _, r in fitted), default=0.0) + margin + bounds_margin
        return plan_path(start, goal, fitted, bounds_low=points.min(axis=0) - extent,
                         bounds_high=points.max(axis=0) + extent, margin=margin, seed=seed, time_limit=time_limit)

    return plan


__all__ = ["GlobalPlanningError", "PathFollower", "PathPlanner", "StallMonitor", "StallRecovery",
           "rrt_path_planner"]
