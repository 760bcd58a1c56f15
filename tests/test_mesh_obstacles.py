"""Mesh and URDF-scene obstacles in scenario files: loading, bad input (each refused naming
its field), the checker's distance grid (a lower bound, how tight), and a guided Panda run
into a mesh shelf without touching it (measured on the meshes)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from dynfab.geometry.distance_grid import distance_grid
from dynfab.geometry.mesh_distance import nearest_on_mesh
from dynfab.geometry.mesh_files import read_mesh
from dynfab.scenario.schema import ScenarioError, scenario_from_dict

START = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785]


def _scenario(obstacles: list[dict], **extra: object) -> dict:
    return {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 5.0,
            "initial_state": {"q": START},
            "goal": [{"type": "position", "link": "panda_hand", "position": [0.62, 0.0, 0.42], "tolerance": 0.05}],
            "obstacles": obstacles, **extra}


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A shelf (two boards and a back, each closed), a scene URDF naming it and
    a box, a URDF naming a missing mesh, and files that are not meshes."""
    folder = tmp_path_factory.mktemp("meshes")
    boards = [trimesh.creation.box(extents=(0.4, 0.8, 0.02)).apply_translation((0, 0, z)) for z in (0.0, 0.35)]
    back = trimesh.creation.box(extents=(0.02, 0.8, 0.37)).apply_translation((0.2, 0, 0.175))
    trimesh.util.concatenate([*boards, back]).export(folder / "shelf.stl")
    (folder / "points.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                       "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n")
    (folder / "scene.urdf").write_text(
        '<robot name="scene"><link name="root"/><link name="shelf"><collision><origin xyz="0.1 0 0"/>'
        '<geometry><mesh filename="shelf.stl"/></geometry></collision></link>'
        '<link name="table"><collision><geometry><box size="1 1 0.05"/></geometry></collision></link>'
        '<joint name="a" type="fixed"><parent link="root"/><child link="shelf"/></joint>'
        '<joint name="b" type="revolute"><parent link="root"/><child link="table"/><origin xyz="0 0 -0.3"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>')
    (folder / "missing.urdf").write_text(
        '<robot name="scene"><link name="root"><collision><geometry><mesh filename="gone.stl"/></geometry>'
        '</collision></link></robot>')
    return folder


def test_a_urdf_scene_becomes_its_collision_geometry_placed(files: Path) -> None:
    scenario = scenario_from_dict(_scenario([{"type": "urdf", "file": "scene.urdf", "position": [0.75, 0.0, 0.25]}]),
                                  files)
    shelf, table = scenario.obstacles
    assert shelf.type == "mesh" and shelf.position == pytest.approx((0.85, 0.0, 0.25))
    assert table.type == "box" and table.size == (1.0, 1.0, 0.05) and table.position == pytest.approx((0.75, 0.0, -0.05))
    assert shelf.mesh.watertight  # three closed boards: solid once the STL's repeated vertices are merged


def test_an_obstacle_after_a_urdf_scene_is_named_by_its_entry_in_the_file(files: Path) -> None:
    """A URDF scene's two geometries are two obstacles but one entry: the moving sphere after
    it is ``obstacles[1]`` in messages and contacts, not the third obstacle."""
    from dynfab.robots import load_robot
    from dynfab.scenario.references import scenario_references

    ball = {"type": "sphere", "radius": 0.05, "trajectory": {"type": "linear", "start": [1.0, 1.0],
                                                              "velocity": [0.0, 0.1]}}
    scenario = scenario_from_dict(_scenario([{"type": "urdf", "file": "scene.urdf", "position": [0.75, 0.0, 0.25]},
                                             ball]), files)
    assert [o.name(k) for k, o in enumerate(scenario.obstacles)] == ["obstacles[0]", "obstacles[0]", "obstacles[1]"]
    with pytest.raises(ScenarioError) as error:
        scenario_references(scenario, load_robot("panda"))
    assert error.value.field == "obstacles[1].trajectory" and "expected 3 coordinates, got 2" in error.value.problem


@pytest.mark.parametrize(("entry", "field", "problem"), [
    ({"type": "mesh", "file": "nowhere.stl", "position": [0, 0, 0]}, "obstacles[0].file", "file not found"),
    ({"type": "mesh", "file": "points.ply", "position": [0, 0, 0]}, "obstacles[0].file", "no triangles"),
    ({"type": "mesh", "file": "scene.urdf", "position": [0, 0, 0]}, "obstacles[0].file", "cannot be read"),
    ({"type": "mesh", "file": "shelf.stl", "position": [0, math.nan, 0]}, "obstacles[0].position[1]", "finite"),
    ({"type": "mesh", "file": "shelf.stl", "position": [0, 0, 0], "scale": 0}, "obstacles[0].scale", "positive"),
    ({"type": "mesh", "file": "shelf.stl", "position": [0, 0, 0], "scale": -2}, "obstacles[0].scale", "positive"),
    ({"type": "mesh", "file": "shelf.stl"}, "obstacles[0]", "exactly one of 'position'"),
    ({"type": "urdf", "file": "missing.urdf"}, "obstacles[0].file", "link 'root': collision mesh 'gone.stl' not found"),
    ({"type": "urdf", "file": "scene.urdf", "position": [0, 0, math.inf]}, "obstacles[0].position[2]", "finite"),
])
def test_bad_mesh_input_is_refused_naming_the_field(files: Path, entry: dict, field: str, problem: str) -> None:
    with pytest.raises(ScenarioError) as error:
        scenario_from_dict(_scenario([entry]), files)
    assert error.value.field == field and problem in error.value.problem


def test_a_mesh_with_too_many_triangles_is_refused_before_use(files: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("dynfab.geometry.mesh_files.MAX_MESH_FACES", 10)
    with pytest.raises(ScenarioError, match=r"has 36 triangles, more than 10"):
        scenario_from_dict(_scenario([{"type": "mesh", "file": "shelf.stl", "position": [0, 0, 0]}]), files)


def test_the_distance_grid_never_overstates_and_is_within_a_cell_diagonal_near_the_surface(files: Path) -> None:
    mesh = read_mesh(files / "shelf.stl")
    grid = distance_grid(mesh)
    points = np.random.default_rng(3).uniform(mesh.bounds[0] - 0.3, mesh.bounds[1] + 0.3, size=(5000, 3))
    exact = nearest_on_mesh(mesh, points).distances
    bound = grid.lower_bound(points)
    assert (bound <= exact + 1e-12).all()
    near = exact < 0.03
    assert near.sum() > 100 and (exact - bound)[near].max() <= math.sqrt(3) * grid.pitch


def test_a_guided_panda_reaches_into_a_mesh_shelf_without_touching_it(files: Path) -> None:
    path = files / "shelf_run.yaml"
    path.write_text(json.dumps(_scenario([{"type": "mesh", "file": "shelf.stl", "position": [0.75, 0.0, 0.25]}])))
    run = subprocess.run([sys.executable, "-m", "dynfab.cli", "run", str(path), "--json"], capture_output=True, text=True,
                         timeout=600)
    result = json.loads(run.stdout)
    assert run.returncode == 0, run.stderr[-2000:]
    assert result["goal_reached"] and result["guided"] and not result["collision"]
    assert result["clearance"] > 0.0  # Franka's meshes vs the shelf's triangles (coal)
