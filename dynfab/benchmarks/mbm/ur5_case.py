"""An MBM problem on the UR5 (``dynfab benchmark mbm --robot ur5``): the Panda problem's
scene without the object to grasp (as ``object-removed``), the UR5 of
:mod:`dynfab.benchmarks.mbm.ur5` at the Panda's base pose, and a *pose* goal for its tool
derived from the Panda's goal:

- goal: the Panda's grasp frame (``panda_hand_tcp`` at its goal configuration: the point
  between the fingertips, approach axis z, fingers closing along y) as a pose goal for
  the UR5's ``tool0`` with ``offset`` :data:`~dynfab.benchmarks.mbm.ur5.GRASP_OFFSET`
  (the UR5's point between its fingertips) and ``tool0``'s rotation turned so its
  gripper's approach and closing axes lie on the Panda's
  (:func:`~dynfab.benchmarks.mbm.ur5.tool_rotation`); reached within :data:`TOLERANCE` [m]
  and :data:`ANGLE_TOLERANCE` [rad];
- start: the UR5's :data:`~dynfab.benchmarks.mbm.ur5.HOME` at rest if its meshes are
  free of the scene, else a collision-free IK solution of the Panda's *start* grasp frame;
- ``dt``, ``duration`` as the Panda's cases.

The case is **invalid** (counted, not run) when neither start is free on the UR5's meshes,
or when no IK solution of the goal pose within the joint limits is free of the scene and
of self-collision on its meshes (:data:`IK_SETTINGS`: up to 200 seeds, HOME first); the
reason says whether the pose is out of reach or every solution found touches.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from dynfab.benchmarks.mbm.conversion import DT, DURATION, PLANNER, obstacle_mapping
from dynfab.benchmarks.mbm.franka import Franka
from dynfab.benchmarks.mbm.problems import Problem
from dynfab.benchmarks.mbm.ur5 import (GRASP_OFFSET, HOME, GraspPose, Ur5, panda_grasp_pose, tool_rotation,
                                       ur5_robot_mapping)
from dynfab.benchmarks.mbm.validity import static_shapes
from dynfab.benchmarks.mbm.variants import Case, grasped_object
from dynfab.motion.inverse_kinematics import IkSettings
from dynfab.scenario.schema import scenario_from_dict

__all__ = ["ANGLE_TOLERANCE", "IK_SETTINGS", "TOLERANCE", "VARIANT", "prepare_ur5_case", "ur5_goal_mapping"]

#: The variant's name in records and tables.
VARIANT = "ur5-object-removed"
#: Position tolerance of the grasp point [m].
TOLERANCE = 0.01
#: Orientation tolerance of the tool [rad].
ANGLE_TOLERANCE = 0.05
#: How hard the validity check searches for a free goal (and start) configuration.
IK_SETTINGS = IkSettings(seeds=200, iterations=100, tolerance=1e-5, solutions=1, time_limit=30.0, seed=0)


def ur5_goal_mapping(grasp: GraspPose) -> dict[str, object]:
    """The scenario pose goal that puts the UR5's grasp frame on ``grasp`` (module doc)."""
    quaternion = GraspPose(grasp.position, tool_rotation(grasp)).quaternion()
    return {"type": "pose", "position": [round(float(v), 6) for v in grasp.position],
            "orientation": [round(v, 8) for v in quaternion], "offset": list(GRASP_OFFSET),
            "tolerance": TOLERANCE, "angle_tolerance": ANGLE_TOLERANCE}


def prepare_ur5_case(problem: Problem, panda: Franka, arm: Ur5, planner: str = PLANNER) -> Case:
    """``problem`` on the UR5 (module doc), variant :data:`VARIANT`.

    Raises:
        ProblemError: The problem has no graspable object.
        ScenarioError: The converted scenario breaks the schema.
    """
    index = grasped_object(problem, panda)
    objects = problem.objects[:index] + problem.objects[index + 1:]
    names = tuple(o.id for o in objects)
    grasp = panda_grasp_pose(panda, panda.clipped(problem.goal))
    goal = ur5_goal_mapping(grasp)
    mapping = _mapping(HOME, goal, [obstacle_mapping(o) for o in objects], planner)
    shapes = static_shapes(scenario_from_dict(mapping))
    invalid = None
    start: Sequence[float] | None = HOME
    home_contact = arm.contact(HOME, shapes)
    if home_contact is not None:
        start = arm.free_ik(panda_grasp_pose(panda, panda.clipped(problem.start)), shapes, IK_SETTINGS).q
        if start is None:
            invalid = (f"start: HOME has {_named(home_contact, names)} and no IK solution of the Panda's start grasp "
                       f"pose is free on the UR5's meshes")
        else:
            mapping = _mapping(tuple(round(float(v), 6) for v in start), goal, mapping["obstacles"], planner)
    result = arm.free_ik(grasp, shapes, IK_SETTINGS) if invalid is None else None
    if result is not None and result.q is None:
        unreached = "goal: no IK solution of the grasp pose within the UR5's limits"
        invalid = (f"{unreached} (out of reach)" if not result.converged else
                   f"{unreached} is free on its meshes ({result.converged} found, all touching the scene or itself)")
    return Case(problem, VARIANT, mapping, names, problem.objects[index].id, invalid)


def _mapping(start: Sequence[float], goal: dict[str, object], obstacles: list[dict[str, object]],
             planner: str) -> dict[str, object]:
    return {"robot": ur5_robot_mapping(), "planner": planner, "dt": DT, "duration": DURATION,
            "initial_state": {"q": [float(v) for v in np.asarray(start, dtype=float)]}, "goal": [goal],
            "obstacles": obstacles}


def _named(contact: str, names: Sequence[str]) -> str:
    """``contact`` with ``obstacles[k]`` replaced by the scene's id of obstacle k."""
    for k in range(len(names) - 1, -1, -1):
        contact = contact.replace(f"obstacles[{k}]", names[k])
    return contact
