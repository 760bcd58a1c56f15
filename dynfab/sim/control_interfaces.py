"""Control-loop adapters: from the planner's q̈ to what a robot's joint controller takes.

A planner runs at the control period ``dt`` (e.g. 100 Hz) and returns joint
accelerations q̈; a robot's joint controller runs faster (1 kHz on a Franka or a UR) and
takes positions, velocities or torques. :class:`SetpointIntegrator` bridges the two: it
starts at the measured state (``reset``), holds each new q̈ of the planner (``hold``) and
at each servo tick advances the desired state by the servo period h,

    q̇_d ← q̇_d + q̈ h,    q_d ← q_d + q̇_d h − ½ q̈ h²   (exact for constant q̈),

stopping at the joints' position limits if it is given them.

The set-points are continuous (Franka's interfaces refuse jumps): the desired state is
not pulled back to the measured one at each planner tick; the planner closes the loop
through the state it is given, the joint controller tracks the set-points. The
interfaces turn a :class:`Setpoint` into the command of one kind of joint controller:

- :class:`PositionInterface`: q_d [rad or m] for a position servo;
- :class:`VelocityInterface`: q̇_d [rad/s or m/s] for a velocity drive;
- :class:`TorqueInterface`: τ = ID(q, q̇, q̈_d + K_p (q_d − q) + K_d (q̇_d − q̇)) [N m or N],
  computed torque through an inverse-dynamics callable (from the robot's model, e.g.
  pinocchio's ``rnea``, libfranka's model, or :class:`~dynfab.sim.mujoco_drives.MujocoInverseDynamics`),
  clipped to the effort limits.

The MuJoCo simulation (:mod:`dynfab.sim.mujoco_sim`) drives its joints through these
same classes. A real loop looks like::

    setpoints = SetpointIntegrator(servo_period=0.001)
    interface = VelocityInterface()
    once:          setpoints.reset(q, qdot)
    every dt:      setpoints.hold(planner.compute(q, qdot))
    every 1 ms:    robot.send(interface.command(setpoints.advance(), q, qdot))
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ControlInterface", "InverseDynamics", "PositionInterface", "Setpoint", "SetpointIntegrator",
           "TorqueInterface", "VelocityInterface", "interface_for"]

Vector = NDArray[np.float64]

InverseDynamics = Callable[[Vector, Vector, Vector], ArrayLike]
"""``(q, q̇, q̈) -> τ``: the joint torques [N m or N] that give ``q̈`` at ``(q, q̇)``."""


@dataclass(frozen=True)
class Setpoint:
    """The desired joint state at one servo tick.

    Attributes:
        position: q_d [rad or m].
        velocity: q̇_d [rad/s or m/s].
        acceleration: q̈_d, the planner's held command [rad/s^2 or m/s^2].
    """

    position: Vector
    velocity: Vector
    acceleration: Vector


class SetpointIntegrator:
    """Integrates the planner's q̈ into setpoints at the servo rate (module doc)."""

    def __init__(self, servo_period: float, lower: ArrayLike | None = None, upper: ArrayLike | None = None) -> None:
        """Args:
            servo_period: h, the joint controller's period [s] (> 0).
            lower: Lower position limits [rad or m] (``-inf``: none); a set-point that
                would leave ``[lower, upper]`` stops at the limit with zero velocity, as
                a robot refuses set-points beyond its limits (and the joint controller
                does not wind up against them).
            upper: Upper position limits [rad or m] (``inf``: none).
        """
        if not (math.isfinite(servo_period) and servo_period > 0.0):
            raise ValueError(f"servo_period must be a positive number of seconds, got {servo_period}")
        self.servo_period = servo_period
        self.lower = None if lower is None else np.asarray(lower, dtype=float)
        self.upper = None if upper is None else np.asarray(upper, dtype=float)
        self._position: Vector | None = None
        self._velocity: Vector | None = None
        self._acceleration: Vector | None = None

    def reset(self, q: ArrayLike, qdot: ArrayLike) -> None:
        """Start the desired state at the measured ``(q, q̇)`` (at the first tick, and after
        the robot was stopped or held off its path, e.g. by a contact)."""
        self._position = np.array(q, dtype=float)
        self._velocity = np.array(qdot, dtype=float)
        if self._position.shape != self._velocity.shape:
            raise ValueError(f"q and qdot must have one shape, got {self._position.shape} and {self._velocity.shape}")
        self._acceleration = np.zeros_like(self._position)

    def hold(self, qddot: ArrayLike) -> None:
        """The planner's new ``q̈``, held until the next call."""
        acceleration = np.array(qddot, dtype=float)
        if self._position is None or acceleration.shape != self._position.shape:
            raise ValueError("hold() needs a reset() first and one acceleration per joint")
        self._acceleration = acceleration

    def advance(self) -> Setpoint:
        """The setpoint one servo period later."""
        if self._position is None or self._velocity is None or self._acceleration is None:
            raise RuntimeError("SetpointIntegrator.advance() before reset()")
        h, a = self.servo_period, self._acceleration
        self._velocity = self._velocity + a * h
        self._position = self._position + self._velocity * h - 0.5 * a * h * h
        if self.lower is not None or self.upper is not None:
            lower = -np.inf if self.lower is None else self.lower
            upper = np.inf if self.upper is None else self.upper
            outside = (self._position < lower) | (self._position > upper)
            if np.any(outside):
                self._position = np.clip(self._position, lower, upper)
                self._velocity = np.where(outside, 0.0, self._velocity)
                a = np.where(outside, 0.0, a)
        return Setpoint(self._position.copy(), self._velocity.copy(), a.copy())


