"""Guidance's last resort among meshes (no point clouds): where no attempt found an escape of
a blocked goal (``goal_in_collision``, also at ``tight_margin``) or a path (``no_path``), a
path judged on the robot's meshes wherever its spheres refuse
(:func:`~dynfab.motion.mesh_escape.mesh_path`), from the start to the goal.

It keeps ``mesh_margin`` on the meshes, but within ``mesh_escape.end_radius`` of an end
nearer them ``0.9 c`` (``c`` that end's clearance on them: an end at exactly its margin would
touch it; kept everywhere, seed-4 kitchen/0008's 0.4 mm start made a path the robot strayed
off into the cupboard), and is checked again with the exact mesh distances every half
``path.resolution`` at half its least margin
(:meth:`~dynfab.motion.mesh_goal_check.MeshGoalCheck.polyline_free`): the search sampled
every ``mesh_escape.resolution``. It is cut at its last configuration the spheres accept by
the planner's margin (:func:`_split`): the way there is timed as any plan's, the rest is the
plan's approach, timed at ``approach_speed`` and followed closely, the obstacles' leaves given
the allowances the spheres need along it
(:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`), as for a grasp's
straight approach (:mod:`dynfab.motion.approach_segment` measures a polyline on its nearest
piece). Simulated (``path.check_rate`` set), the search is bounded by its mesh checks, its
wall time only at ``WALL_FACTOR`` times ``mesh_escape.wall_time``.

Cost (development kitchen, seeds 0-4, load 6-8): 30-300 s of wall time for a plan that
runs it (kitchen/0005, seed 1: 66 s); a simulated run does not wait for it (a plan's
latency is fixed), a robot in real time would.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.shapes import PointCloud
from dynfab.motion.joint_planning import WALL_FACTOR, JointPlannerSettings
from dynfab.motion.joint_trajectory import TimingError, time_path
from dynfab.motion.mesh_escape import SpheresOrMeshes, mesh_path
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.motion.plan_values import Plan
from dynfab.robots.mesh_contact import MeshContactCheck

if TYPE_CHECKING:
    from dynfab.motion.guidance import JointGuidance

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
    meshes, settings = guidance._meshes(), guidance.settings.mesh_escape
    if (meshes is None or settings is None
            or any(isinstance(o.shape, PointCloud) for o in guidance.checker.obstacles)):
        return None
    path, limits = guidance.settings.path, guidance.robot.limits
    if path.check_rate is not None:   # simulated: its checks bound it, the wall time far beyond (the same at any load)
        settings = replace(settings, wall_time=settings.wall_time * WALL_FACTOR)
    ends = []
    for end in (start, target):   # an end nearer the meshes than mesh_margin: its own margin near it
        clearance = meshes.clearance(end)[0]
        if clearance < meshes.margin:
            check = MeshContactCheck(meshes.model, max(0.0, END_SHARE * clearance))
            check.set_obstacles(guidance.checker.obstacles)
            ends.append((end, check))
    contact = MeshContactCheck(meshes.model, meshes.margin)
    contact.set_obstacles(guidance.checker.obstacles)
    margin = min([contact.margin] + [check.margin for _, check in ends])
    validity = SpheresOrMeshes(guidance.checker, contact, settings.coverage, path.self_margin, start.size,
                               tuple(ends), settings.end_radius)
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
