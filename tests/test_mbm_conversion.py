"""MotionBenchMaker problems converted to scenarios: obstacle poses, sizes and quaternion
order checked against the problem's own YAML."""

from __future__ import annotations

import tarfile

import numpy as np
import pytest
import yaml

from dynfab.benchmarks.mbm.conversion import GOAL_TOLERANCE, scenario_mapping
from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.moveit import ProblemError
from dynfab.benchmarks.mbm.problems import bundled_archive, load_problems, problem_from_texts
from dynfab.geometry.shapes import quaternion_matrix
from dynfab.scenario.schema import scenario_from_dict


def _raw(member: str) -> dict:
    with tarfile.open(bundled_archive(), "r:bz2") as tar:
        handle = tar.extractfile(member)
        assert handle is not None
        return yaml.safe_load(handle.read())


@pytest.mark.parametrize("problem_type", ["cage", "bookshelf_small"])
def test_obstacles_match_the_scene_file(problem_type: str) -> None:
    (problem,) = load_problems([problem_type], per_type=1)
    scene = _raw(f"problems/{problem_type}_panda/scene0009.yaml")
    request = _raw(f"problems/{problem_type}_panda/request0009.yaml")
    scenario = scenario_from_dict(scenario_mapping(problem, problem.objects, franka()))
    objects = scene["world"]["collision_objects"]
    assert len(scenario.obstacles) == len(objects)
    for obstacle, item in zip(scenario.obstacles, objects):
        primitive, pose = item["primitives"][0], item["primitive_poses"][0]
        assert obstacle.type == primitive["type"]
        np.testing.assert_allclose(obstacle.position, pose["position"])
        x, y, z, w = pose["orientation"]  # MoveIt's order
        np.testing.assert_allclose(obstacle.orientation, np.array([w, x, y, z]) / np.linalg.norm([w, x, y, z]))
        if obstacle.type == "box":
            np.testing.assert_allclose(obstacle.size, primitive["dimensions"])
        else:
            height, radius = primitive["dimensions"]
            assert (obstacle.length, obstacle.radius) == pytest.approx((height, radius))
    start = dict(zip(request["start_state"]["joint_state"]["name"], request["start_state"]["joint_state"]["position"]))
    assert scenario.initial_state.q == pytest.approx([start[f"panda_joint{i}"] for i in range(1, 8)])
    goal = {c["joint_name"]: c["position"] for c in request["goal_constraints"][0]["joint_constraints"]}
    assert scenario.goals[0].type == "joint" and scenario.goals[0].tolerance == GOAL_TOLERANCE
    assert scenario.goals[0].position == pytest.approx([goal[f"panda_joint{i}"] for i in range(1, 8)], abs=1e-6)


def test_a_cage_wall_is_turned_about_z_as_the_file_says() -> None:
    """The cage's back wall (0.04 x 0.7 x 0.7 m) is turned by -14.9 degrees about z: its
    thin x side points along (cos, sin) of that angle, as MoveIt's x, y, z, w means."""
    (problem,) = load_problems(["cage"], per_type=1)
    scenario = scenario_from_dict(scenario_mapping(problem, problem.objects, franka()))
    index = [o.id for o in problem.objects].index("side_back")
    wall = scenario.obstacles[index]
    angle = 2 * np.arcsin(-0.129817899849396)
    np.testing.assert_allclose(quaternion_matrix(wall.orientation)[:, 0], [np.cos(angle), np.sin(angle), 0.0],
                               atol=1e-9)
    assert wall.size == pytest.approx((0.04, 0.7, 0.7))


_SCENE = """
world:
  collision_objects:
    - id: Can1
      pose: {position: [1.0, 0.0, 0.0], orientation: [0, 0, 0.7071068, 0.7071068]}
      primitives: [{type: cylinder, dimensions: [0.2, 0.03]}]
      primitive_poses: [{position: [0.1, 0.0, 0.5], orientation: [0, 0, 0, 1]}]
"""
_REQUEST = """
start_state: {joint_state: {name: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, panda_joint5,
  panda_joint6, panda_joint7], position: [0, -0.785, 0, -2.356, 0, 1.571, 0.785]}}
goal_constraints:
  - joint_constraints: [{joint_name: panda_joint1, position: 0.1}, {joint_name: panda_joint2, position: 0.2},
      {joint_name: panda_joint3, position: 0.3}, {joint_name: panda_joint4, position: -1.0},
      {joint_name: panda_joint5, position: 0.5}, {joint_name: panda_joint6, position: 1.6},
      {joint_name: panda_joint7, position: 0.7}]
"""


def test_an_object_pose_places_its_primitives() -> None:
    problem = problem_from_texts("box", 1, {"scene": _SCENE, "request": _REQUEST})
    (can,) = problem.objects
    assert can.position == pytest.approx((1.0, 0.1, 0.5))  # turned 90 degrees about z, then shifted
    assert can.orientation == pytest.approx((0.7071068, 0.0, 0.0, 0.7071068))
    assert problem.goal == pytest.approx((0.1, 0.2, 0.3, -1.0, 0.5, 1.6, 0.7))


def test_a_malformed_file_names_file_and_field() -> None:
    scene = _SCENE.replace("[0.2, 0.03]", "[0.2]")
    with pytest.raises(ProblemError, match=r"^problems/box_panda/scene0001\.yaml: "
                                           r"world\.collision_objects\[0\]\.primitives\[0\]\.dimensions: "
                                           r"expected 2 numbers, got 1$"):
        problem_from_texts("box", 1, {"scene": scene, "request": _REQUEST})


def test_problems_can_start_after_the_first_ones_of_each_type() -> None:
    problems = load_problems(["box", "cage"], per_type=2, skip=3)
    assert [(p.type, p.number) for p in problems] == [("box", 12), ("box", 13), ("cage", 12), ("cage", 13)]
