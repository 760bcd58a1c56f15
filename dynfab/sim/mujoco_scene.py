"""What :func:`dynfab.sim.mujoco_model.build_scene` takes and gives: obstacles as MuJoCo sees
them, and the compiled scene with the addresses of the robot's coordinates in it."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from dynfab.geometry.shapes import Shape
from dynfab.robots.robot import DifferentialDriveBase

__all__ = ["MujocoModelError", "MujocoScene", "SceneObstacle"]


class MujocoModelError(ValueError):
    """The robot cannot be simulated by MuJoCo; the one-line message names the link."""


@dataclass(frozen=True)
class SceneObstacle:
    """An obstacle as MuJoCo sees it.

    Attributes:
        shape: Its geometry in its own frame (a plane: the solid half-space z <= 0).
        position: Centre (a plane: its point) at t = 0 [m].
        orientation: Unit quaternion (w, x, y, z) of its frame.
        moving: True if its centre follows a trajectory (a mocap body).
        name: How contacts name it (the scenario file's entry, e.g. ``obstacles[2]``); empty:
            ``obstacles[k]`` by its index ``k`` in the scene.
    """

    shape: Shape
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    moving: bool
    name: str = ""


@dataclass(frozen=True, eq=False)
class MujocoScene:
    """A compiled model and where the robot's coordinates live in it.

    Attributes:
        model: The compiled MuJoCo model.
        joint_qpos: qpos address of each joint coordinate (the arm part of ``q``; all of
            it without a base), shape (n_joints,).
        joint_dof: qvel address of each of them, shape (n_joints,).
        joint_actuators: The motor (torque) actuator of each of them.
        effort: Effort limit of each of them [N m or N] (``robot.limits.effort``; ``inf``
            if unknown).
        lower: Lower position limit of each of them [rad or m] (the URDF's; ``-inf``: none).
        upper: Upper position limit of each of them [rad or m].
        base_qpos: qpos address of the base's free joint, or None without a base.
        base_dof: qvel address of the base's free joint, or None.
        wheel_actuators: Velocity actuators of the (left, right) drive wheels, or None.
        base: The differential-drive base (wheel radius, track), or None.
        base_speed_limit: The base's velocity limits ``(v_max, ω_max)`` [m/s, rad/s]
            (``robot.limits.velocity``), or None without a base.
        mocap: Mocap index of each obstacle (None for a static one).
        robot_bodies: Body ids of the robot.
        obstacle_of_geom: Obstacle index of each obstacle geom id.
        obstacle_names: How contacts name each obstacle (:attr:`SceneObstacle.name`).
    """

    model: mujoco.MjModel
    joint_qpos: np.ndarray
    joint_dof: np.ndarray
    joint_actuators: np.ndarray
    effort: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    base_qpos: int | None
    base_dof: int | None
    wheel_actuators: tuple[int, int] | None
    base: DifferentialDriveBase | None
    base_speed_limit: np.ndarray | None
    mocap: tuple[int | None, ...]
    robot_bodies: frozenset[int]
    obstacle_of_geom: dict[int, int]
    obstacle_names: tuple[str, ...] = ()
