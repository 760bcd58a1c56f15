"""MuJoCo in the loop: the planner at its control period, the joint controllers at 1 kHz.

Every control period ``dt`` the planner (``(t, q, u) -> u̇``, as for
:func:`dynfab.sim.simulate`) sees the robot's state, possibly ``delay`` seconds old and
with Gaussian ``noise`` of standard deviation σ on every coordinate of q [rad or m] and of
u [rad/s or m/s] (seeded). Between its calls, each physics step (h = 1 ms) runs what a
real robot runs: a :class:`~dynfab.sim.control_interfaces.SetpointIntegrator` (reset to
the initial state, then holding each q̈ of the planner, stopping at the joint limits, and
reset again when the tracking error exceeds :data:`RESYNC_ERROR`),
the ``control`` mode's interface
(:func:`~dynfab.sim.control_interfaces.interface_for`), whose command the joint
controllers of :mod:`dynfab.sim.mujoco_drives` turn into torques. A differential-drive
base follows (v, ω) integrated in the same way from the planner's (v̇, ω̇), through its
wheels' velocity actuators, whatever the mode; the integrated (v, ω) stops at the base's
velocity limits, as a drive refuses set-points beyond them (while the wheels lag behind
the set-point, e.g. at their torque limit, it would otherwise wind up past the limits). Moving obstacles (mocap
bodies) are placed every physics step.

A non-finite or wrongly sized command, or a state that is no longer finite, exceeds
:data:`DIVERGED_SPEED` or makes MuJoCo reset it (bad accelerations), ends the run early:
the record holds the steps so far and ``stop_reason`` says why, in one line.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.sim.control_interfaces import Setpoint, SetpointIntegrator, interface_for
from dynfab.sim.mujoco_drives import JointDrive, MujocoInverseDynamics
from dynfab.sim.mujoco_model import MujocoScene
from dynfab.sim.mujoco_state import RobotState
from dynfab.sim.simulator import Controller, ProgressCallback, Record, RunStopped, StopPredicate, n_steps_for

__all__ = ["CONTROL_MODES", "DIVERGED_SPEED", "RESYNC_ERROR", "Contact", "MujocoRun", "simulate_mujoco"]

#: Control modes of the joints.
CONTROL_MODES: tuple[str, ...] = ("torque", "velocity", "position")
#: A generalized speed above this [rad/s or m/s] counts as a diverged simulation.
DIVERGED_SPEED = 1e3
#: Tracking error [rad or m] beyond which the set-points restart from the measured state at
#: the next planner tick (the robot was held off its path, e.g. by a contact): a joint
#: controller that kept pulling towards the old path would snap back when released.
RESYNC_ERROR = 0.05

#: MuJoCo's warnings of a state it had to reset, and what they mean.
_INSTABILITIES = ((mujoco.mjtWarning.mjWARN_BADQPOS, "non-finite or huge positions"),
                  (mujoco.mjtWarning.mjWARN_BADQVEL, "non-finite or huge velocities"),
                  (mujoco.mjtWarning.mjWARN_BADQACC, "non-finite or huge accelerations"),
                  (mujoco.mjtWarning.mjWARN_BADCTRL, "non-finite or huge controls"))

ObstacleCentres = Callable[[NDArray[np.float64]], NDArray[np.float64]]
"""``times (T,) [s] -> centres (T, m, 3) [m]`` of the scenario's obstacles."""

StepObserver = Callable[[float, mujoco.MjData], None]
"""``(t [s], data)``: called after each control period (e.g. to render a video frame)."""


@dataclass(frozen=True)
class Contact:
    """A contact that began: a robot body touched an obstacle or a non-adjacent body.

    Attributes:
        time: When it began [s].
        body: The robot link.
        other: The obstacle (``obstacles[k]``) or the other robot link.
    """

    time: float
    body: str
    other: str


@dataclass(frozen=True)
class MujocoRun:
    """A run under MuJoCo.

    Attributes:
        record: States at the control period, commands and solver times (as
            :func:`dynfab.sim.simulate` records them).
        contacts: Every contact that began, in time order.
        stop_reason: Why the run ended early (one line), or None.
    """

    record: Record
    contacts: tuple[Contact, ...]
    stop_reason: str | None


