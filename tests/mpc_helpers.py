"""What the MPC tests share (tests/test_mpc.py, tests/test_mpc_base.py): scenario runs that
return the controller, a controller built as the runner builds it, one solve of its NLP,
the point robot's blocked line, and tolerances."""

from __future__ import annotations

from typing import Any

import numpy as np

from dynfab.mpc import MpcConfig, MpcController, Plan
from dynfab.scenario.controllers import make_mpc_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import RunResult, robot_for, run_scenario
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot

CLEARANCE_TOLERANCE = 1e-3  # [m] the constraints hold at the stage times; between them a sphere may graze
STAGE_CLEARANCE_TOLERANCE = 1e-4  # [m] the solver's constraint tolerance
LIMIT_TOLERANCE = 1e-6


def run(data: dict[str, Any]) -> tuple[RunResult, MpcController]:
    """Run a scenario mapping; also return the MPC controller the runner built."""
    result = run_scenario(scenario_from_dict(data))
    assert isinstance(result.controller, MpcController)
    return result, result.controller


def point_scenario(goal: dict[str, Any], obstacles: list[dict[str, Any]], q0: list[float],
                   duration: float) -> dict[str, Any]:
    """The point robot at rest at ``q0`` with one goal, MPC planner."""
    return {"robot": "point", "planner": "mpc", "dt": 0.01, "duration": duration,
            "initial_state": {"q": q0}, "goal": [goal], "obstacles": obstacles}


def controller_for(data: dict[str, Any], config: MpcConfig) -> MpcController:
    """An MPC controller for a scenario mapping, built as the runner would."""
    scenario = scenario_from_dict(data)
    robot = robot_for(scenario)
    scenario = validate_for_robot(scenario, robot)
    return make_mpc_controller(scenario, robot, scenario_references(scenario, robot), config)


BLOCKED_LINE = point_scenario({"type": "position", "position": [1.5, 0.1], "tolerance": 0.05},
                              [{"type": "sphere", "position": [0.0, 0.0], "radius": 0.4}], [-1.5, 0.0], 8.0)


def solve(controller: MpcController, q: np.ndarray, qdot: np.ndarray, guess: Plan | None) -> Any:
    """One solve of the controller's NLP for its (static) references at t = 0."""
    horizon = controller.config.stages
    goals = [np.tile(reference.evaluate(0.0).position, (horizon, 1)) for reference in controller.references.goals]
    centres = np.stack([np.tile(reference.evaluate(0.0).position, (horizon, 1))
                        for reference in controller.references.obstacles])
    return controller.problem.solve(q, qdot, goals, centres, controller.obstacle_radii, guess)
