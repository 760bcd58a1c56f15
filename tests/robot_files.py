"""Where the robot descriptions that ship on PyPI lie: example-robot-data and pybullet_data."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

import numpy as np
import pybullet_data


def example_robot_data_dir() -> Path:
    """The ``robots`` folder of the example-robot-data wheel (installed by cmeel)."""
    distribution = importlib.metadata.distribution("example-robot-data")
    urdf = next(f for f in distribution.files if str(f).endswith("ur5_robot.urdf"))
    return Path(str(distribution.locate_file(urdf))).parents[2]


def shipped_urdfs() -> list[Path]:
    """Every URDF of example-robot-data and pybullet_data, sorted."""
    roots = [example_robot_data_dir(), Path(pybullet_data.getDataPath())]
    return sorted(path for root in roots for path in root.rglob("*.urdf"))


#: Arms of example-robot-data: (file under its robots folder, tool link, active joints or None).
ARMS: dict[str, tuple[str, str]] = {
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "kinova": ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),
    "xarm7": ("xarm_description/urdf/xarm7.urdf", "link_eef"),
    "panda": ("panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    "z1": ("z1_description/urdf/z1.urdf", "link06"),
}


def arm_urdf(name: str) -> Path:
    """The URDF of one of :data:`ARMS`."""
    return example_robot_data_dir() / ARMS[name][0]


def folded_configuration(model: object, seed: int) -> tuple[np.ndarray, list[float]]:
    """A UR5-like configuration (joints in [-3, 3] rad) where two checked links of a mesh
    collision model overlap by more than 1 cm, found by a seeded random search; with the
    distance of every checked pair there [m]."""
    from dynfab.geometry.exact_collision import exact_distance

    rng = np.random.default_rng(seed)
    for _ in range(400):
        q = rng.uniform(-3.0, 3.0, len(model.kinematics.joint_names))
        poses = model.link_poses(q)[0]
        depths = [exact_distance(model.meshes[i], poses[i], model.meshes[j], poses[j]) for i, j in model.pairs]
        if min(depths) < -0.01:
            return q, depths
    raise AssertionError("no configuration folded into itself found")
