"""Bad scene input (issue 20 item 6) not covered elsewhere: mesh files without triangles with
an area, URDF scenes naming such meshes or none, an all-NaN cloud file, an open mesh (kept
away from on both sides), NaN, infinite and 10⁷ points given at run time. The whole table,
with the tests of the other items, is in docs/guides/meshes.md ("Bad input")."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import trimesh

from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.geometry.distance_grid import distance_grid
from dynfab.geometry.mesh_distance import mesh_signed_distance, nearest_on_mesh
from dynfab.geometry.mesh_shape import Mesh
from dynfab.perception.point_clouds import PointCloudFeed
from dynfab.robots.builtin import load_robot
from dynfab.scenario.schema import ScenarioError, scenario_from_dict

START = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785]


def _scenario(obstacles: list[dict]) -> dict:
    return {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 1.0, "initial_state": {"q": START},
            "goal": [{"type": "position", "link": "panda_hand", "position": [0.45, 0.0, 0.4], "tolerance": 0.05}],
            "obstacles": obstacles}


def _scene_urdf(mesh: str) -> str:
    return (f'<robot name="scene"><link name="root"><collision><geometry><mesh filename="{mesh}"/></geometry>'
            '</collision></link></robot>')


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An empty STL, one of collinear (zero-area) triangles, URDF scenes naming them, one
    without collision geometry, and a cloud of NaN rows only."""
    folder = tmp_path_factory.mktemp("bad")
    (folder / "empty.stl").write_bytes(b"")
    line = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    trimesh.Trimesh(line, [[0, 1, 2], [1, 2, 3]], process=False).export(folder / "flat.stl")
    (folder / "empty_mesh.urdf").write_text(_scene_urdf("empty.stl"))
    (folder / "flat_mesh.urdf").write_text(_scene_urdf("flat.stl"))
    (folder / "no_collision.urdf").write_text('<robot name="scene"><link name="root"/></robot>')
    np.save(folder / "all_nan.npy", np.full((5, 3), np.nan))
    return folder


@pytest.mark.parametrize(("entry", "problem"), [
    ({"type": "mesh", "file": "empty.stl", "position": [0, 0, 0]}, "empty.stl has no triangles"),
    ({"type": "mesh", "file": "flat.stl", "position": [0, 0, 0]}, "flat.stl has no triangles with an area"),
    ({"type": "urdf", "file": "empty_mesh.urdf"}, "link 'root': empty.stl has no triangles"),
    ({"type": "urdf", "file": "flat_mesh.urdf"}, "link 'root': flat.stl has no triangles with an area"),
    ({"type": "urdf", "file": "no_collision.urdf"}, "no_collision.urdf has no <collision> geometry"),
])
def test_a_mesh_without_faces_is_refused_naming_the_entry_file(files: Path, entry: dict, problem: str) -> None:
    with pytest.raises(ScenarioError) as error:
        scenario_from_dict(_scenario([entry]), files)
    assert error.value.field == "obstacles[0].file" and problem in error.value.problem


def test_a_cloud_file_of_nan_rows_only_is_no_obstacle_and_says_so(files: Path, capsys: pytest.CaptureFixture[str]
                                                                  ) -> None:
    assert scenario_from_dict(_scenario([{"type": "points", "file": "all_nan.npy"}]), files).obstacles == ()
    err = capsys.readouterr().err
    assert "obstacles[0].file: all_nan.npy: 5 NaN or infinite points dropped" in err
    assert "all_nan.npy has no finite point: no obstacle" in err


def test_an_open_mesh_is_kept_away_from_on_both_sides() -> None:
    """A square sheet (two triangles, not watertight) has no inside: a point 10 cm above and
    one 10 cm below are both 10 cm away, signed or not, for the fabric's nearest points and
    for the checker's grid (which never overstates); a closed box's inside reads negative."""
    sheet = Mesh(np.array([[-0.5, -0.5, 0.0], [0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [-0.5, 0.5, 0.0]]),
                 np.array([[0, 1, 2], [0, 2, 3]]))
    assert not sheet.watertight
    sides = np.array([[0.1, 0.0, 0.1], [0.1, 0.0, -0.1]])
    nearest = nearest_on_mesh(sheet, sides)
    np.testing.assert_allclose(nearest.distances, [0.1, 0.1])
    np.testing.assert_allclose(nearest.normals, [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]], atol=1e-9)
    bound = distance_grid(sheet).lower_bound(sides)
    assert (bound > 0.05).all() and (bound <= 0.1 + 1e-12).all()
    np.testing.assert_allclose(mesh_signed_distance(sheet, sides, signed_within=0.2), [0.1, 0.1])
    box = trimesh.creation.box(extents=(0.4, 0.4, 0.4))
    assert mesh_signed_distance(Mesh(box.vertices, box.faces), np.array([0.0, 0.0, 0.15])) == pytest.approx(-0.05)


@pytest.fixture(scope="module")
def feed_and_planner() -> tuple[PointCloudFeed, FabricPlanner]:
    robot = load_robot("panda")
    leaf = NearestSurfaceAvoidance(spheres=moving_spheres(robot))
    planner = FabricPlanner(robot, PlannerConfig(goals=(GoalConfig(link="panda_hand"),), leaves=(leaf,)))
    planner.parameters.goal_position[0] = [0.45, 0.0, 0.4]
    return PointCloudFeed(robot, leaf, planner.parameters.leaves[leaf.name], max_points=200_000), planner


def _finite_step(feed: PointCloudFeed, planner: FabricPlanner) -> None:
    """One tick with the feed's cloud: the planner's next state is finite."""
    q = np.array(START)
    feed.write(q)
    q_next, qdot_next = planner.step(q, np.zeros_like(q))
    assert np.isfinite(q_next).all() and np.isfinite(qdot_next).all()


def test_nan_and_infinite_points_at_run_time_are_dropped_and_counted(
        feed_and_planner: tuple[PointCloudFeed, FabricPlanner]) -> None:
    feed, planner = feed_and_planner
    rng = np.random.default_rng(0)
    wall = np.column_stack([np.full(2000, 0.7), rng.uniform(-0.4, 0.4, 2000), rng.uniform(0.0, 0.8, 2000)])
    wall[:10, 0] = np.nan
    wall[10:15, 1] = np.inf
    wall[15:18, 2] = -np.inf
    update = feed.update_points(wall, np.array(START))
    assert update.received == 2000 and update.dropped == 18 and update.kept > 0
    assert np.isfinite(feed.cloud.points).all()
    _finite_step(feed, planner)
    nothing = feed.update_points(np.full((100, 3), np.nan), np.array(START))
    assert nothing.dropped == 100 and nothing.kept == 0 and feed.cloud.empty
    feed.write(np.array(START))
    assert not planner.parameters.leaves["surfaces"]["active"].any()  # no cloud: no obstacle
    _finite_step(feed, planner)


def test_ten_million_points_at_run_time_keep_the_cap_in_bounded_memory(
        feed_and_planner: tuple[PointCloudFeed, FabricPlanner]) -> None:
    feed, planner = feed_and_planner
    raw = np.random.default_rng(1).uniform([0.5, -1.0, 0.0], [1.5, 1.0, 1.0], (10_000_000, 3)).astype(np.float32)
    tracemalloc.start()
    update = feed.update_points(raw, np.array(START))
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert update.received == 10_000_000 and update.kept <= 200_000 and update.voxel == pytest.approx(0.04)
    assert peak < 200e6  # the 120 MB input is not copied: chunks of 10⁶ rows
    _finite_step(feed, planner)
