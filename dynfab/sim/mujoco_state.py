"""The robot's coordinates in a MuJoCo state, read and written.

Joints: ``q`` and ``q̇`` at their qpos / qvel addresses. A differential-drive base
(free joint of the body below ``base_yaw``): ``(x, y, yaw)`` from its position and
quaternion (yaw unwrapped against the previous reading, so that it is continuous like
the planner's), and its velocity coordinates ``(v, ω)``: the forward speed along the
heading, v = ẋ cos yaw + ẏ sin yaw [m/s], and the yaw rate ω [rad/s] (MuJoCo gives the
free joint's angular velocity in the body frame; upright, its z is the yaw rate).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import NDArray

from dynfab.sim.mujoco_model import MujocoScene

__all__ = ["RobotState"]

Vector = NDArray[np.float64]


class RobotState:
    """Reads and writes the robot's ``(q, u)`` in ``data`` (``u``: q̇, or ``(v, ω, arm)``)."""

    def __init__(self, scene: MujocoScene, data: mujoco.MjData) -> None:
        self.scene = scene
        self.data = data
        self._yaw = 0.0

    def write(self, q: Vector, u: Vector, base_height: float = 0.001) -> None:
        """Put the robot at ``(q, u)`` (a base: ``base_height`` [m] above the floor, wheels at rest)."""
        scene, data = self.scene, self.data
        arm_q, arm_u = (q[3:], u[2:]) if scene.base_qpos is not None else (q, u)
        data.qpos[scene.joint_qpos] = arm_q
        data.qvel[scene.joint_dof] = arm_u
        if scene.base_qpos is None:
            return
        x, y, yaw = q[:3]
        v, omega = u[:2]
        a = scene.base_qpos
        data.qpos[a:a + 7] = (x, y, base_height, math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        d = scene.base_dof
        data.qvel[d:d + 6] = (v * math.cos(yaw), v * math.sin(yaw), 0.0, 0.0, 0.0, omega)
        self._yaw = float(yaw)

    def read(self) -> tuple[Vector, Vector]:
        """The robot's current ``(q, u)``."""
        scene, data = self.scene, self.data
        q = data.qpos[scene.joint_qpos].copy()
        u = data.qvel[scene.joint_dof].copy()
        if scene.base_qpos is None:
            return q, u
        a, d = scene.base_qpos, scene.base_dof
        w, qx, qy, qz = data.qpos[a + 3:a + 7]
        heading = math.atan2(2.0 * (w * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
        self._yaw += math.remainder(heading - self._yaw, 2.0 * math.pi)
        v = data.qvel[d] * math.cos(self._yaw) + data.qvel[d + 1] * math.sin(self._yaw)
        base_q = np.array([data.qpos[a], data.qpos[a + 1], self._yaw])
        base_u = np.array([v, data.qvel[d + 5]])
        return np.concatenate([base_q, q]), np.concatenate([base_u, u])