def simulate_mujoco(controller: Controller, scene: MujocoScene, q0: ArrayLike, qdot0: ArrayLike, dt: float,
                    duration: float, *, control: str = "torque", delay: float = 0.0, noise: float = 0.0,
                    seed: int = 0, obstacle_centres: ObstacleCentres | None = None,
                    stop_when: StopPredicate | None = None, progress: ProgressCallback | None = None,
                    observer: StepObserver | None = None) -> MujocoRun:
    """Run ``controller`` in closed loop with the robot of ``scene`` (module doc).

    Args:
        controller: ``(t, q, u) -> u̇``, called once per control period.
        scene: The compiled robot and obstacles.
        q0: Initial configuration, shape (n,).
        qdot0: Initial velocity coordinates (q̇, or ``(v, ω, arm)`` on a base).
        dt: Control period [s], a whole number of physics steps.
        duration: Simulated time [s].
        control: ``torque``, ``velocity`` or ``position``.
        delay: Age of the state the planner sees [s] (>= 0; rounded to physics steps).
        noise: Standard deviation σ of the Gaussian noise on what the planner sees
            [rad or m for q, rad/s or m/s for u] (>= 0).
        seed: Seed of the noise.
        obstacle_centres: Where the obstacles are over time (moving ones are updated).
        stop_when: Optional predicate on the state after each period; True stops.
        progress: Optional ``(step, n_steps)`` callback.
        observer: Optional ``(t, data)`` callback after each period (and at t = 0).

    Raises:
        ValueError: An invalid ``dt``, ``duration``, ``control``, ``delay`` or ``noise``.
    """
    h = scene.model.opt.timestep
    substeps = round(dt / h)
    if not (math.isfinite(dt) and substeps >= 1 and abs(substeps * h - dt) <= 1e-9 * max(dt, 1.0)):
        raise ValueError(f"dt must be a whole number of MuJoCo steps of {h:g} s, got {dt}")
    if not (math.isfinite(duration) and duration >= dt):
        raise ValueError(f"duration must be at least dt = {dt} s, got {duration}")
    for name, value in (("delay", delay), ("noise", noise)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{name} must be a finite number >= 0, got {value}")
    loop = _Loop(scene, control, h, round(delay / h), noise, seed, obstacle_centres)
    printer = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda text: None)  # the loop reports instabilities itself, in one line
    try:
        return loop.run(controller, np.array(q0, dtype=float), np.array(qdot0, dtype=float), dt, substeps,
                        n_steps_for(duration, dt), stop_when, progress, observer)
    finally:
        mujoco.set_mju_user_warning(printer)