class ControlInterface(Protocol):
    """Turns a setpoint and the measured state into a joint controller's command."""

    def command(self, setpoint: Setpoint, q: Vector, qdot: Vector) -> Vector:
        """The command for this servo tick."""


@dataclass(frozen=True)
class PositionInterface:
    """A position servo's command: q_d [rad or m]."""

    def command(self, setpoint: Setpoint, q: Vector, qdot: Vector) -> Vector:
        return setpoint.position


@dataclass(frozen=True)
class VelocityInterface:
    """A velocity drive's command: q̇_d [rad/s or m/s]."""

    def command(self, setpoint: Setpoint, q: Vector, qdot: Vector) -> Vector:
        return setpoint.velocity


@dataclass(frozen=True)
class TorqueInterface:
    """Computed torque, τ = ID(q, q̇, q̈_d + K_p (q_d − q) + K_d (q̇_d − q̇)), clipped to ±effort.

    Attributes:
        inverse_dynamics: ``(q, q̇, q̈) -> τ`` of the robot's model.
        stiffness: K_p [1/s^2].
        damping: K_d [1/s].
        effort: Effort limit per joint [N m or N] (``inf``: none).
    """

    inverse_dynamics: InverseDynamics
    stiffness: float
    damping: float
    effort: Vector

    def command(self, setpoint: Setpoint, q: Vector, qdot: Vector) -> Vector:
        acceleration = (setpoint.acceleration + self.stiffness * (setpoint.position - q)
                        + self.damping * (setpoint.velocity - qdot))
        torque = np.asarray(self.inverse_dynamics(q, qdot, acceleration), dtype=float)
        return np.clip(torque, -self.effort, self.effort)


def interface_for(control: str, inverse_dynamics: InverseDynamics, effort: Vector,
                  stiffness: float = 400.0, damping: float = 40.0) -> ControlInterface:
    """The interface of a ``control`` mode: ``position``, ``velocity`` or ``torque``.

    Args:
        control: The mode.
        inverse_dynamics: Used by ``torque``.
        effort: Effort limits, used by ``torque`` [N m or N].
        stiffness: K_p of ``torque`` [1/s^2] (default: 20 rad/s, critically damped).
        damping: K_d of ``torque`` [1/s].

    Raises:
        ValueError: An unknown mode.
    """
    if control == "position":
        return PositionInterface()
    if control == "velocity":
        return VelocityInterface()
    if control == "torque":
        return TorqueInterface(inverse_dynamics, stiffness, damping, np.asarray(effort, dtype=float))
    raise ValueError(f"control must be torque, velocity or position, got {control!r}")
