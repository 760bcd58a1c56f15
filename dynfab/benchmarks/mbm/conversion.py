"""An MBM problem as a dynfab scenario mapping: what a scenario YAML file would hold,
validated by the same schema (:func:`dynfab.scenario.schema.scenario_from_dict`).

- ``robot: panda`` (the built-in Panda), start ``q`` = the problem's 7 arm joints;
- one ``joint`` goal at the problem's goal configuration, reached when the Euclidean norm
  of the 7 joint errors is below :data:`GOAL_TOLERANCE` [rad];
- every scene primitive as an obstacle: a ``box`` (``size``: full edge lengths) or a
  ``cylinder`` (``length`` = MoveIt's height, ``radius``; axis z), orientation
  ``w, x, y, z``;
- ``dt`` 0.01 s, ``duration`` :data:`DURATION`.

Start and goal values within :data:`~dynfab.benchmarks.mbm.franka.LIMIT_SLACK` of a joint
limit are moved onto it (the problem set writes limits rounded).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from dynfab.benchmarks.mbm.franka import Franka
from dynfab.benchmarks.mbm.moveit import SceneObject
from dynfab.benchmarks.mbm.problems import Problem

__all__ = ["DT", "DURATION", "GOAL_TOLERANCE", "PLANNER", "obstacle_mapping", "scenario_mapping"]

#: Control period [s].
DT = 0.01
#: Simulated time [s]: generous (reached goals took 5-12 s on a 14-problem subset), bounded.
DURATION = 20.0
#: Norm of the joint error below which the goal counts as reached [rad].
GOAL_TOLERANCE = 0.05
#: The default planner: the dynamic fabric (it sees the moving sphere's velocity).
PLANNER = "dynamic-fabric"


def scenario_mapping(problem: Problem, objects: Sequence[SceneObject], robot: Franka, planner: str = PLANNER,
                     extra_obstacles: Sequence[dict[str, Any]] = ()) -> dict[str, Any]:
    """The scenario mapping of ``problem`` with the scene ``objects`` (module doc) and
    ``extra_obstacles`` (scenario obstacle mappings) after them."""
    return {
        "robot": "panda",
        "planner": planner,
        "dt": DT,
        "duration": DURATION,
        "initial_state": {"q": list(robot.clipped(problem.start))},
        "goal": [{"type": "joint", "position": list(robot.clipped(problem.goal)), "tolerance": GOAL_TOLERANCE}],
        "obstacles": [obstacle_mapping(o) for o in objects] + list(extra_obstacles),
    }


def obstacle_mapping(item: SceneObject) -> dict[str, Any]:
    """A scene primitive as a scenario obstacle mapping."""
    placed = {"position": list(item.position), "orientation": list(item.orientation)}
    if item.kind == "box":
        return {"type": "box", "size": list(item.dimensions), **placed}
    height, radius = item.dimensions
    return {"type": "cylinder", "radius": radius, "length": height, **placed}
