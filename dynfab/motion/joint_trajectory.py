"""A joint-space path timed within velocity and acceleration limits (toppra).

The polyline from the global planner is resampled every ``spacing`` radians, a cubic
spline ``q(s)`` through the samples (natural end conditions) is timed with
TOPP-RA (Pham & Pham 2018, the ``toppra`` package) under

    |q̇_i(t)| ≤ v_i,   |q̈_i(t)| ≤ a_i,

starting and ending at rest, the velocity limits optionally scaled along the path by a
factor ``σ(q(s)) ∈ (0, 1]`` (a guided fabric's reference slows where the path is tight:
:meth:`~dynfab.motion.guidance.JointGuidance.speed_scale`) (TOPP-RA keeps the limits at its grid points; the result is
played slower where sampling finds them exceeded in between; its path velocities are
evaluated as toppra's ``ParametrizeConstAccel`` does, vectorised), and the result is
:class:`JointTrajectory`, the reference
``q_r(t), q̇_r(t), q̈_r(t)`` the dynamic fabric tracks (resting at the end). The spline
stays near the polyline only if the samples are dense at its corners: it is checked
against the polyline every few milliseconds of path and resampled twice as densely
while it strays more than ``deviation`` radians.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.joint_planning import polyline_samples
from dynfab.motion.trajectories import Samples, Trajectory

__all__ = ["ConstantAcceleration", "JointTrajectory", "SpeedScale", "TimingError", "time_path"]

#: ``σ``: configurations (m, n) [rad] ↦ factors (m,) in (0, 1] of the velocity limits there
SpeedScale = Callable[[NDArray[np.float64]], NDArray[np.float64]]
#: the smallest ``σ`` a timing uses (TOPP-RA needs a velocity > 0 everywhere) [-]
LEAST_SPEED_SCALE = 1e-2

if TYPE_CHECKING:
    import toppra


@functools.cache
def _toppra() -> ModuleType:
    """toppra, imported on the first timing (it takes 0.4 s, which ``dynfab run`` on a bad
    file should not pay) with its logging quieted (its debug texts are formatted only when
    enabled) and its list of installed solvers made once: every TOPP-RA instance asks for it,
    and it searches the import path for two optional packages each time (about 0.5 ms of a
    5 ms timing; the installed packages do not change while the process runs)."""
    import toppra
    import toppra.algorithm
    import toppra.constraint
    import toppra.solverwrapper

    toppra.setup_logging("WARNING")
    toppra.solverwrapper.available_solvers = functools.cache(toppra.solverwrapper.available_solvers)
    return toppra


#: a path shorter than this [rad] (a goal where the robot already is) is timed as one of this
#: length: TOPP-RA finds no timing of a path of 3e-9 rad (it did of 1e-8)
SHORTEST_PATH = 1e-7


class TimingError(RuntimeError):
    """TOPP-RA found no timing (it should not for limits > 0 and a path at rest at its ends)."""


class JointTrajectory(Trajectory):
    """A timed joint-space path; before 0 it is at its start, after ``duration`` at rest at its end.

    Attributes:
        duration: time of the motion [s].
        waypoints: the polyline it was timed along (k, n) [rad].
    """

    def __init__(self, timed: ConstantAcceleration, waypoints: NDArray[np.float64], slowdown: float = 1.0) -> None:
        """``timed`` (the timed path) played ``slowdown`` (≥ 1) times slower:
        ``q_r(t) = q(t / k)``, ``q̇_r = q̇(t / k) / k``, ``q̈_r = q̈(t / k) / k²``."""
        self._timed = timed
        self._slowdown = slowdown
        self.duration = float(timed.duration) * slowdown
        self.waypoints = waypoints
        self._end = np.asarray(timed(float(timed.duration)), dtype=float)
        self._n = waypoints.shape[1]

    @property
    def dimension(self) -> int:
        return self._n

    @property
    def end(self) -> NDArray[np.float64]:
        """The final configuration [rad]."""
        return self._end.copy()

    def _sample(self, times: np.ndarray) -> Samples:
        k = self._slowdown
        clipped = np.clip(times, 0.0, self.duration) / k
        position, velocity, acceleration = self._timed.samples(clipped)
        velocity /= k
        acceleration /= k**2
        outside = (times < 0.0) | (times > self.duration)
        velocity[outside] = 0.0
        acceleration[outside] = 0.0
        return position, velocity, acceleration


class ConstantAcceleration:
    """``q(s(t))`` and its time derivatives, with constant path acceleration ``s̈`` between
    TOPP-RA's grid points: the numbers of toppra's ``ParametrizeConstAccel``, evaluated for
    all times at once (toppra loops over them in Python, about 4 µs per time).

    Attributes:
        duration: time from ``s = s_0`` to the last grid point [s].
    """

    def __init__(self, path: toppra.SplineInterpolator, gridpoints: NDArray[np.float64],
                 path_velocities: NDArray[np.float64]) -> None:
        self._path = path
        self._s = np.asarray(gridpoints, dtype=float)
        self._v = np.asarray(path_velocities, dtype=float)
        ds = np.diff(self._s)
        self._u = 0.5 * np.diff(self._v**2) / ds
        self._t = np.concatenate([[0.0], np.cumsum(2.0 * ds / (self._v[:-1] + self._v[1:]))])
        self.duration = float(self._t[-1])

    def samples(self, times: NDArray[np.float64]) -> Samples:
        """``(q, q̇, q̈)`` at ``times`` (m,), each (m, n), sharing the path lookups."""
        s, v, u = self._path_state(np.atleast_1d(np.asarray(times, dtype=float)))
        first = self._path(s, 1)
        return self._path(s), first * v[:, None], self._path(s, 2) * (v**2)[:, None] + first * u[:, None]

    def _path_state(self, t: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                                            NDArray[np.float64]]:
        """``(s, ṡ, s̈)`` at the times ``t`` (m,)."""
        i = np.clip(np.searchsorted(self._t, t, side="right") - 1, 0, self._u.size - 1)
        dt = t - self._t[i]
        u = self._u[i]
        return self._s[i] + dt * self._v[i] + 0.5 * dt**2 * u, self._v[i] + dt * u, u

    def __call__(self, times: float | NDArray[np.float64], order: int = 0) -> NDArray[np.float64]:
        """``q``, ``q̇`` or ``q̈`` (``order`` 0, 1, 2) at ``times`` (m,) or a scalar: (m, n) or (n,)."""
        t = np.asarray(times, dtype=float)
        scalar = t.ndim == 0
        s, v, u = self._path_state(np.atleast_1d(t))
        if order == 0:
            out = self._path(s)
        elif order == 1:
            out = self._path(s, 1) * v[:, None]
        elif order == 2:
            out = self._path(s, 2) * (v**2)[:, None] + self._path(s, 1) * u[:, None]
        else:
            raise ValueError(f"order {order} is not supported (0, 1 or 2)")
        return out[0] if scalar else out


@dataclass(frozen=True)
class TimingSettings:
    """How a path is timed.

    Attributes:
        spacing: first resampling distance of the polyline [rad].
        deviation: largest distance of the spline from the polyline [rad].
        refinements: halvings of ``spacing`` tried at most [-].
        gridpoints: TOPP-RA grid points per unit of path length [-] (at least 100).
    """

    spacing: float = 0.1
    deviation: float = 0.01
    refinements: int = 3
    gridpoints: float = 20.0


def time_path(waypoints: NDArray[np.float64], velocity: NDArray[np.float64], acceleration: NDArray[np.float64],
              settings: TimingSettings = TimingSettings(), speed_scale: SpeedScale | None = None) -> JointTrajectory:
    """The time-optimal timing (within the limits) of a spline near ``waypoints`` (module docstring).

    Args:
        waypoints: the polyline (k, n) [rad], k ≥ 1.
        velocity: velocity limits (n,) [rad/s].
        acceleration: acceleration limits (n,) [rad/s²].
        settings: resampling and deviation.
        speed_scale: ``σ``, the factor of ``velocity`` at the path's configurations (module
            docstring); None: 1 everywhere.

    Raises:
        TimingError: if TOPP-RA fails.
    """
    waypoints = np.atleast_2d(np.asarray(waypoints, dtype=float))
    if len(waypoints) == 1 or _length(waypoints) < SHORTEST_PATH:   # TOPP-RA fails below about 1e-8 rad
        step = SHORTEST_PATH / np.sqrt(waypoints.shape[1])
        waypoints = np.vstack([waypoints[:1], waypoints[:1] + step])
    spacing = settings.spacing
    for _ in range(settings.refinements + 1):
        samples = polyline_samples(waypoints, spacing)
        path = _spline(samples)
        if _deviation(path, waypoints) <= settings.deviation:
            break
        spacing /= 2
    timed = _timed(path, velocity, acceleration, settings, speed_scale)
    return JointTrajectory(timed, waypoints, _slowdown(timed, velocity, acceleration))


def _length(waypoints: NDArray[np.float64]) -> float:
    return float(np.linalg.norm(np.diff(waypoints, axis=0), axis=1).sum())


def _spline(samples: NDArray[np.float64]) -> toppra.SplineInterpolator:
    """The clamped cubic spline through ``samples`` over their normalised chord length."""
    chords = np.linalg.norm(np.diff(samples, axis=0), axis=1)
    keep = np.concatenate([[True], chords > 1e-12])
    samples, chords = samples[keep], np.concatenate([[0.0], chords])[keep]
    s = np.cumsum(chords)
    return _toppra().SplineInterpolator(s / s[-1] * max(s[-1], 1e-9), samples, bc_type="natural")


def _deviation(path: toppra.SplineInterpolator, waypoints: NDArray[np.float64]) -> float:
    """Largest distance [rad] of the spline (sampled finely) from the polyline."""
    low, high = path.path_interval
    points = path(np.linspace(low, high, max(200, int(200 * (high - low)))))
    a, b = waypoints[:-1], waypoints[1:]
    ab = b - a
    lengths = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
    fraction = np.clip((points @ ab.T - np.einsum("ij,ij->i", a, ab)) / lengths, 0.0, 1.0)  # (P, S)
    nearest = a[None] + fraction[:, :, None] * ab[None]
    return float(np.sqrt(np.min(np.sum((nearest - points[:, None]) ** 2, axis=2), axis=1)).max())


def _slowdown(timed: ConstantAcceleration, velocity: NDArray[np.float64], acceleration: NDArray[np.float64]) -> float:
    """How much slower ``timed`` must play to keep its limits between TOPP-RA's grid points
    too (it enforces them at the points): ``k = max(1, max |q̇|/v, √(max |q̈|/a))`` over a
    fine sampling."""
    times = np.linspace(0.0, float(timed.duration), 2001)
    speed = float(np.max(np.abs(np.atleast_2d(timed(times, 1))) / velocity))
    push = float(np.max(np.abs(np.atleast_2d(timed(times, 2))) / acceleration))
    return max(1.0, speed, float(np.sqrt(push)))


def _timed(path: toppra.SplineInterpolator, velocity: NDArray[np.float64], acceleration: NDArray[np.float64],
           settings: TimingSettings, speed_scale: SpeedScale | None = None) -> ConstantAcceleration:
    low, high = path.path_interval
    count = max(100, int(settings.gridpoints * (high - low)))
    gridpoints = np.linspace(low, high, count + 1)
    algorithm = _toppra().algorithm
    constraints = list(_constraints(tuple(map(float, velocity)), tuple(map(float, acceleration))))
    if speed_scale is not None:
        constraints[0] = _scaled_velocity(velocity, gridpoints, speed_scale(path(gridpoints)))
    instance = algorithm.TOPPRA(constraints, path, gridpoints=gridpoints,
                                solver_wrapper="seidel")   # the one toppra picks for linear constraints
    instance.compute_parameterization(0.0, 0.0)
    data = instance.problem_data
    if data.return_code != algorithm.ParameterizationReturnCode.Ok:
        raise TimingError("TOPP-RA found no timing of the planned path within the limits")
    return ConstantAcceleration(path, data.gridpoints, data.sd_vec)


def _scaled_velocity(velocity: NDArray[np.float64], gridpoints: NDArray[np.float64],
                     scale: NDArray[np.float64]) -> object:
    """TOPP-RA's joint velocity constraint ``|q̇_i| ≤ σ(s) v_i`` with ``σ`` given at the grid
    points (at least :data:`LEAST_SPEED_SCALE`, at most 1; linear between them)."""
    factors = np.clip(np.asarray(scale, dtype=float), LEAST_SPEED_SCALE, 1.0)
    bounds = np.column_stack([-velocity, velocity])
    return _toppra().constraint.JointVelocityConstraintVarying(
        lambda s: bounds * float(np.interp(s, gridpoints, factors)))


@functools.lru_cache(maxsize=16)
def _constraints(velocity: tuple[float, ...], acceleration: tuple[float, ...]) -> tuple[object, object]:
    """TOPP-RA's joint velocity and acceleration constraints for these limits, made once:
    they hold no path, and toppra formats every limit into a text as it makes them (about
    1.5 ms for 7 joints, a tenth of a timing)."""
    constraint = _toppra().constraint
    v, a = np.array(velocity), np.array(acceleration)
    return (constraint.JointVelocityConstraint(np.column_stack([-v, v])),
            constraint.JointAccelerationConstraint(np.column_stack([-a, a]),
                                                   discretization_scheme=constraint.DiscretizationType.Interpolation))
