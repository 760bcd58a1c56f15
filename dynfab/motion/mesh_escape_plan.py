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
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.shapes import PointCloud
from dynfab.motion.joint_planning import JointPlannerSettings, NoPathError, plan_joint_path
from dynfab.motion.joint_trajectory import TimingError, time_path
from dynfab.motion.mesh_escape import mesh_escape
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.robots.mesh_contact import MeshContactCheck

if TYPE_CHECKING:
    from dynfab.motion.guidance import JointGuidance, Plan

__all__ = ["escape_plan"]


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
    contact = MeshContactCheck(meshes.model, max(0.0, min(meshes.margin, meshes.clearance(target)[0])))
    contact.set_obstacles(guidance.checker.obstacles)
    escape = mesh_escape(contact, target, lambda q: guidance.checker.free(q, 0.0, path.self_margin),
                         guidance._lower, guidance._upper, settings, tries[0][1])
    if escape is None or not meshes.polyline_free(escape, path.resolution / 2, contact.margin / 2):
        return None
    for leave in dict.fromkeys(guidance._endpoint_tests(start)):
        for attempt, seed in tries:
            try:
                way = plan_joint_path(guidance.checker, start, escape[-1], guidance._lower, guidance._upper,
                                      attempt, seed, None, leave)
                kept = len(way.waypoints) - int(way.escaped_goal)   # the end's own escape joins the approach
                way_in = np.vstack([way.waypoints[kept - 1:], escape[-2::-1]])
                trajectory = PhasedTrajectory((time_path(way.waypoints[:kept], guidance.settings.speed * limits.velocity,
                                                         guidance.settings.acceleration * limits.acceleration,
                                                         guidance.settings.timing),
                                               guidance._approach_timed(way_in)))
            except (NoPathError, TimingError):
                continue
            length = float(np.sum(np.linalg.norm(np.diff(way_in, axis=0), axis=1)))
            return Plan(trajectory, target, time.perf_counter() - began, way.checks + contact.checks, length,
                        float(trajectory.starts[-1]))
    return None
