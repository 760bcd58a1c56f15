"""A URDF joint's transforms as 4 x 4 matrices, and numbers as MJCF attribute text (for
:mod:`dynfab.sim.mujoco_model`)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np

from dynfab.robots.urdf import Joint

__all__ = ["joint_motion", "mjcf_numbers", "origin_matrix", "pose_attributes"]


def origin_matrix(joint: Joint) -> np.ndarray:
    """The joint's origin, parent link frame to joint frame, as a 4 x 4 transform [m]."""
    transform = np.eye(4)
    transform[:3, :3] = np.array(joint.origin.rotation)
    transform[:3, 3] = joint.origin.xyz
    return transform


def joint_motion(joint: Joint, value: float) -> np.ndarray:
    """The joint's motion ``M(value)``: rotation about or translation along its axis."""
    motion = np.eye(4)
    axis = np.array(joint.axis)
    if joint.type == "prismatic":
        motion[:3, 3] = value * axis
    elif joint.type in ("revolute", "continuous"):
        cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        motion[:3, :3] = np.eye(3) + math.sin(value) * cross + (1 - math.cos(value)) * cross @ cross
    return motion


def pose_attributes(transform: np.ndarray) -> dict[str, str]:
    """MJCF ``pos`` [m] and ``quat`` (w, x, y, z) attributes of a 4 x 4 transform."""
    quaternion = np.zeros(4)
    mujoco.mju_mat2Quat(quaternion, np.ascontiguousarray(transform[:3, :3]).reshape(-1))
    return {"pos": mjcf_numbers(transform[:3, 3]), "quat": mjcf_numbers(quaternion)}


def mjcf_numbers(values: Sequence[float] | np.ndarray) -> str:
    """Numbers as MJCF writes them: space-separated, full precision."""
    return " ".join(repr(float(v)) for v in values)
