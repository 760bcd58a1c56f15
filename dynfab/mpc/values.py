"""Values of the MPC problem: a goal term, a plan over the horizon, a solve's result."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dynfab.sim.models import DoubleIntegrator, MotionModel


@dataclass(frozen=True)
class GoalTerm:
    """One goal of the cost.

    Attributes:
        link: goal link of a position, path or orientation goal; ``None`` for a
            joint-space goal.
        axes: indices (0 = x, 1 = y, 2 = z) of the controlled axes of ``link``.
        parent_link: frame in which the link position is measured (``None``: root).
        weight: ω, relative weight of this goal.
        offset: the goal point in the link frame [m].
        link_axes: an orientation goal: unit axes ``a`` in the link frame whose world
            directions ``R a`` (stacked) follow the reference; ``()`` for a position goal.
    """

    link: str | None
    axes: tuple[int, ...] = (0, 1, 2)
    parent_link: str | None = None
    weight: float = 1.0
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    link_axes: tuple[tuple[float, float, float], ...] = ()

    @property
    def dimension(self) -> int | None:
        """Size of ``e_i``; ``None`` for a joint goal (the robot's dof)."""
        if self.link is None:
            return None
        return 3 * len(self.link_axes) if self.link_axes else len(self.axes)


@dataclass(frozen=True, eq=False)
class Plan:
    """A solution over the horizon, stage k at time ``t_0 + k h``.

    Attributes:
        q: configurations q_0..q_H, shape (H + 1, n) [rad or m].
        qdot: velocity coordinates u_0..u_H, shape (H + 1, m): the joint velocities
            (m = n), or ``(v, ω, arm rates)`` on a differential-drive base (m = n − 1)
            [m/s, rad/s].
        qddot: their accelerations ``u̇`` held over each stage, shape (H, m)
            [rad/s² or m/s²].
        slack: collision slacks s_1..s_H, shape (H,) [m].
    """

    q: np.ndarray
    qdot: np.ndarray
    qddot: np.ndarray
    slack: np.ndarray

    def shifted(self, stages: int, stage_length: float, model: MotionModel = DoubleIntegrator()) -> Plan:
        """The plan from stage ``stages`` on, extended at the end with ``u̇ = 0``.

        The extension keeps the dynamics of ``model`` (the prediction model's numeric
        twin, :attr:`PredictionModel.simulator`): per added stage
        ``q ← model.step(q, u, 0, h)`` at constant ``u``, i.e. ``q ← q + h q̇`` for a
        double integrator, a straight line or circular arc for a differential-drive base.
        """
        horizon = self.qddot.shape[0]
        stages = min(stages, horizon)
        q, qdot = self.q[stages:], self.qdot[stages:]
        extension = [q[-1]]
        for _ in range(stages):
            extension.append(model.step(extension[-1], qdot[-1], np.zeros_like(qdot[-1]), stage_length)[0])
        return Plan(q=np.vstack([q, *extension[1:]]),
                    qdot=np.vstack([qdot, np.repeat(qdot[-1:], stages, axis=0)]),
                    qddot=np.vstack([self.qddot[stages:], np.zeros((stages, self.qddot.shape[1]))]),
                    slack=np.concatenate([self.slack[stages:], np.zeros(stages)]))

    @property
    def finite(self) -> bool:
        """Whether every entry is a finite number."""
        return all(np.isfinite(a).all() for a in (self.q, self.qdot, self.qddot, self.slack))


@dataclass(frozen=True, eq=False)
class SolveResult:
    """The outcome of one solve.

    Attributes:
        plan: the solver's last iterate (meaningful only if ``success``).
        success: the solver converged and the plan is finite.
        iterations: solver iterations.
        status: the solver's return status.
    """

    plan: Plan
    success: bool
    iterations: int
    status: str
