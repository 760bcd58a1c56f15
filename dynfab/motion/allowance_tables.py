"""How far the guided fabric's spheres may enter each static obstacle, so that its leaves let
it follow what guidance planned (issue 19): at a goal nearer an obstacle than the planner's
margin (a grasp), along the plan's approach to it, and along the plan's way, where the plan
was checked on tighter spheres than the fabric avoids with
(:class:`~dynfab.motion.guidance.JointGuidance` delegates here;
:meth:`~dynfab.motion.guided_fabric.GuidedFabric.allowances` applies them).

Every allowance is read on the fabric's own spheres, one obstacle at a time: ``c_k(q)``, the
clearance [m] of the robot's spheres at ``q`` from obstacle ``k`` alone (a mesh's or a point
cloud's: what the fabric's nearest-point leaf sees).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.fabric.leaves.surface_points import moving_spheres
from dynfab.geometry.shapes import Mesh, PointCloud
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.placed_obstacle import any_cloud
from dynfab.motion.guidance_settings import GuidanceSettings
from dynfab.motion.joint_planning import polyline_samples
from dynfab.motion.mesh_escape_plan import mesh_allowances
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.motion.obstacle_buffer import mesh_grid
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.motion.plan_values import Plan
from dynfab.perception.surfaces import surface_clearance
from dynfab.robots.robot import Robot

__all__ = ["AllowanceTables", "departure_rows", "way_waypoints"]


def way_waypoints(plan: Plan) -> NDArray[np.float64]:
    """``plan``'s waypoints before its approach (k, n) [rad]: the approach's phase is the
    last, its first configuration ends the way."""
    waypoints = plan.trajectory.waypoints
    if plan.approach > 0.0:
        waypoints = waypoints[:len(waypoints) - len(plan.trajectory.phases[-1].waypoints) + 1]
    return waypoints


def departure_rows(plan: Plan, resolution: float) -> int:
    """How many of the configurations of :meth:`AllowanceTables.way` (``resolution`` [rad]
    apart) lie on ``plan``'s departure, a blocked start's way out (0 without one)."""
    if plan.departure <= 0.0:
        return 0
    return len(polyline_samples(way_waypoints(plan)[:2], resolution))


class AllowanceTables:
    """The allowances of the module docstring for ``robot`` with ``settings``."""

    def __init__(self, robot: Robot, settings: GuidanceSettings) -> None:
        self._robot = robot
        self._settings = settings
        self._single = ConfigurationChecker(robot)   # one obstacle at a time, the fabric's spheres
        self._single_planning = ConfigurationChecker(robot.planning_robot)   # the same on the plans'
        self._leaf_spheres = list(moving_spheres(robot))   # those a nearest-point leaf acts on
        self._leaf_radii = np.asarray(robot.sphere_radii, dtype=float)[self._leaf_spheres]

    def at(self, q: NDArray[np.float64], obstacles: Sequence[PlacedObstacle],
           buffers: Sequence[float]) -> NDArray[np.float64]:
        """How far [m] the fabric's spheres may enter each obstacle so that its leaves,
        which keep ``buffers[k]`` of clearance, still see ``goal_clearance`` at ``q``:
        ``a_k = max(0, buffer_k + goal_clearance − c_k(q))``."""
        if not obstacles:
            return np.zeros(0)
        clearances = np.array([self.obstacle_clearance(q, obstacle) for obstacle in obstacles])
        return np.maximum(0.0, np.asarray(buffers, dtype=float) + self._settings.goal_clearance - clearances)

    def approach(self, plan: Plan, obstacles: Sequence[PlacedObstacle], buffers: Sequence[float],
                 meshes: Callable[[], MeshGoalCheck | None]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`at` along ``plan``'s approach: its configurations every
        ``path.resolution`` from its start to the goal (k, n) [rad] and the allowances of
        ``obstacles`` at each (k, m) [m]. The straight approach may pass closer to an
        obstacle than the goal is (a table under a grasp), where the leaves would hold the
        robot short of the goal (problems 21-28, as posed: table_pick); what it may pass
        matters only until the robot is past it. Along the meshes' plan's polyline approach
        (more than two configurations, among meshes without clouds; ``meshes()`` the mesh
        check, None without meshes) the leaves see the meshes' clearance instead
        (:func:`~dynfab.motion.mesh_escape_plan.mesh_allowances`)."""
        if not isinstance(plan.trajectory, PhasedTrajectory):
            raise ValueError("approach_allowances: the plan has no approach")
        waypoints = plan.trajectory.phases[-1].waypoints
        segment = polyline_samples(waypoints, self._settings.path.resolution)
        goal_clearance = self._settings.goal_clearance
        if (len(waypoints) > 2 and not any_cloud(obstacles)
                and (check := meshes()) is not None):   # the meshes' plan's polyline (mesh_escape_plan)
            return segment, self._seeing_meshes(check, segment, obstacles, buffers)
        clearances = np.empty((len(segment), len(obstacles)))
        for k, obstacle in enumerate(obstacles):
            clearances[:, k] = self._clearances(self._single, segment, obstacle)
        return segment, np.maximum(0.0, np.asarray(buffers, dtype=float) + goal_clearance - clearances)

    def way(self, plan: Plan, obstacles: Sequence[PlacedObstacle], buffers: Sequence[float],
            meshes: Callable[[], MeshGoalCheck | None] = lambda: None
            ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The configurations of ``plan``'s way (its polyline before an approach) every
        ``path.resolution`` (k, n) [rad] and the allowance of each of ``obstacles`` at each
        (k, m) [m]: what the fabric's leaves, on the robot's own spheres, need to see at
        least what the plan's (tighter) planning spheres show less ``sphere_coverage``, at
        most ``way_clearance``:

            a_k(q) = max(0, buffer_k + min(way_clearance, p_k(q) − sphere_coverage) − c_k(q))

        with ``p_k`` the planning spheres' clearance from obstacle ``k`` alone [m]. Zero
        where both are the same spheres (then ``c_k = p_k`` and ``buffer_k ≤
        sphere_coverage``: the default 5 mm each), and for point clouds (their grids read
        ``δ`` below noisy points). A mesh's ``p_k`` is its grid's bound, which reads low,
        so the leaves see no more than the meshes' clearance (since session 22: fresh
        kitchen seed 21's kitchen/0003 was held four times where the planning spheres'
        grid kept 14-16 mm from a cabinet and the fabric's spheres read 6-7 mm, against
        their 5 mm buffer). Along a blocked start's way out
        (:attr:`~dynfab.motion.plan_values.Plan.departure`, judged on the robot's meshes;
        ``meshes()`` the mesh check, None without meshes; not among point clouds) the
        leaves see the meshes' clearance from every mesh obstacle instead, as along the
        meshes' plan's approach (:func:`~dynfab.motion.mesh_escape_plan.mesh_allowances`): on the
        spheres, which leave up to ``sphere_coverage`` of the meshes outside, such a start
        is inside the obstacle, the leaves' barrier stops every motion deeper at its clamp,
        and the robot slid along the way out off it (fresh kitchen seed 20, kitchen/0007: a
        start 0.16 mm from the cupboard, 6.6 mm into it on the fabric's spheres;
        ``panda_link5`` touched the cupboard while leaving). Not from boxes, cylinders and
        spheres: there the allowance's 3 mm of slack let a robot held beside a grasp's
        approach (fresh generated seed 21, as posed table_under_pick/0005) put
        ``panda_link7`` 1.1 mm into a box on leaving, where it had touched 0.16 mm deep (a
        box's way allowance kept 0.25 rad off the way; they fade off it since:
        :mod:`~dynfab.motion.way_window`)."""
        settings = self._settings
        samples = polyline_samples(way_waypoints(plan), settings.path.resolution)
        table = np.zeros((len(samples), len(obstacles)))
        if self._robot.planning_robot is not self._robot:
            self._planned_way(samples, obstacles, buffers, table)
        columns = [k for k, o in enumerate(obstacles) if isinstance(o.shape, Mesh)]
        if plan.departure > 0.0 and columns and not any_cloud(obstacles):
            check = meshes()
            if check is not None:
                leaving = departure_rows(plan, settings.path.resolution)
                table[:leaving, columns] = np.maximum(table[:leaving, columns], self._seeing_meshes(
                    check, samples[:leaving], [obstacles[k] for k in columns], [buffers[k] for k in columns]))
        return samples, table

    def way_at(self, q: NDArray[np.float64], obstacles: Sequence[PlacedObstacle], buffers: Sequence[float],
               columns: Sequence[int]) -> NDArray[np.float64]:
        """The allowance of :meth:`way` of each of ``obstacles`` in ``columns`` at the robot's
        own configuration ``q`` [rad] (the others' 0) [m], as the planning spheres give it
        (not from point clouds, nor the meshes' clearance of a departure):

            a_k(q) = max(0, buffer_k + min(way_clearance, p_k(q) − sphere_coverage) − c_k(q)),

        ``c_k`` looked for only within ``buffer_k + way_clearance`` (beyond it ``a_k = 0``).
        ``p_k − sphere_coverage`` is at most the meshes' clearance at any ``q``, on the plan's
        way or off it: capped by it, an allowance read on the way holds the robot's spheres
        no deeper than its meshes allow where the robot is
        (:meth:`~dynfab.motion.guided_fabric.GuidedFabric.allowances`)."""
        settings = self._settings
        allowances = np.zeros(len(obstacles))
        for k in columns:
            obstacle = obstacles[k]
            within = buffers[k] + settings.way_clearance
            if isinstance(obstacle.shape, PointCloud) or (fabric := self.obstacle_clearance(q, obstacle, within)) >= within:
                continue
            self._single_planning.set_obstacles((obstacle,))
            allowances[k] = self._way_rule(buffers[k], self._single_planning.clearances(q)[0], fabric)
        return allowances

    def _way_rule(self, buffer: float, planned: ArrayLike, fabric: ArrayLike) -> NDArray[np.float64]:
        """``a = max(0, buffer + min(way_clearance, p − sphere_coverage) − c)`` [m] of
        :meth:`way` for the planning spheres' clearance ``p`` and the fabric's ``c`` [m]."""
        settings = self._settings
        return np.maximum(0.0, buffer + np.minimum(settings.way_clearance,
                                                   np.asarray(planned) - settings.sphere_coverage) - fabric)

    def _seeing_meshes(self, check: MeshGoalCheck, segment: NDArray[np.float64],
                       obstacles: Sequence[PlacedObstacle], buffers: Sequence[float]) -> NDArray[np.float64]:
        """The allowances (k, m) [m] at ``segment`` (k, n) that let the leaves see the
        robot's meshes' clearance from each of ``obstacles``
        (:func:`~dynfab.motion.mesh_escape_plan.mesh_allowances`, on the fabric's clearances
        :meth:`obstacle_clearance`)."""
        spheres = np.array([[self.obstacle_clearance(q, o) for o in obstacles] for q in segment])
        return mesh_allowances(check.model, segment, obstacles, buffers, spheres.reshape(len(segment), len(obstacles)),
                               self._settings.goal_clearance)

    def _planned_way(self, samples: NDArray[np.float64], obstacles: Sequence[PlacedObstacle],
                     buffers: Sequence[float], table: NDArray[np.float64]) -> None:
        """Write into ``table`` (k, m) the allowances of :meth:`way` that the planning
        spheres give at ``samples`` (k, n) [m] (primitives and meshes, not point clouds).
        A mesh's ``p_k`` is the planning spheres' grid bound, at most their exact clearance
        (what the plan kept), and its ``c_k`` the fabric's exact one
        (:meth:`obstacle_clearance`), asked only where the fabric spheres' grid bound, at
        most ``c_k``, is within ``buffer_k + way_clearance`` (elsewhere ``a_k = 0``)."""
        settings = self._settings
        for k, obstacle in enumerate(obstacles):
            if isinstance(obstacle.shape, PointCloud):
                continue
            fabric = self._clearances(self._single, samples, obstacle)
            near = np.flatnonzero(fabric < buffers[k] + settings.way_clearance)   # elsewhere a_k = 0
            if near.size == 0:
                continue
            if isinstance(obstacle.shape, Mesh):
                fabric[near] = [self.obstacle_clearance(q, obstacle) for q in samples[near]]
            planned = self._clearances(self._single_planning, samples[near], obstacle)
            table[near, k] = self._way_rule(buffers[k], planned, fabric[near])

    def obstacle_clearance(self, q: NDArray[np.float64], obstacle: PlacedObstacle, within: float = np.inf) -> float:
        """``c_k(q)`` [m] (module docstring): the checker's, or for a mesh or a point cloud
        what the fabric's nearest-point leaf sees
        (:func:`~dynfab.perception.surfaces.surface_clearance` of the spheres a joint moves:
        exact for a mesh, where the checker's grid reads up to ``h√3`` less). With a finite
        ``within`` [m], a mesh's exact distances are asked only for the spheres its grid's
        lower bound puts within it (:meth:`way_at` near MBM table_bars' meshes: 0.4-0.9 ms, not
        1.5-2 ms), and a clearance
        of at least ``within`` may read ``within`` (a sphere whose centre is farther inside
        a closed mesh than ``within`` plus its radius is not seen: the grid bounds the
        unsigned distance)."""
        if isinstance(obstacle.shape, Mesh | PointCloud):
            centres = np.asarray(self._robot.sphere_centers(q))[self._leaf_spheres]
            radii = self._leaf_radii
            if isinstance(obstacle.shape, Mesh) and np.isfinite(within):
                bound = mesh_grid(obstacle.shape).lower_bound(obstacle.placement.to_local(centres)) - radii
                near = bound < within
                if not near.any():
                    return within
                centres, radii = centres[near], radii[near]
            return surface_clearance(centres, radii, obstacle.shape, obstacle.placement)
        self._single.set_obstacles((obstacle,))
        return self._single.clearances(q)[0]

    @staticmethod
    def _clearances(checker: ConfigurationChecker, samples: NDArray[np.float64],
                    obstacle: PlacedObstacle) -> NDArray[np.float64]:
        """The clearance [m] of ``checker``'s spheres from ``obstacle`` alone at each of ``samples`` (k,)."""
        checker.set_obstacles((obstacle,))
        return checker.batch(samples)[:, 0]
