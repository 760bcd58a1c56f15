"""Turn a scenario into a controller ``(t, q, q̇) ↦ q̈`` for the simulator.

A controller owns its planner and, each tick, writes the scenario's current goals and
obstacles into the planner's runtime parameters before calling it.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from dynfab.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots.robot import Robot
from dynfab.scenario import GoalSpec, Scenario, ScenarioError


class Controller(Protocol):
    """What the simulator calls once per control period."""

    def __call__(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray: ...


class StaticFabricController:
    """Static optimization fabrics with static goals and obstacles.

    Attributes:
        planner: the compiled planner.
    """

    def __init__(self, planner: FabricPlanner) -> None:
        self.planner = planner

    def __call__(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        return self.planner.compute(q, qdot)


def make_controller(scenario: Scenario, robot: Robot) -> Controller:
    """The controller of ``scenario.planner`` for ``robot``.

    Raises:
        ScenarioError: if the scenario asks for something this planner cannot do.
    """
    if scenario.planner != "static-fabric":
        raise ScenarioError("planner", f"{scenario.planner!r} is not available yet; use static-fabric")
    for i, goal in enumerate(scenario.goals):
        if goal.type == "path":
            raise ScenarioError(f"goal[{i}].type", "path goals need the dynamic-fabric planner, not available yet")
    for i, obstacle in enumerate(scenario.obstacles):
        if obstacle.trajectory is not None:
            raise ScenarioError(f"obstacles[{i}].trajectory", "moving obstacles are not available yet")
    config = PlannerConfig(goals=tuple(_goal_config(goal) for goal in scenario.goals),
                           obstacle_slots=len(scenario.obstacles))
    planner = FabricPlanner(robot, config)
    for i, goal in enumerate(scenario.goals):
        planner.parameters.goal_position[i][:] = goal.position
    for k, obstacle in enumerate(scenario.obstacles):
        centre = np.zeros(3)
        centre[: len(obstacle.position)] = obstacle.position
        planner.parameters.obstacle_position[k] = centre
        planner.parameters.obstacle_radius[k] = obstacle.radius
    return StaticFabricController(planner)


def _goal_config(goal: GoalSpec) -> GoalConfig:
    if goal.type == "joint":
        return GoalConfig(link=None, weight=goal.weight)
    return GoalConfig(link=goal.link, axes=goal.axes, parent_link=goal.parent_link, weight=goal.weight)
