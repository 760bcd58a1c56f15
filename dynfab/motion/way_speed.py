"""How fast a plan's way may be followed where it passes near meshes: the factor of the
way's velocity limits (``time_path(..., speed_scale)``, :mod:`dynfab.motion.joint_trajectory`).

    σ(q) = clip(c(q) / slow_clearance, slow_speed, 1)   [-]

with ``c`` the clearance of the robot's collision meshes from the plan's mesh obstacles [m]
(coal's exact distances, :func:`~dynfab.robots.mesh_sweep.clearance_per_sample`, measured
at every configuration where the planning spheres are nearer them than ``slow_clearance``,
elsewhere σ = 1: about 2 ms each in MBM's kitchen, whose cupboard's convex hull holds the
robot, so a way of 10 rad costs 0.3-0.7 s. Measured every 0.2 rad and interpolated, it cost
90 ms, but a finger passed a bar of fresh table_bars seed 33 at speed between two
measurements and touched it in 0007 and 0012);
for a robot without meshes the planning spheres' clearance; σ = 1 without mesh obstacles
(``slow_clearance`` and ``slow_speed`` of
:class:`~dynfab.motion.guidance_settings.GuidanceSettings`). A robot lagging ``e`` behind a
reference that turns a corner is pulled across it by about ``e`` times its lever; slower, it
lags less (MBM kitchen seed 11/0004 with a 10 cm mesh band: 0.07 rad behind at 0.5 of the
limits, a finger 11 mm into a cupboard). The room it has for that is the meshes' clearance:
the spheres stick out of the meshes by up to 1 cm at the hand and 2 cm on the arm, and read
from them the way crawled where the meshes had room (session 27: fresh kitchen seed 31/0002's
way, 10.8 rad, took 22 s of a 20 s run, 13.6 s of it below half speed, its spheres 17 mm and
its meshes 24 mm from the kitchen at the median). Only meshes slow it:

- primitives have their own guard, the reference waits where it is out of sight of the
  robot (:func:`~dynfab.motion.plan_joining.in_sight`), and slowed among them the way cost
  cage runs their 20 s (MBM object removed, cage 81-96: 14/16 slowed, 16/16 not);
- point clouds' grids read the larger spheres far lower than they are (a 3 cm exact band,
  the noise), and the way crawled (MBM points ``--seed 7``, cage 81-96: 10/16 slowed, 14/16
  not).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.shapes import Mesh
from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.guidance_settings import GuidanceSettings
from dynfab.motion.mesh_goal_check import placed_shapes, robot_mesh_model
from dynfab.robots.mesh_collision import moving_part
from dynfab.robots.mesh_sweep import clearance_per_sample
from dynfab.robots.robot import Robot

__all__ = ["WaySpeed"]


class WaySpeed:
    """``q ↦ σ(q)`` of the module docstring for ``robot``'s planning spheres and meshes."""

    def __init__(self, robot: Robot, settings: GuidanceSettings) -> None:
        self._robot = robot
        self._settings = settings
        self._meshes_alone = ConfigurationChecker(robot.planning_robot)   # the meshes among other shapes

    def scale(self, checker: ConfigurationChecker, qs: NDArray[np.float64]) -> NDArray[np.float64]:
        """``σ`` at each of ``qs`` (m, n) among ``checker``'s obstacles (``checker`` on the
        planning spheres) [-]."""
        obstacles = checker.obstacles
        meshes = [o for o in obstacles if isinstance(o.shape, Mesh)]
        if not meshes:
            return np.ones(len(qs))
        if len(meshes) < len(obstacles):   # among others: the planning spheres against the meshes alone
            self._meshes_alone.set_obstacles(meshes)
            checker = self._meshes_alone
        settings = self._settings
        qs = np.asarray(qs, dtype=float)
        clearance = checker.batch(qs)[:, 0]
        model = robot_mesh_model(self._robot)
        near = np.flatnonzero(clearance < settings.slow_clearance)
        if model is not None and near.size:
            clearance[near] = clearance_per_sample(moving_part(model), qs[near], placed_shapes(meshes),
                                                   cap=settings.slow_clearance)
        return np.clip(clearance / settings.slow_clearance, settings.slow_speed, 1.0)
