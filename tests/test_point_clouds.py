"""Point clouds: voxel downsampling and its cap, the bounds the fabric and the checker read
(never above the distance to a measured point), the file readers and their bad input, the
scenario entry (empty, NaN, malformed), the run-time feed (robot filtered out, nearest
points written), 10⁷ points in bounded time and memory, the compiled checker's bound, the
example."""

from __future__ import annotations

import math
import re
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.geometry.cloud_files import CloudFileError, read_points
from dynfab.geometry.cloud_grid import cloud_distance_grid
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Placement
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.perception.point_clouds import PointCloudFeed
from dynfab.robots.builtin import load_robot
from dynfab.scenario.schema import ScenarioError, scenario_from_dict

START = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785]


def _wall(rng: np.random.Generator, count: int = 20_000) -> np.ndarray:
    """Noisy points on a vertical wall x = 0.6 and a floor z = 0."""
    wall = np.column_stack([np.full(count, 0.6), rng.uniform(-0.4, 0.4, count), rng.uniform(0.0, 0.8, count)])
    floor = np.column_stack([rng.uniform(0.2, 0.8, count), rng.uniform(-0.4, 0.4, count), np.zeros(count)])
    return np.concatenate([wall, floor]) + rng.normal(0.0, 0.002, (2 * count, 3))


def _scenario(obstacles: list[dict]) -> dict:
    return {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 2.0, "initial_state": {"q": START},
            "goal": [{"type": "position", "link": "panda_hand", "position": [0.45, 0.0, 0.4], "tolerance": 0.05}],
            "obstacles": obstacles}


def test_downsampling_keeps_one_voxel_centre_per_occupied_voxel_within_its_half_diagonal() -> None:
    raw = _wall(np.random.default_rng(0))
    cloud = PointCloud.from_points(raw, voxel=0.02)
    cells = np.unique(np.floor(raw / 0.02).astype(int), axis=0)
    assert len(cloud.points) == len(cells)
    assert np.allclose(np.sort(cloud.points, axis=0), np.sort((cells + 0.5) * 0.02, axis=0))
    gaps, _ = cKDTree(cloud.points).query(raw)
    assert gaps.max() <= cloud.lowering + 1e-12 and cloud.lowering == pytest.approx(0.01 * math.sqrt(3))


def test_the_cap_doubles_the_voxel_until_it_holds() -> None:
    raw = _wall(np.random.default_rng(1))
    cloud = PointCloud.from_points(raw, voxel=0.005, max_points=2000)
    assert len(cloud.points) <= 2000 and cloud.voxel in (0.01, 0.02, 0.04, 0.08)
    assert len(PointCloud.from_points(raw, voxel=cloud.voxel / 2).points) > 2000


def test_nan_and_infinite_rows_are_dropped_and_counted() -> None:
    raw = _wall(np.random.default_rng(2), 100)
    raw[[3, 7], 1] = np.nan
    raw[11, 2] = np.inf
    cloud = PointCloud.from_points(raw, voxel=0.01)
    assert cloud.dropped == 3 and np.isfinite(cloud.points).all()


def test_the_fabric_and_the_checker_never_overstate_the_distance_to_a_measured_point() -> None:
    rng = np.random.default_rng(3)
    raw = _wall(rng)
    cloud = PointCloud.from_points(raw, voxel=0.01)
    queries = rng.uniform([0.0, -0.6, -0.2], [1.0, 0.6, 1.0], (4000, 3))
    exact, _ = cKDTree(raw).query(queries)
    nearest = cloud.nearest(queries)
    assert nearest.found.all() and (nearest.distances <= exact + 1e-12).all()
    # the leaf's tangent-plane clearance n·(x − point) equals the distance written
    plane = np.einsum("ij,ij->i", nearest.normals, queries - nearest.points)
    assert np.allclose(plane, nearest.distances)
    assert (exact - nearest.distances).max() <= 2 * cloud.lowering
    grid = cloud_distance_grid(cloud)
    bound = grid.lower_bound(queries)
    assert (bound <= exact + 1e-12).all() and (bound >= grid.lower_bound(queries) - 1e-12).all()
    near = exact < 0.05
    assert near.sum() > 200 and (exact - bound)[near].max() <= math.sqrt(3) * grid.pitch + 2 * cloud.lowering


def test_nearest_points_beyond_the_reach_are_not_found() -> None:
    cloud = PointCloud.from_points(np.array([[0.0, 0.0, 0.0]]), voxel=0.01)
    found = cloud.nearest(np.array([[0.0, 0.0, 0.1], [0.0, 0.0, 0.5]]), max_distance=0.2)
    assert found.found.tolist() == [True, False]
    assert found.distances[0] == pytest.approx(math.hypot(0.005, 0.005, 0.095) - cloud.lowering)  # to the voxel centre


