"""Check a reference for non-finite values over a whole run, before the run starts.

An expression such as ``1/(t - 0.5)``, ``log(1 - t)`` or ``exp(1000 t)``, a polynomial or
linear motion that overflows, or a spline with absurd waypoints is finite at ``t = 0`` and
turns NaN or infinite later. Each reference is sampled at every control step (when there
are at most :data:`MAX_STEP_SAMPLES`), on a uniform grid of :data:`GRID_SAMPLES` times,
at the ends of every spline segment and at both ends of the run; the first time any
position, velocity or acceleration is not finite is reported.
"""

from __future__ import annotations

import numpy as np

from dynfab.motion.spline_trajectory import SplineTrajectory
from dynfab.motion.trajectories import Trajectory

#: control steps sampled one by one up to this many (beyond, the uniform grid alone) [-]
MAX_STEP_SAMPLES = 1_000_000
#: times of the uniform grid over the run [-]
GRID_SAMPLES = 20_001
#: times evaluated per call, so that a long run never allocates all samples at once [-]
CHUNK = 50_000


def check_times(trajectory: Trajectory, duration: float, dt: float) -> np.ndarray:
    """The sorted times [s] at which :func:`first_non_finite` evaluates ``trajectory``."""
    parts = [np.linspace(0.0, duration, GRID_SAMPLES)]
    steps = duration / dt
    if steps <= MAX_STEP_SAMPLES:
        parts.append(np.arange(int(steps) + 1) * dt)
    if isinstance(trajectory, SplineTrajectory):
        parts.append(trajectory.knot_times)
    times = np.unique(np.concatenate(parts))
    return times[(times >= 0.0) & (times <= duration)]


def first_non_finite(trajectory: Trajectory, duration: float, dt: float) -> tuple[float, str] | None:
    """The first checked time [s] at which ``trajectory`` is not finite, and which of
    ``position``, ``velocity``, ``acceleration`` is not; None if it is finite throughout.

    Overflow inside the trajectory's own arithmetic counts as not finite.
    """
    times = check_times(trajectory, duration, dt)
    for start in range(0, times.size, CHUNK):
        chunk = times[start:start + CHUNK]
        with np.errstate(all="ignore"):
            try:
                samples = trajectory.sample(chunk)
            except (OverflowError, FloatingPointError, ZeroDivisionError):
                return _first_failing_time(trajectory, chunk)
        bad = None
        for name, values in zip(("position", "velocity", "acceleration"), samples):
            rows = np.flatnonzero(~np.isfinite(values).all(axis=1))
            if rows.size and (bad is None or rows[0] < bad[0]):
                bad = (int(rows[0]), name)
        if bad is not None:
            return float(chunk[bad[0]]), bad[1]
    return None


def _first_failing_time(trajectory: Trajectory, times: np.ndarray) -> tuple[float, str]:
    """One time at a time, for a trajectory whose arithmetic raised on a whole chunk."""
    for t in times:
        try:
            with np.errstate(all="ignore"):
                point = trajectory.evaluate(float(t))
        except (OverflowError, FloatingPointError, ZeroDivisionError):
            return float(t), "position"
        for name in ("position", "velocity", "acceleration"):
            if not np.isfinite(getattr(point, name)).all():
                return float(t), name
    return float(times[-1]), "position"
