"""MBM's mesh scenes (kitchen, table_bars): scene joints in {type: urdf}, problems generated
from a seed as MBM does, and the distance grid's disk cache."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dynfab.benchmarks.mbm.franka import TCP_LINK, franka
from dynfab.benchmarks.mbm.scene_configs import data_root, scene_config
from dynfab.benchmarks.mbm.scenes import generate_scene_problem, prepare_scene_case
from dynfab.benchmarks.mbm.validity import static_shapes
from dynfab.geometry.distance_grid import distance_grid
from dynfab.geometry.mesh_files import read_mesh
from dynfab.robots.mesh_sweep import sweep_meshes
from dynfab.scenario.schema import ScenarioError, scenario_from_dict

KITCHEN = "package://motion_bench_maker/configs/scenes/kitchen/kitchen.urdf"


def _scene(joints: dict[str, float]) -> dict[str, object]:
    q = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
    return {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 0.1, "initial_state": {"q": q},
            "goal": [{"type": "joint", "position": q}],
            "obstacles": [{"type": "urdf", "file": KITCHEN, "package_dirs": [str(data_root())], "joints": joints}]}


def test_scene_joints_turn_their_links() -> None:
    closed = scenario_from_dict(_scene({})).obstacles
    opened = scenario_from_dict(_scene({"dishwasher_door_joint": -1.57})).obstacles
    door = 2  # breadth first from the root: cupboard, kitchen_counter, dishwasher_door, ...
    assert closed[door].orientation == pytest.approx((1.0, 0.0, 0.0, 0.0))
    # a turn by -1.57 rad about y: w = cos(-0.785), y = sin(-0.785)
    assert opened[door].orientation == pytest.approx((np.cos(0.785), 0.0, -np.sin(0.785), 0.0))
    assert opened[door].position == pytest.approx(closed[door].position)


@pytest.mark.parametrize(("joints", "message"), [
    ({"door": 0.1}, "obstacles[0].joints.door: no movable joint of the scene is named 'door'"),
    ({"dishwasher_door_joint": 0.5}, "obstacles[0].joints.dishwasher_door_joint: 0.5 is outside the joint's limits"),
])
def test_bad_scene_joints_are_named(joints: dict[str, float], message: str) -> None:
    with pytest.raises(ScenarioError, match=message.replace("[", r"\[").replace("]", r"\]").replace(".", r"\.")):
        scenario_from_dict(_scene(joints))


@pytest.mark.parametrize("scene", ["kitchen", "table_bars"])
def test_generated_problem_is_free_reproducible_and_at_its_query(scene: str) -> None:
    robot = franka()
    problem = generate_scene_problem(scene, 1, 7, robot)
    again = generate_scene_problem(scene, 1, 7, robot)
    assert again.start == problem.start and again.scene == problem.scene
    assert np.array_equal(again.goal_pose, problem.goal_pose)
    case = prepare_scene_case(problem)
    shapes = static_shapes(scenario_from_dict(case.mapping))
    sweep = sweep_meshes(robot.meshes, np.array([problem.start, problem.goal]), shapes)
    assert not sweep.obstacle_contacts and not sweep.self_contacts
    tcp = np.array(robot.robot.kinematics.transform(np.array(problem.goal), TCP_LINK), dtype=float)
    assert np.allclose(tcp, problem.goal_pose, atol=1e-5)
    config = scene_config(scene)
    assert len(problem.scene["joints"]) == {"kitchen": 3, "table_bars": 2}[scene]  # every movable joint drawn
    goal = case.mapping["goal"][0]
    assert goal["type"] == "pose" and goal["tolerance"] == 0.01
    assert config.goal_queries[0].obj in problem.queries


def test_distance_grid_is_loaded_from_its_disk_cache(tmp_path: Path) -> None:
    path = data_root() / "motion_bench_maker/configs/scenes/kitchen/meshes/dishwasher_door.stl"
    built = distance_grid(read_mesh(path, (1.0, 1.0, 1.0)), cache=tmp_path)
    files = list(tmp_path.glob("grid-*.npz"))
    assert len(files) == 1
    loaded = distance_grid(read_mesh(path, (1.0, 1.0, 1.0)), cache=tmp_path)
    assert loaded is not built and np.array_equal(loaded.values, built.values)
    assert loaded.pitch == built.pitch and np.array_equal(loaded.origin, built.origin)
    files[0].write_bytes(b"not a grid")
    rebuilt = distance_grid(read_mesh(path, (1.0, 1.0, 1.0)), cache=tmp_path)
    assert np.array_equal(rebuilt.values, built.values)
