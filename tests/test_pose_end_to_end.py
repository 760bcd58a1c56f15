"""End to end: the Panda with pose, axis and offset goals, static and dynamic; the
orientation error of every run is measured from the recorded joint states."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import pytest
import yaml

from dynfab.cli import main
from dynfab.geometry.orientation import direction_angle
from dynfab.scenario.runner import RunResult, run_scenario
from dynfab.scenario.schema import load_scenario, scenario_from_dict

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
#: the hand pointing down (its z along the world's −z)
HAND_DOWN_Q0 = [0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785]
TOOL = [0.0, 0.0, 0.1]


def _scenario(goals: list[dict[str, Any]], planner: str = "static-fabric", duration: float = 8.0,
              q0: list[float] = HAND_DOWN_Q0) -> dict[str, Any]:
    return {"robot": "panda", "planner": planner, "dt": 0.01, "duration": duration,
            "initial_state": {"q": q0}, "goal": goals}


def _hand_z_angles(result: RunResult, direction: list[float]) -> np.ndarray:
    """Angle between the hand's z axis and ``direction`` at every sample [rad]."""
    kinematics = result.robot.kinematics
    q = ca.SX.sym("q", kinematics.dof)
    hand_z = ca.Function("z", [q], [kinematics.rotation(q, "panda_hand")[:, 2]]).map(result.record.q.shape[0])
    return direction_angle(np.array(hand_z(result.record.q.T)).T, direction)


def _point(result: RunResult, offset: list[float]) -> np.ndarray:
    return np.array(result.robot.kinematics.position(result.record.q[-1], "panda_hand", offset=offset)).ravel()


def test_pose_example_reaches_position_and_orientation() -> None:
    scenario = load_scenario(EXAMPLES / "panda_pose_down.yaml")
    goal = scenario.goals[0]
    result = run_scenario(scenario)
    metrics = result.metrics
    assert metrics.success and not metrics.collision, metrics
    assert metrics.orientation_error is not None and metrics.orientation_error < goal.angle_tolerance
    assert np.linalg.norm(_point(result, list(goal.offset)) - goal.position) < goal.tolerance
    assert _hand_z_angles(result, [0, 0, -1])[-1] < goal.angle_tolerance
    # the start is far from the target orientation: reaching it took a real rotation
    assert _hand_z_angles(result, [0, 0, -1])[0] > 0.3


def test_pose_goal_from_rpy_with_mpc() -> None:
    goal = {"type": "pose", "offset": TOOL, "position": [0.45, 0.3, 0.35], "rpy": [np.pi, 0.0, 0.5],
            "tolerance": 0.05, "angle_tolerance": 0.1}
    result = run_scenario(scenario_from_dict(_scenario([goal], planner="mpc", duration=6.0,
                                                       q0=[1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])))
    assert result.metrics.success, result.metrics
    assert result.metrics.orientation_error < 0.1


def test_axis_goal_keeps_the_tool_down_while_the_position_goal_is_reached() -> None:
    position = {"type": "position", "offset": TOOL, "position": [0.3, -0.45, 0.25], "tolerance": 0.01}
    axis = {"type": "axis", "axis": [0, 0, 1], "direction": [0, 0, -1]}
    with_axis = run_scenario(scenario_from_dict(_scenario([position, axis])))
    assert with_axis.metrics.success, with_axis.metrics
    assert np.linalg.norm(_point(with_axis, TOOL) - position["position"]) < 0.01
    assert _hand_z_angles(with_axis, [0, 0, -1]).max() < 0.1
    assert with_axis.metrics.orientation_error < 0.01
    without = run_scenario(scenario_from_dict(_scenario([position])))
    assert without.metrics.success
    assert _hand_z_angles(without, [0, 0, -1]).max() > 0.2, "the axis goal must be what keeps the tool down"


def test_primary_axis_goal_is_reached_by_its_angle() -> None:
    axis = {"type": "axis", "axis": [0, 0, 1], "direction": [1, 0, -1], "angle_tolerance": 0.05}
    result = run_scenario(scenario_from_dict(_scenario([axis], duration=5.0)))
    angles = _hand_z_angles(result, [np.sqrt(0.5), 0, -np.sqrt(0.5)])
    assert angles[0] > 0.7
    assert result.metrics.success and result.metrics.orientation_error < 0.01
    first = int(np.flatnonzero(angles < 0.05)[0])
    assert result.metrics.time_to_goal == pytest.approx(result.record.t[first])


