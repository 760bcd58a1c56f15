"""End to end: scenario mappings through ``run_scenario`` and the metrics of the runs.

Every run is a real closed-loop simulation of the static fabric planner; the tests
assert on the metrics of docs/design.md section 6 and on the final state.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from dynfab.scenario.controllers import FabricController
from dynfab.experiments import exp1, point_reaching
from dynfab.scenario.runner import RunResult, run_scenario
from dynfab.scenario.schema import scenario_from_dict

PANDA_Q0 = [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]
SEEDS = range(10)


def run_recording_controller(data: dict[str, Any]) -> tuple[RunResult, FabricController]:
    """Run a scenario mapping as the paper would (the fabric alone: no global guidance, no
    stall recovery) and also return the controller the runner built for it."""
    result = run_scenario(scenario_from_dict({**data, "recovery": False, "guidance": False}))
    assert isinstance(result.controller, FabricController)
    return result, result.controller


def panda_scenario(goal: dict[str, Any], duration: float = 10.0) -> dict[str, Any]:
    """The Panda at rest in the common start pose, one goal, no obstacles."""
    return {
        "robot": "panda",
        "planner": "static-fabric",
        "dt": 0.01,
        "duration": duration,
        "initial_state": {"q": PANDA_Q0},
        "goal": [goal],
    }


@pytest.mark.parametrize("seed", SEEDS)
def test_experiment1_panda_reaches_goal_without_collision(seed: int) -> None:
    data = exp1.scenario(seed)
    result, controller = run_recording_controller(data)
    metrics = result.metrics
    assert metrics.success, f"exp1 seed {seed}: {metrics}"
    assert not metrics.collision and metrics.clearance is not None and metrics.clearance > 0.0
    assert metrics.time_to_goal is not None and metrics.time_to_goal < data["duration"]
    assert np.isfinite(result.record.qddot).all()
    assert controller.planner.fallback_count == 0, f"exp1 seed {seed}: non-finite fabric output"


@pytest.mark.parametrize("seed", SEEDS)
def test_point_robot_reaches_goal_among_discs(seed: int) -> None:
    data = point_reaching.scenario(seed)
    result, controller = run_recording_controller(data)
    metrics = result.metrics
    assert metrics.success, f"point_reaching seed {seed}: {metrics}"
    assert np.isfinite(result.record.qddot).all()
    assert controller.planner.fallback_count == 0


def test_point_reaching_scenarios_follow_their_distribution() -> None:
    for seed in range(50):
        data = point_reaching.scenario(seed)
        assert data == point_reaching.scenario(seed)
        start = np.array(data["initial_state"]["q"])
        goal = np.array(data["goal"][0]["position"])
        assert np.all(np.abs(start) <= 2.0) and np.all(np.abs(goal) <= 2.0)
        assert 1.5 - 1e-3 <= np.linalg.norm(goal - start) <= 3.0 + 1e-3
        assert 1 <= len(data["obstacles"]) <= 5
        for obstacle in data["obstacles"]:
            centre, radius = np.array(obstacle["position"]), obstacle["radius"]
            assert 0.2 <= radius <= 0.4
            assert np.linalg.norm(centre - start) - radius - 0.1 > 0.05 - 1e-3
            assert np.linalg.norm(centre - goal) - radius > 0.1 - 1e-3
        blocking = data["obstacles"][0]
        direction = (goal - start) / np.linalg.norm(goal - start)
        offset = np.array(blocking["position"]) - start
        sideways = abs(direction[0] * offset[1] - direction[1] * offset[0])
        assert sideways <= 0.5 * blocking["radius"] + 1e-3, f"seed {seed}: first disc is off the segment"


def test_panda_without_obstacles_converges_to_hand_goal() -> None:
    goal = [0.5, -0.3, 0.4]
    result = run_scenario(scenario_from_dict(panda_scenario(
        {"type": "position", "link": "panda_hand", "position": goal, "tolerance": 0.01})))
    assert result.metrics.success
    assert result.metrics.clearance is None
    assert np.linalg.norm(result.goal_positions[-1] - goal) < 0.01
    assert np.linalg.norm(result.record.qdot[-1]) < 0.05


def test_panda_joint_goal_converges_to_configuration() -> None:
    target = np.array([-0.5, -0.4, 0.3, -2.2, 0.2, 1.9, 0.6])
    result = run_scenario(scenario_from_dict(panda_scenario(
        {"type": "joint", "position": target.tolist(), "tolerance": 0.05})))
    assert result.metrics.success
    assert np.max(np.abs(result.record.q[-1] - target)) < 0.05
    assert np.linalg.norm(result.record.qdot[-1]) < 0.05


@pytest.mark.parametrize(("axis", "target"), [("x", 1.0), ("y", -0.8)])
def test_point_goal_on_one_axis_leaves_the_other_free(axis: str, target: float) -> None:
    start = np.array([-1.0, 0.5])
    data = {
        "robot": "point",
        "planner": "static-fabric",
        "dt": 0.01,
        "duration": 10.0,
        "initial_state": {"q": start.tolist()},
        "goal": [{"type": "position", "link": "point", "axes": axis, "position": [target], "tolerance": 0.01}],
    }
    result = run_scenario(scenario_from_dict(data))
    assert result.metrics.success
    assert result.goal_positions.shape == (result.record.t.shape[0], 1)
    controlled, free = (0, 1) if axis == "x" else (1, 0)
    final = result.record.q[-1]
    assert abs(final[controlled] - target) < 0.01
    assert abs(final[free] - start[free]) < 1e-6
