"""Scenario files: valid files parse, every kind of bad input names its field."""

from __future__ import annotations

import copy
import dataclasses
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from dynfab.robots import load_robot
from dynfab.scenario.schema import (
    GoalSpec,
    InitialState,
    ScenarioError,
    UrdfRobotSpec,
    load_scenario,
    scenario_from_dict,
    validate_for_robot,
)

DESIGN_EXAMPLE = """
robot: panda                 # a built-in name, or {urdf: path/to/robot.urdf, ...}
planner: static-fabric       # static-fabric | dynamic-fabric | mpc
dt: 0.01                     # control period [s]
duration: 30.0               # [s] simulated time
initial_state:
  q: [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]
  qdot: [0, 0, 0, 0, 0, 0, 0]        # optional, zeros by default
goal:                        # one or more weighted sub-goals; the first is primary
  - type: position           # position | joint | path
    link: panda_hand         # goal link (end effector)
    position: [0.5, -0.4, 0.3]
    tolerance: 0.05          # [m] reached when closer than this
    weight: 1.0
obstacles:
  - type: sphere
    position: [0.5, 0.2, 0.5]
    radius: 0.15
  - type: sphere             # a moving sphere: position is a trajectory in t
    trajectory: {type: linear, start: [-1.0, -0.4, 0.7], velocity: [0.1, 0.0, 0.0]}
    radius: 0.1
"""

PANDA_LINKS = tuple(f"panda_link{i}" for i in range(9)) + ("panda_hand",)
_DELETE = object()


def _base() -> dict[str, Any]:
    """A valid scenario mapping for a 7-joint arm."""
    return {
        "robot": "panda",
        "planner": "dynamic-fabric",
        "dt": 0.01,
        "duration": 5.0,
        "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
        "goal": [{"type": "position", "link": "panda_hand", "position": [0.5, -0.4, 0.3]}],
        "obstacles": [{"type": "sphere", "position": [0.5, 0.2, 0.5], "radius": 0.15}],
    }


def _changed(path: tuple[str | int, ...], value: object) -> dict[str, Any]:
    """The base scenario with the item at ``path`` set to ``value`` (or deleted)."""
    data = copy.deepcopy(_base())
    parent: Any = data
    for key in path[:-1]:
        parent = parent[key]
    if value is _DELETE:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return data


def _fake_robot(dof: int = 7, planar: bool = False, links: tuple[str, ...] = PANDA_LINKS,
                goal_link: str = "panda_hand") -> SimpleNamespace:
    """Stand-in exposing the Robot attributes validate_for_robot reads."""
    return SimpleNamespace(
        kinematics=SimpleNamespace(dof=dof, link_names=links, joint_names=tuple(f"j{i + 1}" for i in range(dof)),
                                   lower=(-3.0,) * dof, upper=(3.0,) * dof),
        planar=planar, goal_link=goal_link, base=None
    )


def _error(data: object, base_dir: Path = Path(".")) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, base_dir)
    return info.value


def test_design_example_parses(tmp_path: Path) -> None:
    file = tmp_path / "example.yaml"
    file.write_text(DESIGN_EXAMPLE)
    scenario = load_scenario(file)
    assert scenario.path == file
    assert scenario.robot == "panda"
    assert scenario.planner == "static-fabric"
    assert scenario.dt == 0.01 and scenario.duration == 30.0
    assert scenario.initial_state.q == (1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0)
    assert scenario.initial_state.qdot == (0.0,) * 7
    assert scenario.goals == (
        GoalSpec(type="position", link="panda_hand", position=(0.5, -0.4, 0.3)),
    )
    static, moving = scenario.obstacles
    assert static.position == (0.5, 0.2, 0.5) and static.radius == 0.15
    assert static.trajectory is None
    assert moving.position is None and moving.radius == 0.1
    assert moving.trajectory is not None
    assert moving.trajectory["type"] == "linear"
    assert moving.trajectory["start"] == (-1.0, -0.4, 0.7)
    with pytest.raises(TypeError):
        moving.trajectory["type"] = "circle"  # type: ignore[index]