def test_path_example_keeps_the_tool_down_along_the_path() -> None:
    scenario = load_scenario(EXAMPLES / "panda_path_tool_down.yaml")
    result = run_scenario(scenario)
    assert result.metrics.success, result.metrics
    assert result.metrics.summed_error < 0.01
    assert np.linalg.norm(result.goal_positions - result.goal_reference, axis=1).max() < 0.03
    assert _hand_z_angles(result, [0, 0, -1]).max() < 0.05
    assert result.metrics.orientation_error < 0.01
    # the tool point, not the hand, follows the path
    final = scenario.goals[0].trajectory["waypoints"][-1]
    assert np.linalg.norm(_point(result, TOOL) - final) < 0.01


def test_dynamic_axis_goal_follows_a_turning_direction() -> None:
    """The hand's z stays 45° below the horizon while the direction turns about the
    world z at 0.3 rad/s; the dynamic fabric follows it closely."""
    start = np.array([1.0, 0.0, -1.0]) / np.sqrt(2.0)
    position = {"type": "position", "offset": TOOL, "position": [0.45, 0.0, 0.35], "tolerance": 0.02}
    axis = {"type": "axis", "axis": [0, 0, 1], "direction": start.tolist(), "angular_velocity": [0, 0, 0.3]}
    result = run_scenario(scenario_from_dict(_scenario([position, axis], planner="dynamic-fabric", duration=8.0)))
    assert result.metrics.success, result.metrics
    t = result.record.t
    reference = np.stack([np.cos(0.3 * t), np.sin(0.3 * t), -np.ones_like(t)], axis=1) / np.sqrt(2.0)
    kinematics = result.robot.kinematics
    hand_z = np.array([np.array(kinematics.rotation(q, "panda_hand"))[:, 2] for q in result.record.q[::10]])
    errors = direction_angle(hand_z, reference[::10])
    assert errors[t[::10] > 2.0].max() < 0.05
    assert result.metrics.orientation_error < 0.05


def test_offset_point_reaches_the_target() -> None:
    offset = [0.05, 0.0, 0.2]
    goal = {"type": "position", "offset": offset, "position": [0.4, -0.3, 0.45], "tolerance": 0.01}
    data = _scenario([goal], q0=[1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])
    result = run_scenario(scenario_from_dict(data))
    assert result.metrics.success, result.metrics
    assert np.linalg.norm(_point(result, offset) - goal["position"]) < 0.01
    assert np.linalg.norm(_point(result, [0, 0, 0]) - goal["position"]) > 0.15
    np.testing.assert_allclose(result.goal_positions[-1], _point(result, offset))


def test_cli_json_reports_orientation_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = yaml.safe_load((EXAMPLES / "panda_pose_down.yaml").read_text())
    data["duration"] = 0.5
    path = tmp_path / "pose.yaml"
    path.write_text(yaml.safe_dump(data))
    main(["run", str(path), "--json"])
    report = json.loads(capsys.readouterr().out)
    assert report["orientation_error"] > 0.05 and report["goal_reached"] is False


def test_ur5_from_its_shipped_urdf_reaches_a_pose_of_tool0() -> None:
    """The contract's own example: a pose goal for ``tool0`` of a URDF as it ships
    (example-robot-data is a test dependency)."""
    data = {"robot": {"urdf": "package://example-robot-data/robots/ur_description/urdf/ur5_robot.urdf",
                      "goal_link": "tool0"},
            "planner": "static-fabric", "dt": 0.01, "duration": 6.0,
            "initial_state": {"q": [0.0, -1.2, 1.5, -1.9, -1.57, 0.0]},
            "goal": [{"type": "pose", "link": "tool0", "offset": TOOL, "position": [0.4, 0.2, 0.3],
                      "orientation": [0, 1, 0, 0], "tolerance": 0.02, "angle_tolerance": 0.1}]}
    result = run_scenario(scenario_from_dict(data))
    assert result.metrics.success, result.metrics
    assert result.metrics.orientation_error < 0.01
    final = np.array(result.robot.kinematics.position(result.record.q[-1], "tool0", offset=TOOL)).ravel()
    assert np.linalg.norm(final - [0.4, 0.2, 0.3]) < 0.02