def test_ten_million_points_reduce_in_bounded_time_and_memory() -> None:
    raw = np.random.default_rng(4).uniform(-1.0, 1.0, (10_000_000, 3)).astype(np.float32)
    tracemalloc.start()
    start = time.perf_counter()
    cloud = PointCloud.from_points(raw, voxel=0.01, max_points=200_000)
    elapsed = time.perf_counter() - start
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert len(cloud.points) <= 200_000 and cloud.voxel == pytest.approx(0.04)
    assert elapsed < 30.0
    assert peak < 200e6  # the 120 MB input is not copied: chunks of 10⁶ rows


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("clouds")
    points = np.array([[0.5, 0.0, 0.1], [0.5, 0.1, 0.2], [0.6, -0.1, 0.3]])
    np.save(folder / "cloud.npy", points)
    header = ("VERSION .7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
              "WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\n")
    rows = np.column_stack([points, np.ones(3)]).astype("<f4")
    (folder / "ascii.pcd").write_text(header + "DATA ascii\n" + "\n".join(" ".join(f"{v:.6f}" for v in r) for r in rows))
    (folder / "binary.pcd").write_bytes((header + "DATA binary\n").encode() + rows.tobytes())
    (folder / "cloud.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                      "property float z\nend_header\n" + "\n".join(" ".join(map(str, r)) for r in points))
    (folder / "truncated.pcd").write_bytes((header + "DATA binary\n").encode() + rows.tobytes()[:20])
    (folder / "compressed.pcd").write_text(header + "DATA binary_compressed\n")
    (folder / "no_z.pcd").write_text(header.replace("x y z", "x y w") + "DATA ascii\n1 2 3 4\n")
    (folder / "garbage.npy").write_bytes(b"not an array at all")
    (folder / "flat.npy").write_bytes(b"")
    np.save(folder / "pairs.npy", np.zeros((4, 2)))
    (folder / "garbage.ply").write_text("ply\nthis is not a header\n")
    (folder / "cloud.xyz").write_text("0 0 0\n")
    np.save(folder / "empty.npy", np.zeros((0, 3)))
    np.save(folder / "nan.npy", np.array([[0.5, 0.0, 0.1], [np.nan, 0.0, 0.0], [0.5, np.inf, 0.0]]))
    return folder


@pytest.mark.parametrize("name", ["cloud.npy", "ascii.pcd", "binary.pcd", "cloud.ply"])
def test_every_format_reads_the_same_points(files: Path, name: str) -> None:
    assert np.allclose(read_points(files / name), np.load(files / "cloud.npy"), atol=1e-6)


@pytest.mark.parametrize(("name", "problem"), [
    ("missing.npy", "file not found"),
    ("garbage.npy", "cannot be read as a .npy array"),
    ("flat.npy", "cannot be read as a .npy array"),
    ("pairs.npy", "expected an (N, 3) array of numbers, got shape (4, 2)"),
    ("garbage.ply", "cannot be read as a PLY file"),
    ("truncated.pcd", "PCD binary data holds 20 bytes, fewer than the 48 of its 3 points"),
    ("compressed.pcd", "PCD DATA binary_compressed is not read"),
    ("no_z.pcd", "PCD has no z field"),
    ("cloud.xyz", "unknown point-cloud format .xyz"),
])
def test_a_malformed_cloud_file_is_refused_naming_the_entry_file(files: Path, name: str, problem: str) -> None:
    with pytest.raises(ScenarioError) as error:
        scenario_from_dict(_scenario([{"type": "points", "file": name}]), files)
    assert error.value.field == "obstacles[0].file" and problem in error.value.problem


def test_a_cloud_file_too_large_is_refused_before_it_is_read(files: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("dynfab.geometry.cloud_files.MAX_CLOUD_BYTES", 10)
    with pytest.raises(CloudFileError, match="more than the 0 MB"):
        read_points(files / "cloud.npy")


def test_a_scenario_cloud_loads_drops_nan_rows_and_an_empty_one_is_no_obstacle(
        files: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cloud = scenario_from_dict(_scenario([{"type": "points", "file": "cloud.npy", "voxel": 0.005}]), files).obstacles
    assert len(cloud) == 1 and cloud[0].type == "points" and len(cloud[0].cloud.points) == 3
    nan = scenario_from_dict(_scenario([{"type": "points", "file": "nan.npy"}]), files).obstacles
    assert len(nan[0].cloud.points) == 1 and "nan.npy: 2 NaN or infinite points dropped" in capsys.readouterr().err
    assert scenario_from_dict(_scenario([{"type": "points", "file": "empty.npy"}]), files).obstacles == ()
    assert "empty.npy has no finite point: no obstacle" in capsys.readouterr().err


@pytest.mark.parametrize(("entry", "field"), [
    ({"type": "points", "file": "cloud.npy", "voxel": 0}, "obstacles[0].voxel"),
    ({"type": "points", "file": "cloud.npy", "max_points": 0}, "obstacles[0].max_points"),
    ({"type": "points", "file": "cloud.npy", "position": [0, 0, 0]}, "obstacles[0].position"),
])
def test_bad_cloud_keys_are_refused_naming_the_field(files: Path, entry: dict, field: str) -> None:
    with pytest.raises(ScenarioError) as error:
        scenario_from_dict(_scenario([entry]), files)
    assert error.value.field == field


@pytest.fixture(scope="module")
def feed_and_planner() -> tuple[PointCloudFeed, FabricPlanner]:
    robot = load_robot("panda")
    leaf = NearestSurfaceAvoidance(spheres=moving_spheres(robot))
    planner = FabricPlanner(robot, PlannerConfig(goals=(GoalConfig(link="panda_hand"),), leaves=(leaf,)))
    return PointCloudFeed(robot, leaf, planner.parameters.leaves[leaf.name]), planner


def test_the_feed_filters_the_robot_out_and_writes_the_nearest_points(
        feed_and_planner: tuple[PointCloudFeed, FabricPlanner]) -> None:
    feed, planner = feed_and_planner
    robot = planner.robot
    q = np.array(START)
    centres = np.asarray(robot.sphere_centers(q), dtype=float).reshape(-1, 3)
    on_robot = centres[::5] + np.array([0.0, 0.0, 0.01])
    wall = _wall(np.random.default_rng(5), 5000)
    update = feed.update_points(np.concatenate([wall, on_robot, [[np.nan, 0.0, 0.0]]]), q)
    assert update.dropped == 1 and update.on_robot >= len(on_robot)
    assert cKDTree(feed.cloud.points).query(on_robot)[0].min() > 0.01  # none of the robot left
    feed.write(q)
    views = planner.parameters.leaves["surfaces"]
    active = views["active"].astype(bool)
    assert active.any() and not active.all()
    points = views["points"].reshape(-1, 3)[active]
    truth, _ = cKDTree(wall).query(points)
    assert truth.max() < 2 * feed.cloud.lowering  # written points sit on the measured surface


def test_an_empty_update_leaves_every_sphere_inactive(feed_and_planner: tuple[PointCloudFeed, FabricPlanner]) -> None:
    feed, planner = feed_and_planner
    update = feed.update_points(np.zeros((0, 3)), np.array(START))
    feed.write(np.array(START))
    assert update.kept == 0 and not planner.parameters.leaves["surfaces"]["active"].any()
    with pytest.raises(ValueError, match=r"expected an \(N, 3\) array of numbers, got shape \(2, 2\)"):
        feed.update_points(np.zeros((2, 2)), None)


def test_the_point_cloud_example_reaches_its_goal_with_the_robot_filtered_out() -> None:
    example = Path(__file__).resolve().parent.parent / "examples" / "panda_point_cloud.py"
    run = subprocess.run([sys.executable, str(example)], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    found = re.search(r"(\d+) on the robot.*error ([\d.]+) m; closest sphere to the wall ([\d.]+) cm", run.stdout, re.S)
    assert found is not None, run.stdout
    assert int(found[1]) > 0 and float(found[2]) < 0.06 and float(found[3]) > 0.0


def test_the_compiled_checker_bounds_the_sphere_distance_to_the_cloud_from_below() -> None:
    robot = load_robot("panda")
    rng = np.random.default_rng(6)
    raw = _wall(rng)
    cloud = PointCloud.from_points(raw, voxel=0.01)
    checker = ConfigurationChecker(robot, [PlacedObstacle(cloud, Placement((0.0, 0.0, 0.0)))])
    assert checker.compiled
    qs = rng.uniform(robot.kinematics.lower, robot.kinematics.upper, (300, robot.dof))
    moving = list(moving_spheres(robot))   # c_obs is over the spheres a joint moves
    radii = np.asarray(robot.sphere_radii)[moving]
    tree = cKDTree(raw)
    exact = np.array([(tree.query(np.asarray(robot.sphere_centers(q), dtype=float).reshape(-1, 3)[moving])[0]
                       - radii).min() for q in qs])
    bound = checker.batch(qs)[:, 0]
    assert (bound <= exact + 1e-12).all()
    grid = cloud_distance_grid(cloud)
    mirrored = np.array([(grid.lower_bound(np.asarray(robot.sphere_centers(q), dtype=float).reshape(-1, 3)[moving])
                          - radii).min() for q in qs])
    assert np.allclose(bound, mirrored, atol=1e-9)  # the kernel computes what cloud_grid says
    near = (exact > 0) & (exact < 0.05)
    assert near.sum() > 5 and (exact - bound)[near].max() < 2 * math.sqrt(3) * 0.01 + 2 * cloud.lowering
