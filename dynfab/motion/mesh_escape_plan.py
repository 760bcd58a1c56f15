"""The plan to a goal no attempt of guidance escaped among meshes (no point clouds): the
goal's escape on the robot's meshes (:func:`~dynfab.motion.mesh_escape.mesh_escape`), the
spheres' path from the start to the escape's end, and the escape backwards as the plan's
approach.

The escape is grown at ``m = min(mesh_margin, c(goal))`` from the obstacles (``c`` the
goal's clearance on the meshes), then checked with the exact mesh distances every half
``path.resolution`` at ``m / 2``
(:meth:`~dynfab.motion.mesh_goal_check.MeshGoalCheck.polyline_free`): the boolean check
sees surfaces only and samples every ``mesh_escape.resolution``. The approach is timed at
``approach_speed`` and followed closely, the obstacles' leaves given the allowances the
spheres need along it (:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`),
as for a grasp's straight approach; the robot's meshes keep their distance along it, its
spheres need not.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.shapes import PointCloud
from dynfab.motion.joint_planning import JointPlannerSettings
from dynfab.motion.joint_trajectory import TimingError, time_path
from dynfab.motion.mesh_escape import SpheresOrMeshes, mesh_path
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.robots.mesh_contact import MeshContactCheck

if TYPE_CHECKING:
    from dynfab.motion.guidance import JointGuidance, Plan

__all__ = ["END_SHARE", "escape_plan"]

#: the share of the nearer end's clearance on the meshes the path keeps where that is
#: nearer than ``mesh_margin`` (an end at exactly the margin would touch it) [-]
END_SHARE = 0.9


def escape_plan(guidance: JointGuidance, start: NDArray[np.float64], target: NDArray[np.float64],
                tries: Sequence[tuple[JointPlannerSettings, int]], began: float) -> Plan | None:
    """The plan of the module docstring from ``start`` to ``target`` among ``guidance``'s
    obstacles: the first of ``tries`` (planner settings, seed) that plans to the escape's
    end, the start's way out judged as guidance judges it; None without meshes, among point
    clouds, without ``mesh_escape`` settings, or if the escape or every try fails.

    Args:
        guidance: the guidance planning (its checker holds the obstacles).
        start: the start (n,) [rad].
        target: the goal (n,) [rad], blocked on the spheres.
        tries: the attempts' settings and seeds.
        began: when the plan began (``time.perf_counter()``) [s].
    """
    from dynfab.motion.guidance import Plan   # guidance imports this module

    meshes, settings = guidance._meshes(), guidance.settings.mesh_escape
    if (meshes is None or settings is None
            or any(isinstance(o.shape, PointCloud) for o in guidance.checker.obstacles)):
        return None
    path, limits = guidance.settings.path, guidance.robot.limits
    ends = min(meshes.clearance(target)[0], meshes.clearance(start)[0])
    margin = max(0.0, min(meshes.margin, END_SHARE * ends))
    contact = MeshContactCheck(meshes.model, margin)
    contact.set_obstacles(guidance.checker.obstacles)
    validity = SpheresOrMeshes(guidance.checker, contact, settings.coverage, path.self_margin, start.size)
    for _, seed in tries:
        way = mesh_path(validity, start, target, guidance._lower, guidance._upper, settings, seed)
        if way is not None:
            break
    if way is None or not meshes.polyline_free(way, path.resolution / 2, margin / 2):
        return None
    cruise, approach = _split(way, lambda q: guidance.checker.free(q, path.margin, path.self_margin),
                              path.resolution / 2)
    try:
        phases = (() if cruise is None else
                  (time_path(cruise, guidance.settings.speed * limits.velocity,
                             guidance.settings.acceleration * limits.acceleration, guidance.settings.timing),))
        trajectory = PhasedTrajectory(phases + (guidance._approach_timed(approach),))
    except TimingError:
        return None
    length = float(np.sum(np.linalg.norm(np.diff(approach, axis=0), axis=1)))
    return Plan(trajectory, target, time.perf_counter() - began, validity.checks, length,
                float(trajectory.starts[-1]))


def _split(way: NDArray[np.float64], accept: Callable[[NDArray[np.float64]], bool], step: float
           ) -> tuple[NDArray[np.float64] | None, NDArray[np.float64]]:
    """``way`` (k, n) cut at its last configuration (of those ``step`` [rad] apart on it)
    that ``accept`` takes: the way there (None if that is its start) and the rest, the
    approach."""
    for piece in range(len(way) - 2, -1, -1):
        a, b = way[piece], way[piece + 1]
        count = max(1, int(np.ceil(float(np.linalg.norm(b - a)) / step)))
        for k in range(count, -1, -1):
            q = a + (b - a) * k / count
            if accept(q):
                if piece == 0 and k == 0:
                    return None, way
                return np.vstack([way[:piece + 1], q[None]]), np.vstack([q[None], way[piece + 1:]])
    return None, way
