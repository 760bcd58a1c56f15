"""A link's meshes against a point cloud's kept points (geometry/cloud_collision.py): the
signed distance equals brute force (points inside a link as deep as their distance to its
surface, also for a mesh whose vertices are not merged), its cheap bound is below it, a
touch at the cloud's edge is no hull-deep contact, and the sweep lowers it by the voxel's
half-diagonal in a run's metrics."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from dynfab.geometry.cloud_collision import winding_numbers
from dynfab.geometry.exact_collision import exact_distance, hull_distance, mesh_set, placement_matrix, shape_geometry
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Placement, quaternion_from_rpy
from dynfab.robots.mesh_sweep import PlacedShape

SIZE = np.array([0.06, 0.1, 0.2])
LINK = trimesh.creation.box(extents=SIZE)


def _plane_cloud() -> PointCloud:
    """A 1 m square of points every 5 mm at z = 0, noisy (σ = 2 mm), kept at 1 cm."""
    grid = np.linspace(-0.5, 0.5, 201)
    a, b = np.meshgrid(grid, grid)
    raw = np.column_stack([a.ravel(), b.ravel(), np.zeros(a.size)])
    return PointCloud.from_points(raw + np.random.default_rng(3).normal(0.0, 0.002, raw.shape), voxel=0.01)


def _pose(position: tuple[float, float, float], rpy: tuple[float, float, float]) -> np.ndarray:
    return placement_matrix(Placement(position, quaternion_from_rpy(rpy)))


def _brute_force(pose: np.ndarray, cloud: PointCloud) -> float:
    """min over the kept points of minus trimesh's signed distance (positive inside)."""
    local = (cloud.points - pose[:3, 3]) @ pose[:3, :3]
    return float(np.min(-trimesh.proximity.signed_distance(LINK, local)))


POSES = [((0.0, 0.0, 0.2), (0.0, 0.0, 0.0)), ((0.1, -0.05, 0.11), (0.3, 0.2, 0.1)),
         ((0.0, 0.0, 0.09), (0.0, 0.0, 0.0)), ((0.02, 0.03, 0.05), (0.4, -0.3, 0.2)),
         ((-0.1, 0.1, 0.0), (1.2, 0.4, -0.5))]


@pytest.mark.parametrize(("position", "rpy"), POSES)
def test_the_distance_to_a_cloud_is_the_signed_distance_to_its_points(position: tuple[float, float, float],
                                                                      rpy: tuple[float, float, float]) -> None:
    cloud = _plane_cloud()
    solid = shape_geometry(cloud)
    pose = _pose(position, rpy)
    expected = _brute_force(pose, cloud)
    for link in (mesh_set([LINK]), mesh_set([_unmerged(LINK)])):
        distance = exact_distance(link, pose, solid, np.eye(4))
        assert distance == pytest.approx(expected, abs=1.5e-4)  # the specks: 0.1 mm triangles
        assert hull_distance(link, pose, solid, np.eye(4)) <= distance + 1e-12


def test_deep_points_count_as_deep_as_they_are_inside_the_link() -> None:
    cloud = _plane_cloud()
    pose = _pose((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))  # the plane through the box's middle
    distance = exact_distance(mesh_set([LINK]), pose, shape_geometry(cloud), np.eye(4))
    assert distance < -0.02  # the kept points near the centre are ~3 cm from the nearest face
    assert distance == pytest.approx(_brute_force(pose, cloud), abs=1e-6)


def test_a_touch_at_the_edge_of_a_cloud_is_no_deeper_than_the_point_is_inside() -> None:
    """The tiny-triangle mesh read the convex hull of the whole cloud as the depth."""
    cloud = _plane_cloud()
    edge = cloud.points[np.argmax(cloud.points[:, 0])]  # the other points 1 cm or more back in x
    pose = _pose(tuple(edge + np.array([0.029, 0.0, 0.0])), (0.0, 0.0, 0.0))  # edge points 1 mm inside a face
    distance = exact_distance(mesh_set([LINK]), pose, shape_geometry(cloud), np.eye(4))
    assert distance == pytest.approx(-0.001, abs=1e-6)


