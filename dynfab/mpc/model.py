"""Prediction models of the MPC baseline: how the plan's state moves over one stage.

The state of stage k is ``(q_k, u_k)``: the configuration and the robot's velocity
coordinates, the same as the simulator's (:mod:`dynfab.sim.models`). The input ``u̇_k``
(the acceleration of the velocity coordinates) is held constant over the stage of length
h [s]; the velocities are then exact in both models,

    u_{k+1} = u_k + h u̇_k.

**Holonomic robots** (fixed arms, the point robot): ``u = q̇`` and every joint is an exact
double integrator,

    q_{k+1} = q_k + h u_k + ½ h² u̇_k.

**Robots on a differential-drive base** (``boxer``, ``boxer-panda``):
``q = (x, y, θ, arm...)``, ``u = (v, ω, arm rates...)``. The arm joints are exact double
integrators as above. The base pose moves along the circular arc of the stage's mid-point
speeds ``v̄ = v_k + ½ h v̇_k``, ``ω̄ = ω_k + ½ h ω̇_k`` (the simulator's
:class:`~dynfab.sim.models.DifferentialDrive` with one sub-step per stage):

    Δ = ω̄ h,   θ_{k+1} = θ_k + Δ,
    (x, y)_{k+1} = (x, y)_k + v̄ h sinc(Δ/2) (cos(θ_k + Δ/2), sin(θ_k + Δ/2)),

the exact motion of a unicycle driving at the constant speeds ``(v̄, ω̄)``: the base
follows ``ẋ = v̄ cos θ``, ``ẏ = v̄ sin θ``, ``θ̇ = ω̄`` and so satisfies the non-holonomic
constraint ``ẏ cos θ − ẋ sin θ = 0`` at every instant of the predicted motion *by
construction*; in particular the chord of each stage lies along the mean heading
``θ_k + Δ/2``. The heading ``θ_{k+1}`` is exact for the held ``ω̇``
(``∫ ω dt = h ω̄``). The position differs from the held-acceleration motion the robot
really executes (speeds changing linearly over the stage, a clothoid-like curve) by
O(h³): across the heading by ``(v̇ ω − v ω̇) h³ / 12`` (1e-4 m at h = 0.1 s,
``v̇ = ω = 1``; 5e-4 m at ``v = 1.9 m/s``, ``ω̇ = −3 rad/s²``), the same order along
it; the plan's first stage, the one executed, is re-planned from the measured state
every stage. The arc was chosen over RK4 with sub-steps: RK4 would track that
held-acceleration motion more closely (O(h⁵) per step), but its end point is the end
point of a rolling motion only up to its own error, while each arc *is* one (and is what
the simulator integrates on each of its sub-steps).

``sinc(a) = sin(a)/a`` is written with a safe branch: for ``|a| < 0.1`` its Taylor
polynomial ``1 − a²/6 + a⁴/120 − a⁶/5040 + a⁸/362880`` (truncation error below 3·10⁻¹⁸,
of its second derivative below 3·10⁻¹⁴), else ``sin(a)/a`` of an argument that is never
zero, so that values and the derivatives the solver uses are finite and accurate
everywhere (the quotient's second derivative loses ~ε/a³ to cancellation, 2·10⁻¹³ at
the switch). Within the yaw-rate bound, ``|a| = |ω̄| h / 2 ≤ 0.1``: the polynomial.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from dynfab.robots.robot import Robot
from dynfab.sim.models import DifferentialDrive, DoubleIntegrator, MotionModel

_SINC_SWITCH = 0.1  # |a| below which sinc uses its Taylor polynomial


def sinc(a: ca.SX) -> ca.SX:
    """``sin(a)/a`` (1 at ``a = 0``), finite with finite derivatives for every ``a``."""
    small = ca.fabs(a) < _SINC_SWITCH
    safe = ca.if_else(small, 1.0, a)
    square = a * a
    series = 1.0 - square / 6.0 * (1.0 - square / 20.0 * (1.0 - square / 42.0 * (1.0 - square / 72.0)))
    return ca.if_else(small, series, ca.sin(safe) / safe)


def double_integrator_step(q: ca.SX, u: ca.SX, udot: ca.SX, h: float) -> ca.SX:
    """``q + h u + ½ h² u̇``: configuration after a stage with constant ``u̇`` (``u = q̇``)."""
    return q + h * u + 0.5 * h * h * udot


def differential_drive_step(q: ca.SX, u: ca.SX, udot: ca.SX, h: float) -> ca.SX:
    """Configuration after a stage for ``q = (x, y, θ, arm)``, ``u = (v, ω, arm rates)``:
    the unicycle arc of the mid-point speeds for the base, a double integrator per arm
    joint (module docstring)."""
    v_mid = u[0] + 0.5 * h * udot[0]
    omega_mid = u[1] + 0.5 * h * udot[1]
    turn = omega_mid * h
    middle = q[2] + 0.5 * turn
    chord = v_mid * h * sinc(0.5 * turn)
    base = ca.vertcat(q[0] + chord * ca.cos(middle), q[1] + chord * ca.sin(middle), q[2] + turn)
    if q.shape[0] == 3:
        return base
    return ca.vertcat(base, double_integrator_step(q[3:], u[2:], udot[2:], h))


@dataclass(frozen=True)
class PredictionModel:
    """The model of the module docstring for one robot.

    Attributes:
        configuration_size: n, the size of ``q``.
        differential_drive: whether ``q`` starts with a differential-drive base pose.
        velocity_limits: bounds ``|u| ≤ u_max`` on the velocity coordinates
            (``robot.limits.velocity``: joints, or ``(v, ω, arm joints)`` on a base)
            [m/s, rad/s, rad/s...].
        acceleration_limits: bounds ``|u̇| ≤ a_max`` (``robot.limits.acceleration``).
    """

    configuration_size: int
    differential_drive: bool
    velocity_limits: np.ndarray
    acceleration_limits: np.ndarray

    @classmethod
    def for_robot(cls, robot: Robot) -> PredictionModel:
        """The model of ``robot``: differential drive if it has a ``base``."""
        return cls(configuration_size=robot.dof, differential_drive=robot.base is not None,
                   velocity_limits=robot.limits.velocity, acceleration_limits=robot.limits.acceleration)

    @property
    def velocity_size(self) -> int:
        """m, the size of ``u`` and ``u̇``: n − 1 on a differential-drive base, else n."""
        return self.configuration_size - 1 if self.differential_drive else self.configuration_size

    @property
    def simulator(self) -> MotionModel:
        """The simulator's numeric twin: ``step(q, u, u̇, h)`` with one sub-step computes
        exactly :meth:`step` (used to extend a shifted plan)."""
        return DifferentialDrive() if self.differential_drive else DoubleIntegrator()

    def step(self, q: ca.SX, u: ca.SX, udot: ca.SX, h: float) -> ca.SX:
        """``q_{k+1}`` from ``(q_k, u_k, u̇_k)`` over a stage of length ``h`` [s]."""
        if self.differential_drive:
            return differential_drive_step(q, u, udot, h)
        return double_integrator_step(q, u, udot, h)