class _Loop:
    """The state of one run."""

    def __init__(self, scene: MujocoScene, control: str, h: float, delay_steps: int, noise: float, seed: int,
                 obstacle_centres: ObstacleCentres | None) -> None:
        if control not in CONTROL_MODES:
            raise ValueError(f"control must be one of {', '.join(CONTROL_MODES)}, got {control!r}")
        self.scene = scene
        self.model = scene.model
        self.data = mujoco.MjData(scene.model)
        self.h = h
        self.state = RobotState(scene, self.data)
        self.setpoints = SetpointIntegrator(h, scene.lower, scene.upper)
        self.setpoint: Setpoint | None = None
        self.interface = interface_for(control, MujocoInverseDynamics(scene, self.data), scene.effort)
        self.drive = JointDrive(scene, self.data, control, h)
        self.history: deque[tuple[NDArray[np.float64], NDArray[np.float64]]] = deque(maxlen=delay_steps + 1)
        self.noise = noise
        self.rng = np.random.default_rng(seed)
        self.obstacle_centres = obstacle_centres
        self.kinds = _geom_kinds(scene)
        self.touching: set[tuple[int, int]] = set()
        self.contacts: list[Contact] = []

    def run(self, controller: Controller, q0: NDArray[np.float64], u0: NDArray[np.float64], dt: float,
            substeps: int, n_steps: int, stop_when: StopPredicate | None, progress: ProgressCallback | None,
            observer: StepObserver | None) -> MujocoRun:
        self.state.write(q0, u0)
        self._place_obstacles(np.zeros(1))
        mujoco.mj_forward(self.model, self.data)
        q, u = self.state.read()
        self.history.append((q, u))
        base = self.scene.base_qpos is not None
        self.setpoints.reset(q[3:] if base else q, u[2:] if base else u)
        self.base_velocity = u[:2].copy() if base else np.zeros(0)
        qs, us = [q], [u]
        commands: list[NDArray[np.float64]] = []
        solver_time: list[float] = []
        reason = None
        if observer is not None:
            observer(0.0, self.data)
        for k in range(n_steps):
            t = k * dt
            seen_q, seen_u = self._observation()
            start = time.perf_counter()
            try:
                command = np.asarray(controller(t, seen_q, seen_u), dtype=float).reshape(-1)
            except RunStopped as stop:
                reason = str(stop)
                break
            elapsed = time.perf_counter() - start
            if command.shape != u.shape or not np.all(np.isfinite(command)):
                reason = (f"the planner returned {'a non-finite' if command.shape == u.shape else 'a wrongly sized'} "
                          f"acceleration at t = {t:.3f} s")
                break
            reason = self._period(t, q, u, command, substeps)
            if reason is not None:
                break
            q, u = self.state.read()
            qs.append(q)
            us.append(u)
            commands.append(command)
            solver_time.append(elapsed)
            if observer is not None:
                observer((k + 1) * dt, self.data)
            if progress is not None:
                progress(k + 1, n_steps)
            if stop_when is not None and stop_when((k + 1) * dt, q.copy(), u.copy()):
                break
        record = _record(dt, qs, us, commands, solver_time, len(u0))
        return MujocoRun(record, tuple(self.contacts), reason)

    def _observation(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The oldest buffered state (``delay`` ago), with noise."""
        q, u = self.history[0]
        if self.noise == 0.0:
            return q.copy(), u.copy()
        return q + self.rng.normal(0.0, self.noise, q.shape), u + self.rng.normal(0.0, self.noise, u.shape)

    def _period(self, t: float, q: NDArray[np.float64], u: NDArray[np.float64], command: NDArray[np.float64],
                substeps: int) -> str | None:
        """Run one control period of physics steps; the reason if the state diverged."""
        scene, model, data, h = self.scene, self.model, self.data, self.h
        base = scene.base_qpos is not None
        arm = slice(2, None) if base else slice(None)
        joint_q = data.qpos[scene.joint_qpos]
        if self.setpoint is not None and np.max(np.abs(self.setpoint.position - joint_q), initial=0.0) > RESYNC_ERROR:
            self.setpoints.reset(joint_q, data.qvel[scene.joint_dof])  # held off its path: no wind-up
        self.setpoints.hold(command[arm])
        times = t + h * np.arange(1, substeps + 1)
        centres = None if self.obstacle_centres is None else self.obstacle_centres(times)
        for i in range(substeps):
            if centres is not None:
                self._set_mocap(centres[i])
            mujoco.mj_step1(model, data)
            joint_q, joint_u = data.qpos[scene.joint_qpos], data.qvel[scene.joint_dof]
            self.setpoint = self.setpoints.advance()
            self.drive.apply(self.interface.command(self.setpoint, joint_q, joint_u), joint_q, joint_u)
            if base:
                limit = scene.base_speed_limit
                self.base_velocity = np.clip(self.base_velocity + command[:2] * h, -limit, limit)
                data.ctrl[list(scene.wheel_actuators)] = scene.base.wheel_speeds(*self.base_velocity)
            mujoco.mj_step2(model, data)
            problem = self._diverged(times[i])
            if problem is not None:
                return problem
            self._record_contacts(times[i])
            if self.history.maxlen > 1:
                self.history.append(self.state.read())
        if self.history.maxlen == 1:
            self.history.append(self.state.read())
        return None

    def _diverged(self, t: float) -> str | None:
        data = self.data
        for warning, what in _INSTABILITIES:
            if data.warning[warning].number > 0:
                return f"MuJoCo became unstable ({what}) at t = {t:.3f} s"
        if not (np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))):
            return f"the MuJoCo state became non-finite at t = {t:.3f} s"
        if np.max(np.abs(data.qvel), initial=0.0) > DIVERGED_SPEED:
            return f"the MuJoCo state diverged (a speed above {DIVERGED_SPEED:g}) at t = {t:.3f} s"
        return None

    def _record_contacts(self, t: float) -> None:
        """Note every robot-obstacle or robot-robot geom pair that began touching."""
        if self.data.ncon == 0 and not self.touching:
            return
        touching = set()
        for a, b in self.data.contact.geom.tolist() if self.data.ncon else ():
            kinds = (self.kinds[a], self.kinds[b])
            if 1 in kinds and 0 not in kinds and kinds != (2, 2):
                touching.add((a, b))
        for a, b in sorted(touching - self.touching):
            first, second = (a, b) if self.kinds[a] == 1 else (b, a)
            self.contacts.append(Contact(float(t), self._name(first), self._name(second)))
        self.touching = touching

    def _name(self, geom: int) -> str:
        if self.kinds[geom] == 2:
            return self.scene.obstacle_names[self.scene.obstacle_of_geom[geom]]
        return self.model.body(int(self.model.geom_bodyid[geom])).name

    def _place_obstacles(self, times: NDArray[np.float64]) -> None:
        if self.obstacle_centres is not None:
            self._set_mocap(self.obstacle_centres(times)[0])

    def _set_mocap(self, centres: NDArray[np.float64]) -> None:
        for k, index in enumerate(self.scene.mocap):
            if index is not None:
                self.data.mocap_pos[index] = centres[k]


def _geom_kinds(scene: MujocoScene) -> NDArray[np.int64]:
    """Per geom: 1 a robot collision geom, 2 an obstacle, 0 anything else (floor, wheels)."""
    kinds = np.zeros(scene.model.ngeom, dtype=int)
    for geom in range(scene.model.ngeom):
        if geom in scene.obstacle_of_geom:
            kinds[geom] = 2
        elif int(scene.model.geom_bodyid[geom]) in scene.robot_bodies and scene.model.geom_contype[geom] == 1:
            kinds[geom] = 1
    return kinds


def _record(dt: float, qs: list[NDArray[np.float64]], us: list[NDArray[np.float64]],
            commands: list[NDArray[np.float64]], solver_time: list[float], m: int) -> Record:
    """The run as a read-only Record (see :class:`dynfab.sim.Record`)."""
    arrays = (np.arange(len(qs)) * dt, np.array(qs), np.array(us),
              np.array(commands).reshape(len(commands), m), np.array(solver_time))
    for array in arrays:
        array.setflags(write=False)
    return Record(*arrays)
