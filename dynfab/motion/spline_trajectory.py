"""A reference through waypoints: a C2 cubic spline from rest to rest (SciPy's
``CubicSpline``, clamped), as scenario ``trajectory: {type: spline}`` and the RRT paths of
Experiment 2b use it."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from dynfab.motion.trajectories import Samples, Trajectory, derived_field
from dynfab.motion.trajectory_values import TrajectoryError, numbers, point, positive, sequence


@dataclass(frozen=True)
class SplineTrajectory(Trajectory):
    """A C2 cubic spline through waypoints, from rest at t = 0 to rest at t = T.

    Waypoint Pᵢ is reached at ``tᵢ = T sᵢ / s_N``, where ``sᵢ`` is the chord length
    Σⱼ₌₁ⁱ |Pⱼ − Pⱼ₋₁| [m], so the speed is roughly uniform between the ends. The spline
    is clamped (``ẋ̃ = 0`` at t = 0 and t = T); before t = 0 it holds P₀, from t = T on
    it holds P_N, both with ``ẋ̃ = ẍ̃ = 0``. It is C2 on [0, T); a clamped cubic cannot
    also fix the end accelerations, so ``ẍ̃`` jumps to 0 at t = T (and from 0 at t = 0).

    Attributes:
        waypoints: P₀ ... P_N [m], at least 2, each of 2 or 3 numbers (all alike);
            consecutive waypoints must differ.
        duration: T [s] > 0, the time the last waypoint is reached.
    """

    waypoints: Sequence[Sequence[float]]
    duration: float
    _spline: CubicSpline = derived_field()

    def __post_init__(self) -> None:
        items = sequence(self.waypoints, "waypoints")
        if len(items) < 2:
            raise TrajectoryError("waypoints", f"expected at least 2 waypoints, got {len(items)}")
        first = point(items[0], "waypoints[0]")
        points = [first]
        for i, item in enumerate(items[1:], 1):
            points.append(numbers(item, f"waypoints[{i}]", len(first)))
        duration = positive(self.duration, "duration")
        chords = np.linalg.norm(np.diff(np.array(points), axis=0), axis=1)
        for i, chord in enumerate(chords, 1):
            if chord == 0.0:
                problem = f"equals waypoints[{i - 1}] (consecutive waypoints must differ)"
                raise TrajectoryError(f"waypoints[{i}]", problem)
        knots = duration * np.concatenate([[0.0], np.cumsum(chords)]) / np.sum(chords)
        knots[-1] = duration
        object.__setattr__(self, "waypoints", tuple(tuple(point.tolist()) for point in points))
        object.__setattr__(self, "duration", duration)
        spline = CubicSpline(knots, np.array(points), bc_type="clamped", axis=0)
        object.__setattr__(self, "_spline", spline)

    @property
    def dimension(self) -> int:
        return len(self.waypoints[0])

    @property
    def knot_times(self) -> np.ndarray:
        """The times ``tᵢ`` at which the waypoints are reached [s] (segment ends)."""
        return np.array(self._spline.x)

    def _sample(self, times: np.ndarray) -> Samples:
        clamped = np.clip(times, 0.0, self.duration)
        moving = ((times >= 0.0) & (times < self.duration))[:, None]
        position = self._spline(clamped)
        velocity = np.where(moving, self._spline(clamped, 1), 0.0)
        acceleration = np.where(moving, self._spline(clamped, 2), 0.0)
        return position, velocity, acceleration
