"""The collision models that ship with dynfab: the ``auto`` fits of the URDF robots its
experiments and benchmarks name (:data:`SHIPPED_ROBOTS`), stored under their cache key in
:data:`~dynfab.robots.collision_model.SHIPPED_DIR` so that a first run of them reads the fit
instead of making it (20-70 s each on this project's 2-core machine).

    python -m dynfab.experiments.shipped_models

fits every one of them afresh (example-robot-data installed) and writes the folder anew:
after a change of the fit (``_CACHE_VERSION``) or of example-robot-data.
tests/test_shipped_models.py checks that the folder holds exactly their entries and that
a fresh fit of the smallest one equals its entry.
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from dynfab.benchmarks.mbm.ur5 import UR5_URDF
from dynfab.experiments.arms import ARMS, installed_urdf
from dynfab.experiments.arms_pose import POSE_ARMS
from dynfab.robots.collision_model import SHIPPED_DIR, auto_collision_model, entry_name

__all__ = ["SHIPPED_ROBOTS", "ShippedRobot", "main", "shipped_names"]


@dataclass(frozen=True)
class ShippedRobot:
    """A URDF robot whose ``auto`` collision model ships (default fit and pair selection).

    Attributes:
        urdf: ``package://`` URI of its URDF.
        joints: Active joints (``None``: every movable one).
        locked: Values of the others [rad or m].
    """

    urdf: str
    joints: tuple[str, ...] | None = None
    locked: tuple[tuple[str, float], ...] = ()


#: The arms experiments' robots as their scenarios name them, each of example-robot-data's
#: arms with every movable joint active (``dynfab spheres`` on its URDF), and the UR5 with
#: its gripper of the MotionBenchMaker benchmark.
SHIPPED_ROBOTS: tuple[ShippedRobot, ...] = tuple(dict.fromkeys(
    [ShippedRobot(arm.urdf, arm.joints, arm.locked) for arm in POSE_ARMS.values()]
    + [ShippedRobot(arm.urdf) for arm in ARMS.values()]
    + [ShippedRobot(UR5_URDF)]))


def shipped_names() -> dict[str, ShippedRobot]:
    """The entry file name of each of :data:`SHIPPED_ROBOTS` with the installed URDFs."""
    return {entry_name(installed_urdf(robot.urdf), robot.joints, dict(robot.locked)): robot for robot in SHIPPED_ROBOTS}


def main() -> None:
    """Fit every one of :data:`SHIPPED_ROBOTS` afresh and write :data:`SHIPPED_DIR` anew."""
    with tempfile.TemporaryDirectory() as folder:
        for name, robot in shipped_names().items():
            model = auto_collision_model(installed_urdf(robot.urdf), robot.joints, dict(robot.locked),
                                         cache=Path(folder), shipped=False)
            print(f"{robot.urdf} ({len(model.spheres)} spheres, {len(model.self_collision_pairs)} pairs): {name}",
                  file=sys.stderr)
        SHIPPED_DIR.mkdir(parents=True, exist_ok=True)
        for old in SHIPPED_DIR.glob("collision-*.json"):
            old.unlink()
        for fitted in Path(folder).glob("collision-*.json"):
            (SHIPPED_DIR / fitted.name).write_bytes(fitted.read_bytes())


if __name__ == "__main__":
    main()
