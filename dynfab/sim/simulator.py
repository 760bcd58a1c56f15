"""Embedded kinematic simulator: closes the loop around a controller.

Each control period the controller is asked for an acceleration, which is held constant
over the period (zero-order hold) and integrated in ``substeps`` sub-steps of length
h = dt / substeps by a motion model (:mod:`dynfab.sim.models`): exactly for holonomic
joints (a double integrator per joint),

    q    <- q + qdot h + 1/2 qddot h^2
    qdot <- qdot + qddot h,

and along arcs for a differential-drive base, whose velocity coordinates are then
``(v, ω, arm rates)`` instead of ``q̇``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.sim.models import DoubleIntegrator, MotionModel

Controller = Callable[[float, NDArray[np.float64], NDArray[np.float64]], ArrayLike]
"""``(t [s], q, qdot) -> qddot``: commanded joint accelerations [rad/s^2 or m/s^2]."""

StopPredicate = Callable[[float, NDArray[np.float64], NDArray[np.float64]], bool]
"""``(t [s], q, qdot) -> bool``: True ends the simulation after the current step."""

ProgressCallback = Callable[[int, int], None]
"""``(step, n_steps)``: called after each completed step (1-based)."""


class ControllerError(RuntimeError):
    """The controller returned an acceleration of the wrong shape or a non-finite one."""


class RunStopped(RuntimeError):
    """Raised by a controller to end the run early (e.g. a reference that turned
    non-finite); the simulator keeps the steps so far and the message as the reason."""


@dataclass(frozen=True)
class Record:
    """A simulated run; state k holds at t[k], command k acts on [t[k], t[k] + dt).

    All arrays are read-only.

    Attributes:
        t: Times of the states, shape (N + 1,) [s]; t[0] = 0.
        q: Joint positions, shape (N + 1, n).
        qdot: Velocity coordinates, shape (N + 1, m): joint velocities (m = n), or
            ``(v, ω, arm rates)`` for a differential-drive base (m = n − 1).
        qddot: Commanded accelerations of the velocity coordinates, shape (N, m).
        solver_time: Wall time of each controller call, shape (N,) [s].
        stop_reason: Why the controller ended the run early (:class:`RunStopped`), or None.
    """

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    qdot: NDArray[np.float64]
    qddot: NDArray[np.float64]
    solver_time: NDArray[np.float64]
    stop_reason: str | None = None

    @property
    def steps(self) -> int:
        """Number N of control steps (controller calls)."""
        return int(self.qddot.shape[0])


def n_steps_for(duration: float, dt: float) -> int:
    """Number of whole control periods in ``duration``: floor(duration / dt).

    A relative slack of 1e-9 absorbs round-off, so 30 s at 0.01 s gives 3000 steps.
    """
    return math.floor(duration / dt * (1.0 + 1e-9))


def simulate(
    controller: Controller,
    q0: ArrayLike,
    qdot0: ArrayLike,
    dt: float,
    duration: float,
    *,
    substeps: int = 1,
    model: MotionModel = DoubleIntegrator(),
    stop_when: StopPredicate | None = None,
    progress: ProgressCallback | None = None,
) -> Record:
    """Run ``controller`` in closed loop with a holonomic double integrator.

    Args:
        controller: ``(t, q, qdot) -> qddot``, called once per control period.
        q0: Initial joint positions, shape (n,).
        qdot0: Initial joint velocities, shape (n,).
        dt: Control period [s] (> 0).
        duration: Simulated time [s]; the run has ``n_steps_for(duration, dt)`` steps.
        substeps: Integration sub-steps per control period (>= 1).
        model: How a command moves the robot (default: holonomic joints).
        stop_when: Optional predicate on the new state after each step; True stops the
            run early. Without it the full duration is simulated.
        progress: Optional ``(step, n_steps)`` callback after each step.

    Returns:
        The recorded run (truncated at the stopping step if ``stop_when`` fired).

    Raises:
        ValueError: On an invalid ``dt``, ``duration``, ``substeps`` or initial state.
        ControllerError: If the controller returns a wrong shape or a non-finite value.
    """
    q = np.array(q0, dtype=float)
    qdot = np.array(qdot0, dtype=float)
    _check_arguments(q, qdot, dt, duration, substeps, model)
    n_steps = n_steps_for(duration, dt)
    n = qdot.shape[0]
    qs = np.empty((n_steps + 1, q.shape[0]))
    qdots = np.empty((n_steps + 1, n))
    qddots = np.empty((n_steps, n))
    solver_time = np.empty(n_steps)
    qs[0], qdots[0] = q, qdot
    h = dt / substeps
    steps_done = n_steps
    stop_reason = None
    for k in range(n_steps):
        t = k * dt
        start = time.perf_counter()
        try:
            command = controller(t, q.copy(), qdot.copy())
        except RunStopped as stop:
            steps_done, stop_reason = k, str(stop)
            break
        solver_time[k] = time.perf_counter() - start
        qddot = _checked_command(command, n, t, k)
        for _ in range(substeps):
            q, qdot = model.step(q, qdot, qddot, h)
        qs[k + 1], qdots[k + 1], qddots[k] = q, qdot, qddot
        if progress is not None:
            progress(k + 1, n_steps)
        if stop_when is not None and stop_when((k + 1) * dt, q.copy(), qdot.copy()):
            steps_done = k + 1
            break
    return _record(dt, qs, qdots, qddots, solver_time, steps_done, stop_reason)


def _check_arguments(
    q: NDArray[np.float64], qdot: NDArray[np.float64], dt: float, duration: float, substeps: int,
    model: MotionModel,
) -> None:
    """Raise ValueError on an invalid simulation setup."""
    if q.ndim != 1 or qdot.ndim != 1 or qdot.shape[0] != model.velocity_size(q.shape[0]):
        raise ValueError(
            f"q0 and qdot0 must be vectors of {q.shape[0] if q.ndim == 1 else '?'} positions and "
            f"{model.velocity_size(q.shape[0]) if q.ndim == 1 else '?'} velocities, got {q.shape} and {qdot.shape}"
        )
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qdot))):
        raise ValueError("the initial state must be finite")
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be a positive number of seconds, got {dt}")
    if not (math.isfinite(duration) and duration >= dt):
        raise ValueError(f"duration must be at least dt = {dt} s, got {duration}")
    if substeps < 1:
        raise ValueError(f"substeps must be at least 1, got {substeps}")


def _checked_command(command: ArrayLike, n: int, t: float, step: int) -> NDArray[np.float64]:
    """Return the controller's command as a finite (n,) float array, or raise."""
    qddot = np.asarray(command, dtype=float).reshape(-1)
    if qddot.shape != (n,):
        raise ControllerError(
            f"controller returned {qddot.size} accelerations at t = {t:.4f} s (step {step}), "
            f"expected {n}"
        )
    if not np.all(np.isfinite(qddot)):
        raise ControllerError(
            f"controller returned a non-finite acceleration at t = {t:.4f} s (step {step}): "
            f"{np.array2string(qddot, precision=4, max_line_width=10_000)}"
        )
    return qddot


def _record(
    dt: float,
    qs: NDArray[np.float64],
    qdots: NDArray[np.float64],
    qddots: NDArray[np.float64],
    solver_time: NDArray[np.float64],
    steps: int,
    stop_reason: str | None = None,
) -> Record:
    """Freeze the first ``steps`` steps of the run into a read-only Record."""
    arrays = (
        np.arange(steps + 1) * dt,
        qs[: steps + 1].copy(),
        qdots[: steps + 1].copy(),
        qddots[:steps].copy(),
        solver_time[:steps].copy(),
    )
    for array in arrays:
        array.setflags(write=False)
    return Record(*arrays, stop_reason=stop_reason)
