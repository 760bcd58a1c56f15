"""Guidance for the end of a path goal (scenario/path_end.py): the fabric follows the path,
guidance plans to its end once its time is over; paths without an end are not guided,
and asking for it is refused with the field named."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.motion.inverse_kinematics import AxisTarget, PointTarget
from dynfab.motion.joint_trajectory import SHORTEST_PATH, time_path
from dynfab.robots import load_robot
from dynfab.scenario.controllers import FabricController
from dynfab.scenario.guided_controller import (SIMULATED_PLAN_LATENCY, goal_targets, guidance_refusal,
                                               make_scenario_controller)
from dynfab.scenario.path_end import PathEndController
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import ScenarioError, scenario_from_dict, validate_for_robot

#: the hand in front of the robot at +y; a wall at y = 0 between it and the path's end (-y)
START = np.array([1.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
WALL = {"type": "box", "position": [0.45, 0.0, 0.35], "size": [0.6, 0.04, 0.7]}
BEHIND_THE_WALL = [0.45, -0.25, 0.3]
PATH_TIME = 4.0


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def _hand(panda) -> list[float]:
    return np.asarray(panda.kinematics.position(START, "panda_hand")).ravel().round(3).tolist()


def _through_the_wall(panda, trajectory: dict | None = None, **keys) -> dict:
    """A path for the hand from where it is straight through the wall to behind it."""
    path = {"type": "path", "link": "panda_hand", "tolerance": 0.02,
            "trajectory": trajectory or {"type": "spline", "waypoints": [_hand(panda), BEHIND_THE_WALL],
                                         "duration": PATH_TIME}}
    return {"robot": "panda", "planner": "dynamic-fabric", "dt": 0.01, "duration": 12.0,
            "initial_state": {"q": START.tolist()}, "goal": [path], "obstacles": [WALL], **keys}


def test_the_end_of_a_path_behind_a_wall_is_reached_guided_and_not_by_the_fabric_alone(panda) -> None:
    alone = run_scenario(scenario_from_dict(_through_the_wall(panda, guidance=False))).metrics
    result = run_scenario(scenario_from_dict(_through_the_wall(panda)))
    guided = result.metrics
    assert alone.guided is False and alone.plans == 0
    assert alone.final_distance > 0.2   # held in front of the wall
    assert not alone.success and alone.failure is not None   # a path's end not reached is a failure
    assert result.mesh_sweep is not None   # clearance and self-collision measured on Franka's meshes
    assert guided.final_distance < 0.02 and not guided.collision and guided.self_collision is False
    assert guided.clearance > 0.0 and guided.max_velocity_ratio <= 1.0 + 1e-9
    run_json = guided.to_dict()
    assert run_json["guided"] is True and run_json["plans"] >= 1 and run_json["fallbacks"] == 0
    assert run_json["failure"] is None and run_json["plan_time_ms"] > 0.0


def test_the_path_is_followed_by_the_fabric_until_its_time_is_over_then_guidance_plans_to_its_end(panda) -> None:
    scenario = validate_for_robot(scenario_from_dict(_through_the_wall(panda)), panda)
    controller = make_scenario_controller(scenario, panda, scenario_references(scenario, panda))
    assert isinstance(controller, PathEndController) and controller.end_time == PATH_TIME
    follower = controller.planner
    qdot = np.zeros(7)
    for t in (0.0, 0.01, PATH_TIME - 0.01):
        controller(t, START, qdot)
        assert not controller.ended and controller.planner is follower and controller.status.plans == 0
    controller(PATH_TIME, START, qdot)
    assert controller.ended and controller.planner is not follower   # guided from the handover on
    controller(PATH_TIME + SIMULATED_PLAN_LATENCY, START, qdot)       # the plan applied after its latency
    assert controller.status.plans == 1
    assert controller.status.guided and controller.fallback is None
    hand_at_goal = np.asarray(panda.kinematics.position(controller.guided.guided.plan.goal, "panda_hand")).ravel()
    assert np.linalg.norm(hand_at_goal - BEHIND_THE_WALL) < 1e-3   # the plan's goal: IK of the path's end


def test_the_targets_of_a_path_end_are_its_last_point_for_the_goal_point_and_the_other_goals(panda) -> None:
    data = _through_the_wall(panda)
    data["goal"][0].update(offset=[0.0, 0.0, 0.1], axes="xz", trajectory={
        "type": "spline", "waypoints": [[0.4, 0.3], [0.5, 0.2], [0.45, 0.35]], "duration": 3.0})
    data["goal"].append({"type": "axis", "link": "panda_hand", "axis": [0, 0, 1], "direction": [0, 0, -1]})
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    targets = goal_targets(scenario, panda, scenario_references(scenario, panda))
    assert targets[0] == PointTarget("panda_hand", targets[0].position, (0.0, 0.0, 0.1), (0, 2), None,
                                     scenario.goals[0].tolerance)   # the goal's tolerances come along
    assert targets[0].position == pytest.approx((0.45, 0.35), abs=1e-12)
    assert targets[1] == AxisTarget("panda_hand", (0.0, 0.0, 1.0), (0.0, 0.0, -1.0), scenario.goals[1].angle_tolerance)
    with pytest.raises(ValueError, match="goal\\[0\\] is a path goal"):
        goal_targets(scenario, panda)


@pytest.mark.parametrize(("trajectory", "why"), [
    ({"type": "circle", "center": [0.45, 0.0, 0.55], "radius": 0.1, "angular_velocity": 0.5}, "periodic"),
    ({"type": "linear", "start": [0.4, 0.3, 0.5], "velocity": [0.0, -0.01, 0.0]}, "never stops"),
    ({"type": "polynomial", "coefficients": [[0.4], [0.3, -0.01], [0.5]]}, "never stops"),
    ({"type": "expression", "x": ["0.4", "0.3", "0.5"]}, "cannot be known"),
])
def test_paths_without_an_end_are_not_guided_and_asking_for_it_names_the_field(panda, trajectory, why) -> None:
    scenario = validate_for_robot(scenario_from_dict(_through_the_wall(panda, trajectory)), panda)
    assert why in guidance_refusal(scenario, panda) and guidance_refusal(scenario, panda).startswith("goal[0]")
    controller = make_scenario_controller(scenario, panda, scenario_references(scenario, panda))
    assert isinstance(controller, FabricController)   # the fabric alone (a path goal has no stall recovery)
    data = _through_the_wall(panda, trajectory)
    data["goal"][0]["guided_end"] = True
    with pytest.raises(ScenarioError) as refused:
        scenario_from_dict(data)
    assert str(refused.value).startswith("goal[0].guided_end: ")
    assert f"a {trajectory['type']} path has no end at rest" in str(refused.value)


def test_a_path_end_asked_to_be_guided_where_guidance_is_off_is_refused_and_guided_end_false_is_obeyed(panda) -> None:
    data = _through_the_wall(panda, guidance=False)
    data["goal"][0]["guided_end"] = True
    with pytest.raises(ScenarioError) as refused:
        run_scenario(scenario_from_dict(data))
    assert str(refused.value).startswith("goal[0].guided_end: the end of this path cannot be guided (guidance: false)")
    data = _through_the_wall(panda)
    data["goal"][0]["guided_end"] = False
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    assert guidance_refusal(scenario, panda) == "goal[0].guided_end: false"
    assert isinstance(make_scenario_controller(scenario, panda, scenario_references(scenario, panda)),
                      FabricController)


def test_a_path_that_ends_when_the_run_does_is_not_guided_and_asking_for_it_is_refused(panda) -> None:
    data = _through_the_wall(panda)
    data["duration"] = PATH_TIME
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    assert guidance_refusal(scenario, panda) == "goal[0].trajectory: the path ends at 4 s, not before the run does (4 s)"
    data["goal"][0]["guided_end"] = True
    with pytest.raises(ScenarioError, match=r"^goal\[0\]\.guided_end: the end of this path cannot be guided"):
        run_scenario(scenario_from_dict(data))


def test_a_turning_axis_goal_is_not_guided_and_says_why(panda) -> None:
    data = _through_the_wall(panda)
    data["goal"] = [{"type": "axis", "axis": [0, 0, 1], "direction": [0, 0, -1], "angular_velocity": [0, 0, 0.2]}]
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    assert guidance_refusal(scenario, panda) == "goal[0]: an axis goal that turns moves: it has no configuration to plan to"


def test_a_path_end_out_of_reach_leaves_the_path_to_the_fabric_and_status_says_why(panda) -> None:
    out_of_reach = {"type": "spline", "waypoints": [_hand(panda), [1.5, 0.5, 0.3]], "duration": 1.0}
    data = _through_the_wall(panda, out_of_reach)
    data["duration"] = 2.0
    result = run_scenario(scenario_from_dict(data))
    metrics = result.metrics
    assert metrics.guided is False and metrics.fallbacks >= 1 and metrics.plans == 0
    assert metrics.final_distance > 0.3
    assert result.controller.status.failure == "no_ik_solution"
    assert result.controller.guided.guided.failure_message.startswith("inverse kinematics: no solution")
    # a path that ends at rest before the run does is reached only if its end is
    assert not metrics.success and not metrics.goal_reached and metrics.failure is not None


@pytest.mark.parametrize("length", [0.0, 1e-12, 3e-9, 1e-8, 1e-6])
def test_a_path_to_where_the_robot_already_is_is_timed(length: float) -> None:
    """The plan at a path's end when the hand is there already: TOPP-RA found no timing of
    a path shorter than about 1e-8 rad (so guidance failed with ``timing``)."""
    start = np.array([1.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
    end = start + length / np.sqrt(7)
    trajectory = time_path(np.array([start, end]), np.full(7, 2.0), np.full(7, 10.0))
    assert np.linalg.norm(trajectory.end - end) <= SHORTEST_PATH + 1e-15
    position, velocity, _ = trajectory.sample(np.array([0.0, trajectory.duration + 1.0]))
    assert np.allclose(position[0], start, atol=SHORTEST_PATH) and np.all(velocity[-1] == 0.0)
