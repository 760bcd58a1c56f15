"""The ``fabric:`` block of scenario files: documented defaults equal the planner's, an empty
or explicit-default block changes nothing, a changed value reaches the planner's command."""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

import numpy as np
import pytest
import yaml

from dynfab.cli import main
from dynfab.fabric.leaves.orientation import OrientationGoalConfig
from dynfab.fabric.planner import GoalConfig, PlannerConfig
from dynfab.robots import load_robot
from dynfab.scenario import fabric_schema
from dynfab.scenario.controllers import FabricController, make_controller
from dynfab.scenario.fabric_schema import fabric_block
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import robot_for, run_scenario
from dynfab.scenario.schema import ScenarioDocument, ScenarioError, scenario_from_dict, validate_for_robot

PANDA = load_robot("panda")
BOXER = load_robot("boxer")

REACH: dict[str, Any] = {
    "robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 3.0,
    "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
    "goal": [{"type": "position", "position": [0.5, -0.3, 0.5], "tolerance": 0.05}],
    "obstacles": [{"type": "sphere", "position": [0.45, 0.05, 0.55], "radius": 0.1},
                  {"type": "box", "position": [0.2, -0.5, 0.2], "size": [0.1, 0.1, 0.1]}],
}
#: A state moving toward the sphere, near enough for its leaf to act.
STATE = (np.array([0.6, 0.3, 0.0, -1.6, 0.0, 1.9, 0.8]), np.array([-0.4, 0.3, 0.0, 0.2, 0.0, 0.1, 0.0]))


def _controller(data: dict[str, Any]) -> FabricController:
    scenario = scenario_from_dict(data)
    robot = robot_for(scenario)
    scenario = validate_for_robot(scenario, robot)
    controller = make_controller(scenario, robot, scenario_references(scenario, robot))
    assert isinstance(controller, FabricController)
    return controller


def _command(data: dict[str, Any]) -> np.ndarray:
    return _controller(data).planner.compute(*STATE)


def _documented_block() -> dict[str, dict[str, float]]:
    """The YAML example in fabric_schema's docstring."""
    text = fabric_schema.__doc__.split("```yaml\n")[1].split("```")[0]
    return yaml.safe_load(text)["fabric"]


def test_the_documented_defaults_are_the_planners() -> None:
    documented = _documented_block()
    goals = (GoalConfig(link="panda_hand"), OrientationGoalConfig(link="panda_hand"))
    arm = fabric_block(PlannerConfig.for_robot(PANDA, goals, obstacle_slots=1))
    assert arm == {key: value for key, value in documented.items() if key != "steering"}
    base = fabric_block(PlannerConfig.for_robot(BOXER, (GoalConfig(link="base_link"),), obstacle_slots=1))
    assert base["steering"] == documented["steering"]
    assert base["obstacle"] == {**documented["obstacle"], "range": 0.5}
    schema = ScenarioDocument.model_json_schema()["$defs"]["FabricMapping"]["properties"]
    assert "range 0.2 m; 0.5 m on a differential-drive base" in schema["obstacle"]["description"]


@pytest.mark.parametrize("robot", [PANDA, BOXER, load_robot("boxer-panda")], ids=lambda r: r.name)
def test_the_block_of_a_config_applied_to_it_changes_nothing(robot: Any) -> None:
    goals = (GoalConfig(link=robot.goal_link), OrientationGoalConfig(link=robot.goal_link)) \
        if not robot.planar else (GoalConfig(link=robot.goal_link),)
    config = PlannerConfig.for_robot(robot, goals, obstacle_slots=2)
    explicit = ScenarioDocument.model_validate({**REACH, "fabric": fabric_block(config)}).fabric.spec()
    assert explicit.configured(config) == config
    assert scenario_from_dict(REACH).fabric.configured(config) == config


def test_every_key_reaches_the_planner_config() -> None:
    block = {"obstacle": {"gain": 2.0, "energy_gain": 0.3, "range": 0.25},
             "self_collision": {"gain": 0.6, "energy_gain": 0.2, "range": 0.15},
             "joint_limits": {"gain": 0.2, "energy_gain": 0.1, "range": 0.4},
             "goal": {"gain": 7.0, "sharpness": 12.0, "metric_far": 0.4, "metric_near": 3.0, "metric_width": 0.5},
             "orientation": {"gain": 3.0, "sharpness": 8.0, "metric_far": 0.2, "metric_near": 1.5, "metric_width": 1.0},
             "speed_control": {"execution_energy": 0.8, "energy_sharpness": 4.0, "damping": 0.7, "goal_damping": 5.0,
                               "goal_damping_radius": 0.08, "goal_damping_sharpness": 12.0, "base_metric": 0.3}}
    data = {**REACH, "goal": REACH["goal"] + [{"type": "axis", "axis": [0, 0, 1], "direction": [0, 0, -1]}],
            "fabric": block}
    config = _controller(data).planner.config
    assert fabric_block(config) == block
    assert config.shape_avoidance.barrier == config.obstacle_avoidance.barrier
    assert isinstance(config.goals[1], OrientationGoalConfig) and config.goals[1].attractor.gain == 3.0