def test_defaults_and_optional_keys() -> None:
    data = _base()
    del data["obstacles"]
    data["goal"][0] = {"type": "position", "position": [0.5, 0.0]}
    scenario = scenario_from_dict(data)
    assert scenario.obstacles == ()
    assert scenario.initial_state.qdot is None  # zeros of the robot's size once validated
    reach = dataclasses.replace(scenario, goals=(GoalSpec("position", position=(0.5, 0.0, 0.3)),))
    assert validate_for_robot(reach, load_robot("panda")).initial_state.qdot == (0.0,) * 7
    on_a_base = dataclasses.replace(scenario, robot="boxer", initial_state=InitialState((0.0, 0.0, 0.0), None))
    assert validate_for_robot(on_a_base, load_robot("boxer")).initial_state.qdot == (0.0, 0.0)
    goal = scenario.goals[0]
    assert goal.link is None and goal.tolerance == 0.05 and goal.weight == 1.0
    assert goal.parent_link is None and goal.axes is None
    assert scenario.path is None


def test_joint_path_and_partial_goals() -> None:
    data = _base()
    data["goal"] = [
        {"type": "path", "link": "panda_hand", "tolerance": 0.1,
         "trajectory": {"type": "circle", "center": [0.5, 0.0, 0.5], "radius": 0.2,
                        "angular_velocity": 0.5, "normal": [0, 0, 1], "phase": 0}},
        {"type": "joint", "position": [0.0] * 7, "weight": 0.5},
        {"type": "position", "link": "panda_link8", "parent_link": "panda_link0",
         "axes": "xz", "position": [0.1, 0.4]},
    ]
    path, joint, partial = scenario_from_dict(data).goals
    assert path.type == "path" and path.position is None and path.tolerance == 0.1
    assert path.trajectory is not None and path.trajectory["normal"] == (0, 0, 1)
    assert joint.type == "joint" and joint.position == (0.0,) * 7 and joint.weight == 0.5
    assert joint.link is None and joint.trajectory is None
    assert partial.axes == "xz" and partial.position == (0.1, 0.4)
    assert partial.parent_link == "panda_link0"


def test_urdf_robot_resolved_against_scenario_directory(tmp_path: Path) -> None:
    (tmp_path / "robots").mkdir()
    urdf = tmp_path / "robots" / "arm.urdf"
    urdf.write_text("<robot name='arm'/>")
    file = tmp_path / "scenario.yaml"
    file.write_text(
        DESIGN_EXAMPLE.replace(
            "robot: panda ",
            "robot: {urdf: robots/arm.urdf, goal_link: tool, planar: true, "
            "collision_spheres: [{link: tool, center: [0, 0, 0.1], radius: 0.05}, "
            "{link: base, center: [0, 0, 0], radius: 0.2}], self_collision_pairs: [[0, 1]]}",
        )
    )
    robot = load_scenario(file).robot
    assert isinstance(robot, UrdfRobotSpec)
    assert robot.urdf == urdf
    assert robot.goal_link == "tool" and robot.planar is True
    assert [s.link for s in robot.collision_spheres] == ["tool", "base"]
    assert robot.collision_spheres[0].center == (0.0, 0.0, 0.1)
    assert robot.collision_spheres[1].radius == 0.2
    assert robot.self_collision_pairs == ((0, 1),)


