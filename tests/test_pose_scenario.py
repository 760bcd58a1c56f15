"""Scenario keys of pose, axis and offset goals: parsing, one-line errors, references,
and how the orientation error enters the metrics."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from dynfab.geometry.shapes import quaternion_from_rpy, quaternion_matrix
from dynfab.robots import load_robot
from dynfab.scenario.metrics import compute_metrics
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import ScenarioError, scenario_from_dict, validate_for_robot
from dynfab.sim.simulator import Record

POSE = {"type": "pose", "link": "panda_hand", "offset": [0, 0, 0.1], "position": [0.5, -0.3, 0.3],
        "orientation": [0, 2, 0, 0], "tolerance": 0.02, "angle_tolerance": 0.05}
AXIS = {"type": "axis", "link": "panda_hand", "axis": [0, 0, 2], "direction": [0, 0, -1], "weight": 0.5}


def _scenario(*goals: dict[str, Any], robot: str = "panda") -> dict[str, Any]:
    return {"robot": robot, "planner": "static-fabric", "dt": 0.01, "duration": 1.0,
            "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]}, "goal": list(goals)}


def _with(goal: dict[str, Any], **changes: object) -> dict[str, Any]:
    changed = copy.deepcopy(goal)
    for key, value in changes.items():
        if value is None:
            del changed[key]
        else:
            changed[key] = value
    return changed


def test_pose_and_axis_goals_parse_normalised() -> None:
    scenario = scenario_from_dict(_scenario(POSE, AXIS, {"type": "position", "position": [0.1, 0.2, 0.3],
                                                         "offset": [0, 0.05, 0]}))
    pose, axis, position = scenario.goals
    assert pose.orientation == (0.0, 1.0, 0.0, 0.0)
    assert pose.offset == (0.0, 0.0, 0.1) and pose.angle_tolerance == 0.05 and pose.tolerance == 0.02
    assert axis.axis == (0.0, 0.0, 1.0) and axis.direction == (0.0, 0.0, -1.0) and axis.weight == 0.5
    assert axis.angle_tolerance == 0.1 and axis.angular_velocity is None
    assert position.offset == (0.0, 0.05, 0.0)
    rpy = scenario_from_dict(_scenario(_with(POSE, orientation=None, rpy=[np.pi, 0, 0.3]))).goals[0]
    np.testing.assert_allclose(rpy.orientation, quaternion_from_rpy([np.pi, 0, 0.3]))


def test_references_of_pose_and_axis_goals() -> None:
    robot = load_robot("panda")
    turning = _with(AXIS, angular_velocity=[0, 0, 0.5], direction=[1, 0, -1])
    scenario = validate_for_robot(scenario_from_dict(_scenario(POSE, turning)), robot)
    references = scenario_references(scenario, robot)
    assert references.goals[0].evaluate(0.0).position.tolist() == [0.5, -0.3, 0.3]
    columns = references.orientation(0).evaluate(3.0).position.reshape(3, 3)
    np.testing.assert_allclose(columns.T, quaternion_matrix(scenario.goals[0].orientation), atol=1e-12)
    direction = references.goals[1].evaluate(np.pi).position  # half a turn about z at 0.5 rad/s
    np.testing.assert_allclose(direction, [0.0, np.sqrt(0.5), -np.sqrt(0.5)], atol=1e-12)
    assert references.orientation(1) is not None


@pytest.mark.parametrize(
    ("goal", "expected"),
    [
        (_with(POSE, orientation=[0, 0, 0, 0]), "goal[0].orientation: orientation must be a unit quaternion"),
        (_with(POSE, orientation=[1, 0, 0]), "goal[0].orientation: expected 4 numbers, got 3"),
        (_with(POSE, rpy=[0, 0, 0]), "goal[0]: expected exactly one of 'orientation'"),
        (_with(POSE, orientation=None), "goal[0]: expected exactly one of 'orientation'"),
        (_with(POSE, rpy=[0, 0], orientation=None), "goal[0].rpy: expected 3 numbers, got 2"),
        (_with(POSE, position=[0.5, 0.3]), "goal[0].position: expected 3 numbers, got 2"),
        (_with(POSE, angle_tolerance=0), "goal[0].angle_tolerance: must be positive"),
        (_with(POSE, angle_tolerance=4), "goal[0].angle_tolerance: must be at most 3.14159 rad, got 4"),
        (_with(POSE, offset=[0, 0.1]), "goal[0].offset: expected 3 numbers, got 2"),
        (_with(POSE, axes="xy"), "goal[0].axes: unknown key"),
        (_with(AXIS, axis=[0, 0, 0]), "goal[0].axis: expected a non-zero direction"),
        (_with(AXIS, direction=[0, 0, 0]), "goal[0].direction: expected a non-zero direction"),
        (_with(AXIS, direction=None), "goal[0].direction: missing required key"),
        (_with(AXIS, tolerance=0.1), "goal[0].tolerance: unknown key"),
        (_with(AXIS, offset=[0, 0, 0.1]), "goal[0].offset: unknown key"),
        (_with(AXIS, angular_velocity=[0, 1]), "goal[0].angular_velocity: expected 3 numbers, got 2"),
        ({"type": "joint", "position": [0.0] * 7, "offset": [0, 0, 0]}, "goal[0].offset: unknown key"),
        ({"type": "frame"}, "goal[0].type: expected one of position, joint, path, pose, axis"),
    ],
)
def test_bad_pose_and_axis_goals_name_the_field(goal: dict[str, Any], expected: str) -> None:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(_scenario(goal))
    assert str(info.value).startswith(expected), str(info.value)
    assert "\n" not in str(info.value)


def test_planar_robots_reject_orientation_goals() -> None:
    data = _scenario({"type": "axis", "axis": [1, 0, 0], "direction": [0, 1, 0]}, robot="point")
    data["initial_state"]["q"] = [0.0, 0.0]
    with pytest.raises(ScenarioError, match=r"^goal\[0\]\.type: axis goals need a robot in space"):
        run_scenario(scenario_from_dict(data))


def test_unknown_link_of_an_axis_goal_is_named() -> None:
    with pytest.raises(ScenarioError, match=r"^goal\[1\]\.link: unknown link 'tool0'"):
        run_scenario(scenario_from_dict(_scenario(POSE, _with(AXIS, link="tool0"))))


def _record(samples: int) -> Record:
    t = np.arange(samples) * 0.1
    zeros = np.zeros((samples, 1))
    return Record(t=t, q=zeros, qdot=zeros, qddot=zeros[:-1], solver_time=np.zeros(samples - 1))


def test_pose_goal_is_reached_when_position_and_angle_are_both_within_tolerance() -> None:
    positions = np.array([[0.3], [0.0], [0.0], [0.0], [0.0]])
    angles = np.array([0.0, 0.5, 0.2, 0.05, 0.01])
    no_spheres = (np.zeros((5, 0, 3)), np.zeros(0), np.zeros((5, 0, 3)), np.zeros(0))
    metrics = compute_metrics(_record(5), positions, [0.0], 0.05, *no_spheres,
                              orientation_errors=angles, angle_tolerance=0.1)
    assert metrics.time_to_goal == pytest.approx(0.3) and metrics.orientation_error == pytest.approx(0.01)
    secondary = compute_metrics(_record(5), positions, [0.0], 0.05, *no_spheres, orientation_errors=angles)
    assert secondary.time_to_goal == pytest.approx(0.1) and secondary.orientation_error == pytest.approx(0.01)
    never = compute_metrics(_record(5), positions, [0.0], 0.05, *no_spheres,
                            orientation_errors=angles, angle_tolerance=0.005)
    assert not never.goal_reached and never.time_to_goal is None
    plain = compute_metrics(_record(5), positions, [0.0], 0.05, *no_spheres)
    assert plain.orientation_error is None and plain.to_dict()["orientation_error"] is None
