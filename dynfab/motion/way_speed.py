"""How fast a plan's way may be followed where it passes near meshes: the factor of the
way's velocity limits (``time_path(..., speed_scale)``, :mod:`dynfab.motion.joint_trajectory`).

    σ(q) = clip(c(q) / slow_clearance, slow_speed, 1)   [-]

with ``c`` the planning spheres' clearance from the plan's mesh obstacles [m] (σ = 1 without
meshes; ``slow_clearance`` and ``slow_speed`` of
:class:`~dynfab.motion.guidance_settings.GuidanceSettings`). A robot lagging ``e`` behind a
reference that turns a corner is pulled across it by about ``e`` times its lever; slower, it
lags less (MBM kitchen seed 11/0004 with a 10 cm mesh band: 0.07 rad behind at 0.5 of the
limits, a finger 11 mm into a cupboard). Only meshes slow it:

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
from dynfab.robots.robot import Robot

__all__ = ["WaySpeed"]


class WaySpeed:
    """``q ↦ σ(q)`` of the module docstring for ``robot``'s planning spheres."""

    def __init__(self, robot: Robot, settings: GuidanceSettings) -> None:
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
        clearance = checker.batch(qs)[:, 0]
        settings = self._settings
        return np.clip(clearance / settings.slow_clearance, settings.slow_speed, 1.0)
