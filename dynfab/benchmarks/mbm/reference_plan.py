"""MotionBenchMaker's own filter, as a measure: does a plain global planner solve the problem?

MotionBenchMaker keeps a generated problem only if its planner (MoveIt's RRT-Connect, 60 s,
two attempts, FCL on the robot's meshes) solves it from the start to the goal configuration
its inverse kinematics found; otherwise it draws another scene (its ``generate`` script). The
problems dynfab generates (:mod:`~dynfab.benchmarks.mbm.generated_problems`,
:mod:`~dynfab.benchmarks.mbm.scenes`) are all kept, so a set of them holds problems
MotionBenchMaker would have dropped. :func:`reference_plan` runs the reference planner on a
case, and the tables report the success among the problems it solves beside the success
among all (:mod:`~dynfab.benchmarks.mbm.tables`).

The reference planner: OMPL's RRT-Connect from the start to the problem's goal
configuration, every motion checked every ``resolution`` on the robot's meshes at margin 0
(MoveIt's rule: no contact), the planning spheres' test, kept ``coverage`` clear, standing
in for the meshes where it passes (:class:`~dynfab.motion.mesh_escape.SpheresOrMeshes`);
static obstacles only, the true shapes of a variant that gives the planner others. One
search of at most ``checks`` mesh checks, a bound independent of the load: 120 000 take
about 60 s on the 2-core machine (quiet), the time MotionBenchMaker gives. FCL in MoveIt
checks faster than this check does, so the filter is at most as strict as MotionBenchMaker's
in the number of checks, not in time.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.mesh_escape import MeshEscapeSettings, SpheresOrMeshes, mesh_path
from dynfab.motion.mesh_goal_check import robot_mesh_model
from dynfab.robots.joint_bounds import finite_joint_bounds
from dynfab.robots.mesh_contact import MeshContactCheck
from dynfab.scenario.guided_controller import placed_obstacles
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import scenario_from_dict

__all__ = ["REFERENCE_CHECKS", "reference_plan"]

#: Mesh checks of the reference search by default (module docstring) [-].
REFERENCE_CHECKS = 120_000
#: Wall time the search is given [s]: its checks bound it, not the time
_UNTIMED = 1e6


def reference_plan(mapping: dict[str, Any], goal: Sequence[float], checks: int = REFERENCE_CHECKS,
                   seed: int = 0) -> dict[str, Any]:
    """Whether the reference planner (module docstring) finds a path in the scenario
    ``mapping`` (its static obstacles, its robot's meshes) from its start to the joint
    configuration ``goal`` [rad] within ``checks`` mesh checks, as a JSON-ready mapping:
    ``{"solved", "mesh_checks", "checks", "seconds", "length"}`` (``length``: the path's
    joint-space length [rad], None unsolved); ``solved`` is False where the start or the
    goal touches the scene on the meshes.

    Raises:
        ValueError: ``checks`` is not positive, or the robot has no collision meshes.
        ScenarioError: ``mapping`` is not a valid scenario.
    """
    if checks <= 0:
        raise ValueError(f"checks: must be positive, got {checks}")
    began = time.perf_counter()
    scenario = scenario_from_dict(mapping)
    robot = robot_for(scenario)
    obstacles = placed_obstacles(scenario, scenario_references(scenario, robot), 0.0, static=True)
    model = robot_mesh_model(robot)
    if model is None:
        raise ValueError(f"robot '{robot.name}': the reference planner checks the robot's meshes, it has none")
    settings = replace(MeshEscapeSettings(), checks=checks, total_checks=checks)
    meshes = MeshContactCheck(model, 0.0)
    meshes.set_obstacles(obstacles)
    validity = SpheresOrMeshes(ConfigurationChecker(robot.planning_robot, obstacles), meshes, settings.coverage,
                               0.0, robot.dof)
    lower, upper = finite_joint_bounds(robot.kinematics.lower, robot.kinematics.upper)
    start = np.clip(np.asarray(scenario.initial_state.q, dtype=float), lower, upper)
    end = np.clip(np.asarray(goal, dtype=float), lower, upper)
    way = mesh_path(validity, start, end, lower, upper, settings, seed, _UNTIMED)
    length = None if way is None else float(np.sum(np.linalg.norm(np.diff(way, axis=0), axis=1)))
    return {"solved": way is not None, "mesh_checks": validity.mesh_checks, "checks": validity.checks,
            "seconds": time.perf_counter() - began, "length": length}