def test_winding_numbers_tell_inside_from_outside() -> None:
    points = np.array([[0.0, 0.0, 0.0], [0.029, 0.049, 0.099], [0.031, 0.0, 0.0], [0.0, 0.0, 0.3]])
    assert np.allclose(np.abs(winding_numbers(LINK, points)), [1.0, 1.0, 0.0, 0.0], atol=1e-9)


def test_the_lowering_of_a_placed_shape_is_checked() -> None:
    with pytest.raises(ValueError, match="obstacles\\[0\\]: lowering"):
        PlacedShape("obstacles[0]", _plane_cloud(), (Placement((0.0, 0.0, 0.0)),), lowering=-0.01)


def _unmerged(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The mesh with three vertices of its own per face: not watertight until merged."""
    split = trimesh.Trimesh(mesh.triangles.reshape(-1, 3), np.arange(3 * len(mesh.faces)).reshape(-1, 3),
                            process=False)
    assert not split.is_watertight
    return split


def test_a_run_is_measured_less_the_voxel_and_its_start_only_refused_on_a_touch(tmp_path: Path) -> None:
    from dynfab.robots.builtin import load_robot
    from dynfab.scenario.exact_metrics import mesh_model_for, obstacle_shapes
    from dynfab.scenario.schema import ScenarioError, scenario_from_dict
    from dynfab.scenario.start_state import check_start_collisions

    robot = load_robot("panda")
    model = mesh_model_for(robot)
    q = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
    hand = model.link_poses(q[None])[0, model.links.index("panda_hand_body")]
    origin = Placement((0.0, 0.0, 0.0))
    offsets = np.stack(np.meshgrid(*[np.arange(-0.04, 0.05, 0.01)] * 3), axis=-1).reshape(-1, 3)
    candidates = (np.floor((hand[:3, 3] + 0.1 * hand[:3, 2]) / 0.01) + 0.5) * 0.01 + offsets  # voxel centres
    gaps = [sweep_clearance(model, q, [PlacedShape("dot", PointCloud(c[None]), (origin,))]) for c in candidates]
    dot = candidates[int(np.argmin(np.abs(np.array(gaps) - 0.004)))]  # 1-7 mm from the meshes
    np.save(tmp_path / "dot.npy", dot[None])
    mapping = {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 1.0,
               "initial_state": {"q": q.tolist()},
               "goal": [{"type": "position", "link": "panda_hand", "position": [0.45, 0.0, 0.4]}],
               "obstacles": [{"type": "points", "file": "dot.npy", "voxel": 0.01}]}
    scenario = scenario_from_dict(mapping, tmp_path)
    cloud = scenario.obstacles[0].shape
    assert np.allclose(cloud.points, dot[None])
    centres = np.zeros((1, 1, 3))  # a cloud's frame is the world's
    plain, lowered = obstacle_shapes(scenario.obstacles, centres), obstacle_shapes(scenario.obstacles, centres, True)
    gap = sweep_clearance(model, q, plain)
    assert 0.0 < gap < cloud.lowering  # the voxel's half-diagonal reaches the hand
    assert sweep_clearance(model, q, lowered) == pytest.approx(gap - cloud.lowering, abs=1e-12)
    check_start_collisions(q, robot, model, plain)  # not refused: no kept point is touched
    with pytest.raises(ScenarioError, match="initial_state.q"):
        check_start_collisions(q, robot, model, lowered)


def sweep_clearance(model, q: np.ndarray, shapes) -> float:  # type: ignore[no-untyped-def]
    from dynfab.robots.mesh_sweep import sweep_meshes

    clearance = sweep_meshes(model, q[None], shapes).clearance
    assert clearance is not None
    return clearance
