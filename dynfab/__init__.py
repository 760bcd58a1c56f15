"""dynfab: reactive robot motion generation with (dynamic) optimization fabrics.

The public API is this package's namespace (``__all__``)::

    import dynfab
    robot = dynfab.load_robot("panda")
    planner = dynfab.FabricPlanner(robot, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="panda_hand"),)))

Names are imported on first use, so ``import dynfab`` itself loads no CasADi, OMPL or
MuJoCo (``tests/test_public_api.py`` holds it to that).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

__version__ = "0.1.0"

#: public name -> the module that defines it
_EXPORTS: dict[str, str] = {
    # the planner and what it is made of
    "FabricPlanner": "dynfab.fabric.planner",
    "PlannerConfig": "dynfab.fabric.planner_config",
    "GoalConfig": "dynfab.fabric.planner_config",
    "OrientationGoalConfig": "dynfab.fabric.leaves.orientation",
    "ShapeSlots": "dynfab.fabric.parameters",
    "RuntimeParameters": "dynfab.fabric.parameters",
    "ParameterError": "dynfab.fabric.parameters",
    "GoalAttractor": "dynfab.fabric.leaves.goal",
    "Barrier": "dynfab.fabric.leaves.barrier",
    "SphereObstacleAvoidance": "dynfab.fabric.leaves.obstacle",
    "ShapeObstacleAvoidance": "dynfab.fabric.leaves.shape_obstacle",
    "JointLimitAvoidance": "dynfab.fabric.leaves.limits",
    "SelfCollisionAvoidance": "dynfab.fabric.leaves.self_collision",
    "SpeedControl": "dynfab.fabric.speed_control",
    "Leaf": "dynfab.fabric.leaf",
    "LeafContext": "dynfab.fabric.leaf",
    "WorkspaceBounds": "dynfab.fabric.leaves.workspace",
    # robots
    "Robot": "dynfab.robots.robot",
    "CollisionSphere": "dynfab.robots.robot",
    "MotionLimits": "dynfab.robots.limits",
    "load_robot": "dynfab.robots.builtin",
    "robot_from_urdf": "dynfab.robots.builtin",
    "auto_collision_model": "dynfab.robots.collision_model",
    # global guidance
    "GuidedFabric": "dynfab.motion.guided_fabric",
    "GuidanceSettings": "dynfab.motion.guidance",
    "GuidanceError": "dynfab.motion.guidance",
    # scenarios and simulators
    "Scenario": "dynfab.scenario.schema",
    "ScenarioError": "dynfab.scenario.fields",
    "load_scenario": "dynfab.scenario.schema",
    "run": "dynfab.scenario.runner",
    "RunResult": "dynfab.scenario.runner",
    "simulate": "dynfab.sim.simulator",
    "simulate_mujoco": "dynfab.sim.mujoco_sim",
}

__all__ = [
    "__version__",
    "FabricPlanner", "PlannerConfig", "GoalConfig", "OrientationGoalConfig", "ShapeSlots",
    "RuntimeParameters", "ParameterError", "GoalAttractor", "Barrier", "SphereObstacleAvoidance",
    "ShapeObstacleAvoidance", "JointLimitAvoidance", "SelfCollisionAvoidance", "SpeedControl",
    "Leaf", "LeafContext", "WorkspaceBounds",
    "Robot", "CollisionSphere", "MotionLimits", "load_robot", "robot_from_urdf",
    "auto_collision_model", "GuidedFabric", "GuidanceSettings", "GuidanceError", "Scenario",
    "ScenarioError", "load_scenario", "run", "RunResult", "simulate", "simulate_mujoco",
]


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'dynfab' has no attribute '{name}'")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


if TYPE_CHECKING:  # what type checkers and editors see; at run time __getattr__ imports lazily
    from dynfab.fabric.leaf import Leaf, LeafContext
    from dynfab.fabric.leaves.barrier import Barrier
    from dynfab.fabric.leaves.goal import GoalAttractor
    from dynfab.fabric.leaves.limits import JointLimitAvoidance
    from dynfab.fabric.leaves.obstacle import SphereObstacleAvoidance
    from dynfab.fabric.leaves.orientation import OrientationGoalConfig
    from dynfab.fabric.leaves.self_collision import SelfCollisionAvoidance
    from dynfab.fabric.leaves.shape_obstacle import ShapeObstacleAvoidance
    from dynfab.fabric.leaves.workspace import WorkspaceBounds
    from dynfab.fabric.parameters import ParameterError, RuntimeParameters, ShapeSlots
    from dynfab.fabric.planner import FabricPlanner
    from dynfab.fabric.planner_config import GoalConfig, PlannerConfig
    from dynfab.fabric.speed_control import SpeedControl
    from dynfab.motion.guidance import GuidanceError, GuidanceSettings
    from dynfab.motion.guided_fabric import GuidedFabric
    from dynfab.robots.builtin import load_robot, robot_from_urdf
    from dynfab.robots.collision_model import auto_collision_model
    from dynfab.robots.limits import MotionLimits
    from dynfab.robots.robot import CollisionSphere, Robot
    from dynfab.scenario.fields import ScenarioError
    from dynfab.scenario.runner import RunResult, run
    from dynfab.scenario.schema import Scenario, load_scenario
    from dynfab.sim.mujoco_sim import simulate_mujoco
    from dynfab.sim.simulator import simulate