@pytest.mark.parametrize(
    ("path", "value", "expected"),
    [
        (("gaol",), [], "gaol: unknown key"),
        (("dt",), _DELETE, "dt: missing required key"),
        (("dt",), "fast", "dt: expected a number, got str 'fast'"),
        (("dt",), True, "dt: expected a number, got boolean true"),
        (("dt",), -0.01, "dt: must be positive"),
        (("duration",), 0.005, "duration: must be at least dt"),
        (("duration",), float("inf"), "duration: expected a finite number"),
        (("planner",), "rrt", "planner: expected one of static-fabric"),
        (("robot",), "ur5", "robot: expected one of panda, point, boxer, boxer-panda"),
        (("robot",), 3, "robot: expected a built-in robot name or a mapping"),
        (("robot",), {"urdf": "x.urdf", "goal_link": "a", "color": "red"}, "robot.color: unknown key"),
        (("robot",), {"urdf": "missing.urdf", "goal_link": "a"}, "robot.urdf: file not found"),
        (("initial_state",), [1, 2], "initial_state: expected a mapping, got a list of 2"),
        (("initial_state", "q"), 1.0, "initial_state.q: expected a list"),
        (("initial_state", "q"), [], "initial_state.q: expected numbers, got an empty list"),
        (("initial_state", "q", 2), None, "initial_state.q[2]: expected a number, got null"),
        (("initial_state", "v"), [0.0], "initial_state.v: unknown key"),
        (("goal",), [], "goal: expected at least one goal"),
        (("goal",), {"type": "position"}, "goal: expected a list, got a mapping"),
        (("goal", 0), "panda_hand", "goal[0]: expected a mapping"),
        (("goal", 0, "positon"), [0, 0, 0], "goal[0].positon: unknown key"),
        (("goal", 0, "type"), "frame", "goal[0].type: expected one of position, joint, path, pose, axis"),
        (("goal", 0, "type"), _DELETE, "goal[0].type: missing required key"),
        (("goal", 0, "position"), _DELETE, "goal[0].position: missing required key"),
        (("goal", 0, "position"), [1, 2, 3, 4], "goal[0].position: expected 2 or 3 numbers, got 4"),
        (("goal", 0, "position", 1), float("nan"), "goal[0].position[1]: expected a finite number"),
        (("goal", 0, "tolerance"), -0.05, "goal[0].tolerance: must be positive"),
        (("goal", 0, "weight"), 0, "goal[0].weight: must be positive"),
        (("goal", 0, "link"), "", "goal[0].link: expected a non-empty text"),
        (("goal", 0, "axes"), "xx", "goal[0].axes: expected distinct axes"),
        (("goal", 0, "axes"), "xy", "goal[0].position: expected 2 numbers (one per axis of 'xy'), got 3"),
        (("goal", 0, "trajectory"), {"type": "linear"}, "goal[0].trajectory: unknown key"),
        (("goal", 0), {"type": "joint", "position": [0.0] * 7, "link": "panda_hand"},
         "goal[0].link: unknown key"),
        (("goal", 0), {"type": "path", "link": "panda_hand"}, "goal[0].trajectory: missing required key"),
        (("goal", 0), {"type": "path", "trajectory": {"start": [0, 0, 0]}},
         "goal[0].trajectory.type: missing required key"),
        (("obstacles",), "none", "obstacles: expected a list, got str 'none'"),
        (("obstacles", 0, "radius"), -0.1, "obstacles[0].radius: must be positive"),
        (("obstacles", 0, "radius"), _DELETE, "obstacles[0].radius: missing required key"),
        (("obstacles", 0, "type"), "cube", "obstacles[0].type: expected one of sphere, box, cylinder, capsule, plane"),
        (("obstacles", 0, "position"), [0.5], "obstacles[0].position: expected 2 or 3 numbers, got 1"),
        (("obstacles", 0, "position"), _DELETE, "obstacles[0]: expected exactly one of 'position'"),
        (("obstacles", 0, "trajectory"), {"type": "linear"}, "obstacles[0]: expected exactly one of"),
        (("obstacles", 0), {"type": "sphere", "radius": 0.1, "trajectory": [1, 2]},
         "obstacles[0].trajectory: expected a mapping, got a list of 2"),
        (("obstacles", 0), {"type": "sphere", "radius": 0.1, "trajectory": {"type": "zigzag"}},
         "obstacles[0].trajectory.type: expected one of linear, circle, polynomial, expression, spline, rrt"),
    ],
)
def test_bad_input_names_the_field(path: tuple[str | int, ...], value: object, expected: str) -> None:
    message = str(_error(_changed(path, value)))
    assert message.startswith(expected), message
    assert "\n" not in message


