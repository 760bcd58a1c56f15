"""A guided scenario's meshes and point clouds take guidance's grasp allowance: each has an
entry of the nearest-point feed, whose points are then written that much deeper."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from dynfab.fabric.planner import FabricPlanner
from dynfab.robots import load_robot
from dynfab.scenario.controllers import mesh_obstacles
from dynfab.scenario.guided_controller import SurfaceAllowance, guided_planner_config
from dynfab.scenario.references import scenario_references
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot

START = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785]


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory):
    """A Panda guided to a point beside a box mesh, a sphere and a small cloud: its planner,
    the feed of its mesh and cloud, and its references."""
    folder = tmp_path_factory.mktemp("allowance")
    trimesh.creation.box(extents=(0.1, 0.4, 0.4)).export(folder / "box.stl")
    np.save(folder / "cloud.npy", np.array([[0.3, -0.4, 0.6], [0.31, -0.4, 0.6]]))
    robot = load_robot("panda")
    scenario = validate_for_robot(scenario_from_dict({
        "robot": "panda", "planner": "dynamic-fabric", "dt": 0.01, "duration": 1.0, "initial_state": {"q": START},
        "goal": [{"type": "position", "link": "panda_hand", "position": [0.5, 0.0, 0.5]}],
        "obstacles": [{"type": "sphere", "radius": 0.05, "position": [0.0, 0.6, 0.5]},
                      {"type": "mesh", "file": "box.stl", "position": [0.62, 0.0, 0.45]},
                      {"type": "points", "file": "cloud.npy"}]}, folder), robot)
    planner = FabricPlanner(robot, guided_planner_config(robot, scenario))
    surfaces = mesh_obstacles(planner, robot, scenario.obstacles)
    assert surfaces is not None
    return planner, surfaces, scenario_references(scenario, robot)


def test_meshes_and_clouds_each_have_an_allowance_entry_and_nothing_else_has(scene) -> None:
    _, surfaces, _ = scene
    assert (surfaces.surface_of(1), surfaces.surface_of(2)) == (0, 1)
    with pytest.raises(ValueError, match=r"obstacles\[0\]"):
        surfaces.surface_of(0)


def test_an_allowance_written_to_a_mesh_moves_its_nearest_points_that_much_deeper(scene) -> None:
    planner, surfaces, references = scene
    q = np.array([0.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.785])
    views = planner.parameters.leaves["surfaces"]
    surfaces.write(0.0, q, references)
    active = views["active"].astype(bool).copy()
    points, normals = views["points"].reshape(-1, 3).copy(), views["normals"].reshape(-1, 3).copy()
    assert active.any()
    SurfaceAllowance(surfaces, surfaces.surface_of(1)).write(planner.parameters, 0.004)
    surfaces.write(0.0, q, references)
    np.testing.assert_allclose(views["points"].reshape(-1, 3)[active], points[active] - 0.004 * normals[active],
                               atol=1e-12)
    SurfaceAllowance(surfaces, surfaces.surface_of(1)).write(planner.parameters, 0.0)
