"""Guidance's last resort among primitives and meshes (``among_meshes``; never among
point clouds nor among moving obstacles): where no attempt found an escape of
a blocked goal (``goal_in_collision``, also at ``tight_margin``) or a path (``no_path``), a
path judged on the robot's meshes wherever its spheres refuse
(:func:`~dynfab.motion.mesh_escape.mesh_path`), from the start to the goal.

It keeps a margin ``m`` on the meshes: first each of ``mesh_escape.clearances`` (6 mm, one
search), then ``mesh_margin`` (3 mm, a search with each seed of guidance's attempts), until a
search finds a path (the fabric strays 2-3 mm off the part the spheres refuse: a wider
margin leaves it room). Within ``mesh_escape.end_radius`` of an end nearer them than ``m``, ``0.9 c`` (``c``
that end's clearance on them: an end at exactly its margin would touch it; kept everywhere,
seed-4 kitchen/0008's 0.4 mm start made a path the robot strayed off into the cupboard). The
path is checked again with the exact mesh distances every half ``path.resolution`` at half
its least margin
(:meth:`~dynfab.motion.mesh_goal_check.MeshGoalCheck.polyline_free`): the search sampled
every ``mesh_escape.resolution``. It is cut at its last configuration the spheres accept by
the planner's margin (:func:`_split`): the way there is timed as any plan's, the rest is the
plan's approach, timed at ``approach_speed`` and followed closely, the obstacles' leaves given
allowances along it so that they see the meshes' clearance (:func:`mesh_allowances`;
:mod:`dynfab.motion.approach_segment` measures a polyline on its nearest piece). Each search is bounded by its mesh checks (``mesh_escape.checks``), all of them
together by ``mesh_escape.total_checks`` and by ``mesh_escape.budget`` seconds of wall time
from the plan's start (guidance's attempts before it included; in the simulators, whose
plans are bounded by checks at any load, ``WALL_FACTOR`` times as long): spent, the plan
fails with ``mesh_escape_budget``. A simulated run does not wait for it (a plan's latency
is fixed), a robot in real time would.

It is not searched among moving obstacles (one with a velocity other than zero): its
searches take tens of seconds (90 000 mesh checks at 0.3-0.5 ms each) and the scene has
changed when they end; the plan fails with its reason and is asked for again as the
obstacle moves on. Moving-sphere bookshelf_thin/0089 (``--seed 17``, session 24) searched it
eight times among the sphere, as it was or as the capsule it sweeps, each to its budget,
and none found a path; the run took 614 s of wall time for its 20 s and reached its goal on
a later plan.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.shapes import Mesh, PointCloud
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance_settings import GuidanceSettings
from dynfab.motion.joint_planning import WALL_FACTOR
from dynfab.motion.joint_trajectory import JointTrajectory, TimingError, time_path
from dynfab.motion.mesh_escape import MeshEscapeSettings, SpheresOrMeshes, mesh_path
from dynfab.motion.mesh_goal_check import MeshGoalCheck, placed_shapes
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.motion.placed_obstacle import any_moving
from dynfab.motion.plan_values import GuidanceError, Plan
from dynfab.robots.limits import MotionLimits
from dynfab.robots.mesh_collision import MeshCollisionModel, moving_part
from dynfab.robots.mesh_contact import MeshContactCheck
from dynfab.robots.mesh_sweep import clearance_per_sample

__all__ = ["END_SHARE", "LEAF_SLACK", "EscapeScene", "escape_plan", "mesh_allowances", "search_margins"]

#: the share of the nearer end's clearance on the meshes the path keeps where that is
#: nearer than the search's margin (an end at exactly the margin would touch it) [-]
END_SHARE = 0.9
#: ``s`` of :func:`mesh_allowances`: what the leaves see beyond the meshes' clearance along
#: the plan's approach [m]. Chosen on development kitchen seeds 1-4 (the runs of
#: docs/results.md, session 14): at 0 seed-3 kitchen/0019 ended 9 mrad short of its goal
#: at 20 s (1.4 mm clear); at 3 mm it was reached at 18.4 s (0.56 mm clear).
LEAF_SLACK = 0.003


@dataclass(frozen=True)
class EscapeScene:
    """What the meshes' plan needs of guidance (:class:`~dynfab.motion.guidance.JointGuidance`).

    Attributes:
        checker: the configuration checker, its obstacles set.
        meshes: the exact check of the robot's meshes against them (its margin ``mesh_margin``).
        settings: guidance's settings (``mesh_escape`` set).
        limits: the robot's motion limits.
        lower, upper: the joint limits the search keeps (n,) [rad].
        approach_timed: times an approach's polyline (k, n) [rad] as guidance times one.
    """

    checker: ConfigurationChecker
    meshes: MeshGoalCheck
    settings: GuidanceSettings
    limits: MotionLimits
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    approach_timed: Callable[[NDArray[np.float64]], JointTrajectory]


def search_margins(settings: MeshEscapeSettings, mesh_margin: float) -> tuple[float, ...]:
    """The margins searched, in order [m]: ``settings.clearances`` above ``mesh_margin``,
    largest first, then ``mesh_margin``."""
    return tuple(sorted({c for c in settings.clearances if c > mesh_margin}, reverse=True)) + (mesh_margin,)


def escape_plan(scene: EscapeScene, start: NDArray[np.float64], target: NDArray[np.float64],
                seeds: Sequence[int], began: float) -> Plan | None:
    """The plan of the module docstring from ``start`` to ``target`` among ``scene``'s
    obstacles, searched at each margin of :func:`search_margins` with the first
    ``wide_searches`` of ``seeds`` (at ``mesh_margin`` with each) (the first path found that
    passes the exact check kept); None among point clouds, among meshes unless
    ``among_meshes``, among moving obstacles, without ``mesh_escape``
    settings, or if every search ended within its checks without such a path.

    Args:
        scene: what it needs of guidance.
        start: the start (n,) [rad].
        target: the goal (n,) [rad], blocked on the spheres.
        seeds: the searches' seeds at each margin.
        began: when the plan began (``time.perf_counter()``) [s].

    Raises:
        GuidanceError: ``mesh_escape_budget``, its budget spent (``total_checks`` mesh
            checks, or ``budget`` seconds from ``began``: ``WALL_FACTOR`` times as many
            where ``path.check_rate`` is set).
    """
    settings, path = scene.settings.mesh_escape, scene.settings.path
    shapes = [o.shape for o in scene.checker.obstacles]
    if (settings is None or any(isinstance(s, PointCloud) for s in shapes) or any_moving(scene.checker.obstacles)
            or (not settings.among_meshes and any(isinstance(s, Mesh) for s in shapes))):
        return None
    wall = settings.budget * (1.0 if path.check_rate is None else WALL_FACTOR)
    spent, searched = 0, 0
    for margin in search_margins(settings, scene.meshes.margin):
        validity = _validity(scene, start, target, margin)
        least = min([margin] + [check.margin for _, check in validity.ends])
        for seed in seeds if margin == scene.meshes.margin else seeds[:settings.wide_searches]:
            left = began + wall - time.perf_counter()
            if left <= 0.0 or spent >= settings.total_checks:
                raise GuidanceError("mesh_escape_budget", f"the meshes' plan found no path within its budget "
                                    f"({settings.total_checks} mesh checks, {wall:g} s; {searched} searches, "
                                    f"{spent} checks, {time.perf_counter() - began:.1f} s spent)")
            before = validity.mesh_checks
            this = replace(settings, checks=min(settings.checks, settings.total_checks - spent))
            way = mesh_path(validity, start, target, scene.lower, scene.upper, this, seed, left)
            spent, searched = spent + validity.mesh_checks - before, searched + 1
            if way is not None and scene.meshes.polyline_free(way, path.resolution / 2, least / 2):
                return _timed_plan(scene, way, target, began, validity.checks)
    return None


def _validity(scene: EscapeScene, start: NDArray[np.float64], target: NDArray[np.float64],
              margin: float) -> SpheresOrMeshes:
    """The search's validity at ``margin`` [m] (:class:`SpheresOrMeshes`): an end nearer the
    meshes than it keeps ``END_SHARE`` of its own clearance within ``end_radius`` of it."""
    settings = scene.settings.mesh_escape
    assert settings is not None
    obstacles, model = scene.checker.obstacles, scene.meshes.model
    ends = []
    for end in (start, target):
        clearance = scene.meshes.clearance(end)[0]
        if clearance < margin:
            check = MeshContactCheck(model, max(0.0, END_SHARE * clearance))
            check.set_obstacles(obstacles)
            ends.append((end, check))
    contact = MeshContactCheck(model, margin)
    contact.set_obstacles(obstacles)
    return SpheresOrMeshes(scene.checker, contact, settings.coverage, scene.settings.path.self_margin, start.size,
                           tuple(ends), settings.end_radius)


def _timed_plan(scene: EscapeScene, way: NDArray[np.float64], target: NDArray[np.float64], began: float,
                checks: int) -> Plan | None:
    """``way`` cut at its last configuration the spheres accept by the planner's margin
    (:func:`_split`): the way there timed as any plan's, the rest as an approach; None if
    it cannot be timed."""
    path, settings, limits = scene.settings.path, scene.settings, scene.limits
    cruise, approach = _split(way, lambda q: scene.checker.free(q, path.margin, path.self_margin),
                              path.resolution / 2)
    try:
        phases = (() if cruise is None else
                  (time_path(cruise, settings.speed * limits.velocity, settings.acceleration * limits.acceleration,
                             settings.timing),))
        trajectory = PhasedTrajectory(phases + (scene.approach_timed(approach),))
    except TimingError:
        return None
    length = float(np.sum(np.linalg.norm(np.diff(approach, axis=0), axis=1)))
    return Plan(trajectory, target, time.perf_counter() - began, checks, length, float(trajectory.starts[-1]))


def mesh_allowances(model: MeshCollisionModel, segment: NDArray[np.float64], obstacles: Sequence[PlacedObstacle],
                    buffers: Sequence[float], spheres: NDArray[np.float64], goal_clearance: float
                    ) -> NDArray[np.float64]:
    """The obstacles' allowances along this plan's approach (k samples ``segment``, m
    ``obstacles``) [m]: what the fabric's leaves need to see, at each sample, the meshes'
    clearance from each obstacle there plus :data:`LEAF_SLACK`, at most ``goal_clearance``:

        a_k(q) = max(0, buffer_k + min(goal_clearance, m_k(q) + s) − c_k(q))

    with ``m_k`` the robot's meshes' distance from obstacle ``k`` (exact, the links a joint
    moves) and ``c_k`` its spheres' (``spheres``, (k, m)). A grasp's approach gives
    ``goal_clearance`` everywhere (:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`):
    along this one, which runs millimetres from the meshes for radians, the leaves then saw
    15 mm of room where the meshes had 3-6 mm, and the robot strayed 2-3 mm off the path
    toward them (development kitchen seed 1 kitchen/0014, seed 3 kitchen/0019: 0.73 and
    0.28 mm from the kitchen). The barrier brakes only a motion toward the obstacle, harder
    the nearer it reads (:mod:`dynfab.fabric.leaves.barrier`)."""
    moving = moving_part(model)
    meshes = np.column_stack([clearance_per_sample(moving, segment, (shape,)) for shape in placed_shapes(obstacles)]
                             ) if obstacles else np.zeros((len(segment), 0))
    return np.maximum(0.0, np.asarray(buffers, dtype=float) + np.minimum(goal_clearance, meshes + LEAF_SLACK) - spheres)


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
