"""Settings of the MPC baseline (``shared/EXPERIMENTS.md``, Experiment 1).

The defaults are those of the paper's benchmark (localPlannerBench): a horizon of
T = 3 s in H = 30 stages, re-solved at 10 Hz, with the cost weights goal 10, input 5,
velocity 5 and slack 1e10.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

SolverName = Literal["ipopt", "fatrop"]
_SOLVERS: tuple[str, ...] = ("ipopt", "fatrop")


@dataclass(frozen=True)
class MpcConfig:
    """Horizon, weights and solver of the receding-horizon baseline.

    The optimal control problem over stages k = 0..H with stage length h = T / H is

        min   Σ_{k=1..H} [ w_g Σ_i ω_i ||e_i(q_k, t_k)||² + w_v ||u_k||² + w_s s_k ]
            + Σ_{k=0..H-1} w_u ||u̇_k||²

    with ``e_i`` the error of goal ``i`` (weight ``ω_i`` from the scenario) at the stage
    time ``t_k`` and ``u`` the velocity coordinates (``q̇``, or ``(v, ω, arm rates)`` on a
    differential-drive base); see :mod:`dynfab.mpc.problem` for the constraints.

    Attributes:
        horizon: T, the time the plan looks ahead [s].
        stages: H, the number of stages of the horizon.
        solve_period: re-solve period in simulated time [s]; between solves the
            controller executes the last plan.
        goal_weight: w_g, weight of the squared goal error [1/m²] (joint goals: [1/rad²]).
        input_weight: w_u, weight of the squared accelerations ``u̇`` [s⁴/rad²].
        velocity_weight: w_v, weight of the squared velocities ``u`` [s²/rad²].
        slack_weight: w_s, weight of the (linear) collision slack [1/m].
        collision_margin: δ, clearance the collision rows ask for at the stage times,
            ``gap ≥ δ − s`` [m]. 0 is the benchmark's formulation; a positive δ covers
            the graze between stage times (about ``(u_max h)² / (8 (r_j + r_o))``, see
            :mod:`dynfab.mpc.problem`).
        solver: ``"ipopt"`` (interior point, general sparse) or ``"fatrop"``
            (interior point exploiting the stage structure, ``structure_detection:
            auto``).
        max_iter: iteration limit of one solve.
        tolerance: convergence tolerance of the solver (its ``tol``).
        braking_gain: k of the safe action ``u̇ = −k u`` used when no plan is
            available [1/s].
    """

    horizon: float = 3.0
    stages: int = 30
    solve_period: float = 0.1
    goal_weight: float = 10.0
    input_weight: float = 5.0
    velocity_weight: float = 5.0
    slack_weight: float = 1e10
    solver: SolverName = "ipopt"
    max_iter: int = 100
    tolerance: float = 1e-4
    braking_gain: float = 5.0
    collision_margin: float = 0.0

    def __post_init__(self) -> None:
        positive = {"horizon": self.horizon, "solve_period": self.solve_period, "tolerance": self.tolerance}
        for name, value in positive.items():
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"MpcConfig.{name} must be a positive number, got {value}")
        weights = {"goal_weight": self.goal_weight, "input_weight": self.input_weight,
                   "velocity_weight": self.velocity_weight, "slack_weight": self.slack_weight,
                   "braking_gain": self.braking_gain, "collision_margin": self.collision_margin}
        for name, value in weights.items():
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"MpcConfig.{name} must be a non-negative number, got {value}")
        if self.stages < 1 or self.max_iter < 1:
            raise ValueError(f"MpcConfig.stages and max_iter must be >= 1, got {self.stages}, {self.max_iter}")
        if self.solver not in _SOLVERS:
            raise ValueError(f"MpcConfig.solver must be one of {', '.join(_SOLVERS)}, got {self.solver!r}")

    @property
    def stage_length(self) -> float:
        """h = T / H [s]."""
        return self.horizon / self.stages