@pytest.mark.parametrize(("part", "key", "value"), [
    ("obstacle", "gain", 1.0), ("obstacle", "range", 0.5), ("obstacle", "energy_gain", 2.0),
    ("goal", "gain", 2.0), ("speed_control", "damping", 2.0), ("speed_control", "execution_energy", 0.1)])
def test_a_changed_value_changes_the_command(part: str, key: str, value: float) -> None:
    default = _command(REACH)
    assert np.array_equal(_command({**REACH, "fabric": {part: {}}}), default)
    changed = _command({**REACH, "fabric": {part: {key: value}}})
    assert np.all(np.isfinite(changed))
    assert np.linalg.norm(changed - default) > 1e-3 * np.linalg.norm(default)


def test_a_stronger_obstacle_barrier_keeps_more_clearance() -> None:
    weak = run_scenario(scenario_from_dict({**REACH, "fabric": {"obstacle": {"energy_gain": 0.05, "range": 0.1}}}))
    strong = run_scenario(scenario_from_dict({**REACH, "fabric": {"obstacle": {"energy_gain": 2.0, "range": 0.4}}}))
    assert strong.metrics.clearance > weak.metrics.clearance + 0.01


def test_a_default_block_runs_exactly_as_no_block() -> None:
    goals = (GoalConfig(link="panda_hand"),)
    reach = {**REACH, "guidance": False}   # the scenario's own fabric (the guided one has defaults of its own)
    explicit = {**reach, "fabric": fabric_block(PlannerConfig.for_robot(PANDA, goals, obstacle_slots=1))}
    with_block, without = run_scenario(scenario_from_dict(explicit)), run_scenario(scenario_from_dict(reach))
    assert np.array_equal(with_block.record.q, without.record.q)
    assert dataclasses.replace(with_block.metrics, solver_time_ms=0.0) == dataclasses.replace(without.metrics,
                                                                                              solver_time_ms=0.0)


def test_steering_applies_to_differential_drive_bases_only() -> None:
    base = {"robot": "boxer", "planner": "static-fabric", "dt": 0.01, "duration": 1.0,
            "initial_state": {"q": [0.0, 0.0, 0.0]}, "goal": [{"type": "position", "position": [2.0, 0.5]}],
            "fabric": {"steering": {"lookahead": 0.3}, "obstacle": {"range": 0.4}}}
    config = _controller(base).planner.config
    assert (config.steering.lookahead, config.steering.weight) == (0.3, 1.0)
    assert config.obstacle_avoidance.barrier.horizon == 0.4
    with pytest.raises(ScenarioError, match=r"^fabric\.steering: applies to robots on a differential-drive base"):
        _controller({**REACH, "fabric": {"steering": {"weight": 2.0}}})


def test_the_mpc_ignores_the_block() -> None:
    data = {**REACH, "planner": "mpc", "obstacles": REACH["obstacles"][:1], "fabric": {"goal": {"gain": 2.0}}}
    scenario = validate_for_robot(scenario_from_dict(data), PANDA)
    assert not isinstance(make_controller(scenario, PANDA, scenario_references(scenario, PANDA)), FabricController)


def test_schema_command_shows_the_block(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema"]) == 0
    schema = yaml.safe_load(capsys.readouterr().out)
    assert schema["properties"]["fabric"]["$ref"] == "#/$defs/FabricMapping"
    barrier = schema["$defs"]["BarrierMapping"]
    assert barrier["additionalProperties"] is False
    assert barrier["properties"]["range"]["anyOf"][0] == {"minimum": 0.01, "maximum": 10.0, "type": "number"}
    import jsonschema
    jsonschema.validate({**REACH, "fabric": {"obstacle": {"range": 0.3}}}, schema)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({**REACH, "fabric": {"obstacle": {"range": 0.0}}}, schema)


def test_a_bad_block_exits_2_naming_the_field(tmp_path: Any, capsys: pytest.CaptureFixture[str]) -> None:
    data = copy.deepcopy(REACH)
    data["fabric"] = {"goal": {"gain": 5.0, "gian": 1.0}}
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    assert main(["run", str(path)]) == 2
    assert capsys.readouterr().err == ("dynfab: error: fabric.goal.gian: unknown key (allowed: gain, sharpness, "
                                       "metric_far, metric_near, metric_width)\n")
