"""MotionBenchMaker's IK onto a query (``ProblemGenerator::setStateFromQuery``): a pose of
the Panda's IK tip ``panda_link8`` sampled within a query's tolerances about its target,
and a configuration reaching it free of the scene and of self-collision on Franka's meshes.

The tip's target ``T_8`` (4x4, robot base frame) is ``T_object · T_offset · T_ee⁻¹``
(:mod:`~dynfab.benchmarks.mbm.scene_configs`). Per attempt the position is drawn uniformly
in the box of full edges ``position_tolerance`` [m] (world axes) centred on ``T_8``'s, the
rotation as ``R_8 · Rx(a) Ry(b) Rz(c)`` with ``a, b, c`` uniform within
±``orientation_tolerance`` [rad] (robowflex's ``TF::sampleOrientation``); inverse
kinematics (:data:`IK_SETTINGS`, the first seed ``initial``: MoveIt's current state, by
default :data:`READY`) must put the tip on that pose within the joint limits. MBM tries 200
times; here :data:`POSE_ATTEMPTS` poses of 10 seeds each.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from dynfab.benchmarks.mbm.franka import Franka
from dynfab.benchmarks.mbm.scene_configs import Query, pose_matrix
from dynfab.motion.inverse_kinematics import AxisTarget, IkSettings, PointTarget, solve_ik
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes

__all__ = ["IK_SETTINGS", "POSE_ATTEMPTS", "READY", "TIP_LINK", "free_query_ik", "is_free"]

#: MBM's IK tip for the Panda (its ``panda_arm`` group's chain ends there).
TIP_LINK = "panda_link8"
#: Inverse kinematics per sampled tip pose (10 seeds: with :data:`POSE_ATTEMPTS`, MBM's 200).
IK_SETTINGS = IkSettings(seeds=10, iterations=100, tolerance=1e-6, solutions=1, time_limit=1e9)
#: Tip poses sampled per query before the scene is drawn again.
POSE_ATTEMPTS = 20
#: MBM's Panda state (``configs/robots/panda.yaml``): the first IK seed, and the start of the
#: problems whose queries file has no ``start_queries`` [rad].
READY: tuple[float, ...] = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)


def is_free(robot: Franka, q: Sequence[float] | NDArray[np.float64], shapes: Sequence[PlacedShape]) -> bool:
    """Whether ``q`` touches neither ``shapes`` nor the robot itself on Franka's meshes."""
    sweep = sweep_meshes(robot.meshes, np.asarray(q, dtype=float)[None], list(shapes))
    return not sweep.obstacle_contacts and not sweep.self_contacts


def free_query_ik(robot: Franka, target: NDArray[np.float64], query: Query, shapes: Sequence[PlacedShape],
                  rng: np.random.Generator, initial: Sequence[float] = READY
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """A free configuration putting ``panda_link8`` on a pose sampled within ``query``'s
    tolerances about ``target`` (module doc), IK seeded first at ``initial`` [rad], and that
    pose (4x4); None after :data:`POSE_ATTEMPTS` poses."""
    for _ in range(POSE_ATTEMPTS):
        position = target[:3, 3] + rng.uniform(-0.5, 0.5, 3) * np.asarray(query.position_tolerance)
        turn = Rotation.from_euler("XYZ", rng.uniform(-1.0, 1.0, 3) * np.asarray(query.orientation_tolerance))
        rotation = target[:3, :3] @ turn.as_matrix()
        targets: list[PointTarget | AxisTarget] = [PointTarget(TIP_LINK, tuple(float(v) for v in position))]
        targets += [AxisTarget(TIP_LINK, tuple(float(v) for v in np.eye(3)[k]), tuple(float(v) for v in rotation[:, k]))
                    for k in range(3)]
        settings = IkSettings(**{**IK_SETTINGS.__dict__, "seed": int(rng.integers(2**31))})
        result = solve_ik(robot.robot, targets, np.array(initial, dtype=float), lambda q: is_free(robot, q, shapes),
                          settings)
        if result.q is not None:
            return result.q, pose_matrix(position, rotation)
    return None
