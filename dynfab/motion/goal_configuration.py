"""The configuration guidance plans to (:meth:`~dynfab.motion.guidance.JointGuidance.goal_configuration`).

A joint goal as given, clipped into the limits when within :data:`LIMIT_SLACK` of them (a
value rounded when written counts as at the limit); further out, ``goal_outside_limits``.
A task goal through collision-free inverse kinematics, the solution nearest the robot, from
the first of these searches that finds one:

1. clear of obstacles by the planner's margin on the planning spheres (``ik``);
2. merely free: on the spheres' grid at margin 0, else on their exact distances, else on the
   robot's meshes by ``mesh_margin`` (``ik_retry``);
3. among meshes, free on them by ``mesh_goal_floor`` (a grasp nearer than their margin);
4. a nearby target inside half of the goal's tolerances, merely free, on the meshes by
   ``mesh_goal_floor`` (:func:`~dynfab.motion.goal_region.nearby_solution`);

else ``no_ik_solution``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.goal_region import nearby_solution
from dynfab.motion.guidance_settings import GuidanceSettings
from dynfab.motion.inverse_kinematics import solve_ik
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.motion.plan_values import GoalTargets, GuidanceError, JointTarget
from dynfab.robots.robot import Robot

__all__ = ["LIMIT_SLACK", "GoalSearch"]

#: a value within this of a joint limit counts as at the limit [rad or m]
LIMIT_SLACK = 1e-6


@dataclass(frozen=True)
class GoalSearch:
    """The searches of the module docstring for ``robot`` among ``checker``'s obstacles.

    Attributes:
        robot: the robot.
        checker: the planning spheres' checker, its obstacles set.
        meshes: the robot's mesh check against the same obstacles, made on first call
            (None without meshes).
        settings: guidance's settings.
        bounds: the joint bounds plans keep (lower, upper) [rad or m].
    """

    robot: Robot
    checker: ConfigurationChecker
    meshes: Callable[[], MeshGoalCheck | None]
    settings: GuidanceSettings
    bounds: tuple[NDArray[np.float64], NDArray[np.float64]]

    def configuration(self, goal: GoalTargets, q: NDArray[np.float64], seed: int = 0) -> NDArray[np.float64]:
        """The configuration to plan to from ``q`` (module docstring).

        Raises:
            GuidanceError: ``goal_outside_limits`` or ``no_ik_solution``.
        """
        return self.solution(goal, q, seed)[0]

    def solution(self, goal: GoalTargets, q: NDArray[np.float64], seed: int = 0) -> tuple[NDArray[np.float64], bool]:
        """:meth:`configuration`, and whether it reaches a target moved inside the goal's
        tolerances (search 4) rather than the goal itself.

        Raises:
            GuidanceError: ``goal_outside_limits`` or ``no_ik_solution``.
        """
        lower, upper = self.bounds
        if isinstance(goal, JointTarget):
            target = np.asarray(goal.q, dtype=float)
            outside = np.flatnonzero((target < lower - LIMIT_SLACK) | (target > upper + LIMIT_SLACK))
            if outside.size:
                names = self.robot.kinematics.joint_names
                j = int(outside[0])
                raise GuidanceError("goal_outside_limits", f"the goal puts {names[j]} at {target[j]:.6g}, outside "
                                    f"its limits [{lower[j]:.6g}, {upper[j]:.6g}]")
            return np.clip(target, lower, upper), False
        settings = self.settings
        margin, self_margin = settings.path.margin, settings.path.self_margin
        ik = replace(settings.ik, seed=seed)
        result = solve_ik(self.robot, list(goal), q, lambda x: self.checker.free(x, margin, self_margin), ik,
                          lower, upper)
        if result.q is None:
            meshes = self.meshes()
            result = solve_ik(self.robot, list(goal), q, self.merely_free(), replace(settings.ik_retry, seed=seed),
                              lower, upper)
            if result.q is None and meshes is not None:   # nearer the meshes than their margin: as a grasp
                floor = settings.mesh_goal_floor
                result = solve_ik(self.robot, list(goal), q, lambda x: meshes.free(x, floor),
                                  replace(settings.ik_retry, seed=seed), lower, upper)
            if result.q is None:
                nearby = nearby_solution(self.robot, goal, q, self.merely_free(settings.mesh_goal_floor),
                                         settings.goal_region, settings.goal_region_targets, ik, self.bounds)
                if nearby is not None and nearby.q is not None:
                    return nearby.q, True
        if result.q is None:
            found = (f"{result.converged} solutions within the limits, all in collision" if result.converged
                     else "no solution within the joint limits")
            raise GuidanceError("no_ik_solution", f"inverse kinematics: {found} ({result.seeds} seeds)")
        return result.q, False

    def merely_free(self, floor: float | None = None) -> Callable[[NDArray[np.float64]], bool]:
        """Whether a configuration is free on the planning spheres' grid at margin 0, else on
        their exact distances, else on the robot's meshes by ``floor`` [m] (``mesh_margin``
        if None: search 2; ``mesh_goal_floor`` in search 4, as search 3 keeps: a nearby
        target of fresh kitchen seed 20's kitchen/0005, whose exact solutions are all within
        0.2 mm of the kitchen, is found 2.2 mm from it, none among 8 at 3 mm)."""
        meshes, self_margin = self.meshes(), self.settings.path.self_margin

        def free(x: NDArray[np.float64]) -> bool:
            return (self.checker.free(x, 0.0, self_margin) or self.checker.exact_free(x, 0.0, self_margin)
                    or (meshes is not None and meshes.free(x, floor)))
        return free