def test_urdf_robot_bad_spheres_and_pairs(tmp_path: Path) -> None:
    (tmp_path / "arm.urdf").write_text("<robot name='arm'/>")
    robot = {"urdf": "arm.urdf", "goal_link": "tool",
             "collision_spheres": [{"link": "tool", "center": [0, 0], "radius": 0.1}]}
    cases = [
        (robot, "robot.collision_spheres[0].center: expected 3 numbers, got 2"),
        ({**robot, "collision_spheres": [{"link": "tool", "center": [0, 0, 0], "radius": -1}]},
         "robot.collision_spheres[0].radius: must be positive"),
        ({**robot, "collision_spheres": [{"link": "tool", "center": [0, 0, 0], "radius": 1}],
          "self_collision_pairs": [[0, 1]]},
         "robot.self_collision_pairs[0][1]: sphere index 1 out of range"),
        ({**robot, "collision_spheres": [], "self_collision_pairs": [[0]]},
         "robot.self_collision_pairs[0]: expected 2 sphere indices, got 1"),
        ({**robot, "collision_spheres": [], "planar": "yes"},
         "robot.planar: expected true or false, got str 'yes'"),
    ]
    for spec, expected in cases:
        message = str(_error(_changed(("robot",), spec), tmp_path))
        assert message.startswith(expected), message


def test_top_level_must_be_a_mapping() -> None:
    assert str(_error([1, 2])).startswith("scenario: expected a mapping, got a list of 2")
    assert str(_error(None)).startswith("scenario: expected a mapping, got null")


