"""The receding-horizon MPC controller ``(t, q, u) ↦ u̇``.

``u`` are the robot's velocity coordinates, as the simulator integrates them: the joint
velocities ``q̇`` of a holonomic robot (``u̇ = q̈``), or ``(v, ω, arm rates)`` of a robot
on a differential-drive base (n − 1 numbers for ``q = (x, y, θ, arm)``).

Every ``solve_period`` of simulated time the controller solves
:class:`~dynfab.mpc.problem.MpcProblem` from the measured state, with the goal and
obstacle references sampled at the stage times ``t + k h`` (k = 1..H) and the previous
plan, shifted to the current time, as initial guess. Between solves it executes the
plan: a call at time ``t`` returns the acceleration of the stage that contains ``t``,
``u̇ = plan.u̇_k`` with ``k = ⌊(t − t_plan) / h⌋``.

Safe action when a solve fails (the solver did not converge or returned non-finite
numbers): keep executing the last successful plan, i.e. that plan shifted to the current
time; once the time runs past its horizon, or if there never was one, brake:
``u̇ = −k_b u`` (``k_b = MpcConfig.braking_gain`` [1/s]). Failures are counted.

Every command is within the robot's limits: ``|u̇| ≤ a_max``, and, given the control
period ``Δt``, ``|u + u̇ Δt| ≤ u_max`` where the current velocity allows it (else the
command brakes at ``a_max``). A plan keeps these by its bounds up to the solver's
tolerance (IPOPT relaxes bounds by 1e-8 relative, which put the Boxer's speed at
1.00000001 times its limit); the final clip per coordinate removes that.
"""

from __future__ import annotations

import math
import time

import numpy as np

from dynfab.motion.references import References
from dynfab.mpc.config import MpcConfig
from dynfab.mpc.problem import MpcProblem
from dynfab.mpc.values import Plan
from dynfab.sim.simulator import RunStopped

#: tolerance on "a solve period has elapsed", for times accumulated in floating point [s]
_TIME_TOLERANCE = 1e-9


class MpcController:
    """MPC re-solved every ``config.solve_period`` (see module docstring).

    Attributes:
        problem: the NLP, built once.
        references: goal and obstacle trajectories of the scenario.
        obstacle_radii: radius of each obstacle, shape (m,) [m].
        control_period: ``Δt`` between calls [s] (the scenario's ``dt``), used to keep the
            next velocity within its limits; ``None``: only the acceleration is bounded.
        solve_times: wall time of each solve, including the parameter packing [s].
        iterations: solver iterations of each solve.
        failures: number of solves that failed.
    """

    def __init__(self, problem: MpcProblem, references: References, obstacle_radii: np.ndarray,
                 control_period: float | None = None) -> None:
        if len(references.obstacles) != problem.obstacles or len(references.goals) != len(problem.goals):
            raise ValueError("MpcController: references do not match the problem's goals and obstacles")
        self.problem = problem
        self.references = references
        self.obstacle_radii = np.asarray(obstacle_radii, dtype=float)
        if control_period is not None and not (math.isfinite(control_period) and control_period > 0):
            raise ValueError(f"MpcController: control_period must be a positive number of seconds, got {control_period}")
        self.control_period = control_period
        self.solve_times: list[float] = []
        self.iterations: list[int] = []
        self.failures = 0
        self._plan: Plan | None = None
        self._plan_time = 0.0
        self._last_attempt: float | None = None

    @property
    def config(self) -> MpcConfig:
        """Horizon, weights and solver."""
        return self.problem.config

    @property
    def plan(self) -> Plan | None:
        """The plan being executed (the last successful one), if any."""
        return self._plan

    def __call__(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """``u̇`` at time ``t`` [s] for the measured configuration ``q`` (n,) and velocity
        coordinates ``qdot`` = ``u`` (m,); always finite, shape (m,).

        Raises:
            ValueError: if ``q`` or ``u`` has the wrong shape or is not finite.
        """
        q = np.asarray(q, dtype=float)
        qdot = np.asarray(qdot, dtype=float)
        n, m = self.problem.robot.dof, self.problem.model.velocity_size
        if q.shape != (n,) or qdot.shape != (m,):
            raise ValueError(f"q and qdot must have shapes ({n},) and ({m},), got {q.shape} and {qdot.shape}")
        if not (np.isfinite(q).all() and np.isfinite(qdot).all()):
            raise ValueError("q or qdot contains NaN or infinity")
        if self._last_attempt is None or t >= self._last_attempt + self.config.solve_period - _TIME_TOLERANCE:
            self._replan(t, q, qdot)
        return self._command(t, qdot)

    def _replan(self, t: float, q: np.ndarray, qdot: np.ndarray) -> None:
        """Solve from ``(q, q̇)`` at ``t``; keep the plan if the solve succeeded."""
        self._last_attempt = t
        h, horizon = self.config.stage_length, self.config.stages
        times = t + h * np.arange(1, horizon + 1)
        dims = 2 if self.problem.robot.planar else 3
        with np.errstate(all="ignore"):
            goals = [reference.sample(times)[0] for reference in self.references.goals]
            centres = np.zeros((self.problem.obstacles, horizon, dims))
            for o, reference in enumerate(self.references.obstacles):
                centres[o] = reference.sample(times)[0][:, :dims]
        if not (all(np.isfinite(goal).all() for goal in goals) and np.isfinite(centres).all()):
            raise RunStopped(f"a goal or obstacle reference over the MPC horizon {times[0]:.3f}..{times[-1]:.3f} s "
                             "turned non-finite")
        guess = None
        if self._plan is not None:
            guess = self._plan.shifted(round((t - self._plan_time) / h), h, self.problem.model.simulator)
        start = time.perf_counter()
        result = self.problem.solve(q, qdot, goals, centres, self.obstacle_radii, guess)
        self.solve_times.append(time.perf_counter() - start)
        self.iterations.append(result.iterations)
        if result.success:
            self._plan, self._plan_time = result.plan, t
        else:
            self.failures += 1

    def _command(self, t: float, qdot: np.ndarray) -> np.ndarray:
        """The executed plan's acceleration ``u̇`` at ``t``, or the braking action ``−k_b u``,
        clipped to the limits (module docstring)."""
        command = -self.config.braking_gain * qdot
        if self._plan is not None:
            stage = math.floor((t - self._plan_time) / self.config.stage_length + _TIME_TOLERANCE)
            if 0 <= stage < self.config.stages:
                command = self._plan.qddot[stage]
        if self.control_period is not None:
            speed = self.problem.model.velocity_limits
            command = np.clip(command, (-speed - qdot) / self.control_period, (speed - qdot) / self.control_period)
        peak = self.problem.model.acceleration_limits
        return np.clip(command, -peak, peak)
