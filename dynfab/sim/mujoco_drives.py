"""The robot's joint controllers inside MuJoCo, and MuJoCo's inverse dynamics.

What a robot's firmware does with the command of a control interface
(:mod:`dynfab.sim.control_interfaces`), as torques on the joints every physics step, with
the model's bias forces b(q, q̇) (gravity, Coriolis) compensated as Franka's and UR's
drives do, gains scaled per joint by the diagonal m_ii of the joint-space inertia (with
armature), and every torque clipped to the joint's effort limit:

- ``torque``: the commanded τ as it is;
- ``position``: a PD servo on q_d, τ = b + m_ii (ω² (q_d − q) + 2ω (q̇_r − q̇)), with the
  set-point's rate q̇_r = (q_d − q_d,prev) / h as its velocity reference;
- ``velocity``: a PI velocity drive, τ = b + m_ii (2ω (q̇_d − q̇) + ω² ∫ (q̇_d − q̇) dt),
  whose integral stops while the torque is at its limit (anti-windup).

ω = :data:`SERVO_BANDWIDTH` (critically damped).
"""

from __future__ import annotations

import copy

import mujoco
import numpy as np
from numpy.typing import NDArray

from dynfab.sim.mujoco_model import MujocoScene

__all__ = ["SERVO_BANDWIDTH", "JointDrive", "MujocoInverseDynamics"]

Vector = NDArray[np.float64]

#: Closed-loop bandwidth ω of the position servo and the velocity drive [rad/s] (~8 Hz).
SERVO_BANDWIDTH = 50.0


class MujocoInverseDynamics:
    """``(q, q̇, q̈) -> τ`` of the robot's joints from MuJoCo's ``mj_inverse``.

    The joints are set to ``(q, q̇, q̈)`` on a scratch copy of ``data``; everything else
    (a base's pose and velocity) keeps its current value and zero acceleration. τ covers
    inertia (with armature), bias forces and passive forces, not constraint forces:
    like a robot's own dynamics model, it knows nothing of contacts (nor of joint limits and
    mimic couplings), which it would otherwise try to cancel.
    """

    def __init__(self, scene: MujocoScene, data: mujoco.MjData) -> None:
        self.scene = scene
        self.data = data
        self._model = copy.deepcopy(scene.model)
        self._model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
        self._scratch = mujoco.MjData(self._model)

    def __call__(self, q: Vector, qdot: Vector, qddot: Vector) -> Vector:
        scene, scratch = self.scene, self._scratch
        scratch.qpos[:] = self.data.qpos
        scratch.qvel[:] = self.data.qvel
        scratch.qacc[:] = 0.0
        scratch.qpos[scene.joint_qpos] = q
        scratch.qvel[scene.joint_dof] = qdot
        scratch.qacc[scene.joint_dof] = qddot
        mujoco.mj_inverse(self._model, scratch)
        return scratch.qfrc_inverse[scene.joint_dof].copy()


class JointDrive:
    """Torques of one control mode's joint controller (module doc)."""

    def __init__(self, scene: MujocoScene, data: mujoco.MjData, control: str, servo_period: float) -> None:
        if control not in ("torque", "velocity", "position"):
            raise ValueError(f"control must be torque, velocity or position, got {control!r}")
        self.scene = scene
        self.data = data
        self.control = control
        self.h = servo_period
        model = scene.model  # data.M is the lower triangle in rows (CSR): a row's diagonal comes last
        self._diagonal = (model.M_rowadr + model.M_rownnz - 1)[scene.joint_dof]
        self._integral = np.zeros(len(scene.joint_dof))
        self._previous: Vector | None = None

    def apply(self, command: Vector, q: Vector, qdot: Vector) -> None:
        """Write the joint torques for ``command`` into ``data.ctrl``; call after ``mj_step1``."""
        scene, data = self.scene, self.data
        if self.control == "torque":
            torque = command
        else:
            bias = data.qfrc_bias[scene.joint_dof]
            inertia = data.M[self._diagonal]
            w = SERVO_BANDWIDTH
            if self.control == "position":
                previous = command if self._previous is None else self._previous
                self._previous = command.copy()
                rate = (command - previous) / self.h
                torque = bias + inertia * (w * w * (command - q) + 2.0 * w * (rate - qdot))
            else:
                error = command - qdot
                integral = self._integral + error * self.h
                torque = bias + inertia * (2.0 * w * error + w * w * integral)
                unsaturated = np.abs(torque) < scene.effort
                self._integral = np.where(unsaturated, integral, self._integral)  # anti-windup
        data.ctrl[scene.joint_actuators] = np.clip(torque, -scene.effort, scene.effort)