def test_yaml_specific_errors(tmp_path: Path) -> None:
    file = tmp_path / "s.yaml"
    file.write_text(DESIGN_EXAMPLE.replace("dt: 0.01 ", "dt: 1e-2 "))
    with pytest.raises(ScenarioError, match=r"^dt: expected a number, got str '1e-2' \(YAML"):
        load_scenario(file)
    file.write_text(DESIGN_EXAMPLE.replace("radius: 0.15", "radius: .nan"))
    with pytest.raises(ScenarioError, match=r"^obstacles\[0\]\.radius: expected a finite number"):
        load_scenario(file)
    file.write_text("robot: panda\ngoal: [1, 2\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(file)
    assert str(info.value).startswith(f"{file}: invalid YAML")
    assert "line" in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(ScenarioError, match="cannot read file"):
        load_scenario(tmp_path / "missing.yaml")


def test_strings_are_never_evaluated(tmp_path: Path) -> None:
    file = tmp_path / "s.yaml"
    marker = tmp_path / "pwned"
    file.write_text(
        DESIGN_EXAMPLE.replace("dt: 0.01 ", f"dt: !!python/object/apply:os.system ['touch {marker}'] ")
    )
    with pytest.raises(ScenarioError, match="invalid YAML"):
        load_scenario(file)
    assert not marker.exists()


def test_validate_for_robot_fills_goal_link() -> None:
    data = _base()
    data["goal"].append({"type": "path", "trajectory": {"type": "linear", "start": [0.5, 0.0, 0.5], "velocity": [0.0, 0.1, 0.0]}})
    del data["goal"][0]["link"]
    scenario = validate_for_robot(scenario_from_dict(data), _fake_robot())
    assert [goal.link for goal in scenario.goals] == ["panda_hand", "panda_hand"]


def test_validate_for_robot_accepts_planar_shapes() -> None:
    data = _changed(("initial_state", "q"), [0.0, 0.0])
    data["goal"] = [
        {"type": "position", "link": "point", "position": [1.0, 2.0]},
        {"type": "position", "position": [1.0], "axes": "x"},
    ]
    data["obstacles"].append({"type": "sphere", "position": [0.5, 0.2], "radius": 0.1})
    robot = _fake_robot(dof=2, planar=True, links=("world", "point"), goal_link="point")
    scenario = validate_for_robot(scenario_from_dict(data), robot)
    assert [goal.link for goal in scenario.goals] == ["point", "point"]


@pytest.mark.parametrize(
    ("path", "value", "robot", "expected"),
    [
        (("initial_state", "q"), [0.0] * 6, _fake_robot(), "initial_state.q: expected 7 numbers (one per joint: j1, j2, j3, j4, j5, j6, j7), got 6"),
        (("initial_state", "qdot"), [0.0] * 6, _fake_robot(), "initial_state.qdot: expected 7 numbers (one per velocity: j1, j2, j3, j4, j5, j6, j7), got 6"),
        (("goal", 0, "position"), [0.5, 0.1], _fake_robot(), "goal[0].position: expected 3 numbers, got 2"),
        (("goal", 0, "link"), "gripper", _fake_robot(), "goal[0].link: unknown link 'gripper'"),
        (("goal", 0, "parent_link"), "table", _fake_robot(), "goal[0].parent_link: unknown link 'table'"),
        (("goal", 0), {"type": "joint", "position": [0.0] * 3}, _fake_robot(),
         "goal[0].position: expected 7 numbers (one per joint: j1, j2, j3, j4, j5, j6, j7), got 3"),
        (("obstacles", 0, "position"), [0.5, 0.2], _fake_robot(),
         "obstacles[0].position: expected 3 numbers, got 2"),
        (("goal", 0), {"type": "position", "axes": "xz", "position": [0.0, 0.0]},
         _fake_robot(planar=True), "goal[0].axes: planar robot has no z axis"),
        (("goal", 0, "position"), [0.5, 0.1, 0.2], _fake_robot(planar=True),
         "goal[0].position: expected 2 numbers, got 3"),
    ],
)
def test_validate_for_robot_names_the_field(
    path: tuple[str | int, ...], value: object, robot: SimpleNamespace, expected: str
) -> None:
    scenario = scenario_from_dict(_changed(path, value))
    with pytest.raises(ScenarioError) as info:
        validate_for_robot(scenario, robot)  # type: ignore[arg-type]
    assert str(info.value).startswith(expected), str(info.value)


def test_validate_for_robot_checks_urdf_robot_links(tmp_path: Path) -> None:
    (tmp_path / "arm.urdf").write_text("<robot name='arm'/>")
    robot_spec = {"urdf": "arm.urdf", "goal_link": "panda_hand",
                  "collision_spheres": [{"link": "elbow", "center": [0, 0, 0], "radius": 0.1}]}
    scenario = scenario_from_dict(_changed(("robot",), robot_spec), tmp_path)
    with pytest.raises(ScenarioError, match=r"^robot\.collision_spheres\[0\]\.link: unknown link"):
        validate_for_robot(scenario, _fake_robot())  # type: ignore[arg-type]
    fixed = dataclasses.replace(
        scenario, robot=dataclasses.replace(scenario.robot, goal_link="tool")  # type: ignore[type-var]
    )
    with pytest.raises(ScenarioError, match=r"^robot\.goal_link: unknown link 'tool'"):
        validate_for_robot(fixed, _fake_robot())  # type: ignore[arg-type]


def test_error_is_a_value_error_with_field() -> None:
    error = _error(_changed(("goal", 0, "position"), [1.0]))
    assert isinstance(error, ValueError)
    assert error.field == "goal[0].position"
    assert error.problem == "expected 2 or 3 numbers, got 1"
