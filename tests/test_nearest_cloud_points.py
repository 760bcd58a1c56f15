"""The per-tick point-cloud writer (dynfab.perception.nearest_cloud_points): the same leaf
parameters as the general surface feed, on the VM and compiled, every sphere inactive for an
empty cloud, and each active sphere's index naming its nearest kept point."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from dynfab.fabric.c_backend import find_compiler
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.geometry.point_cloud import PointCloud
from dynfab.perception.nearest_cloud_points import NearestCloudPoints
from dynfab.perception.surfaces import SurfaceFeed
from dynfab.robots.builtin import load_robot

KEYS = ("points", "normals", "velocities", "active")


def _table_and_box(rng: np.random.Generator) -> np.ndarray:
    """Noisy points on a table top z = 0 and on the faces x = 0.45 and y = 0.15 of a box on it."""
    count = 20_000
    table = np.column_stack([rng.uniform(0.2, 0.9, count), rng.uniform(-0.5, 0.5, count), np.zeros(count)])
    front = np.column_stack([np.full(count, 0.45), rng.uniform(0.15, 0.45, count), rng.uniform(0.0, 0.4, count)])
    side = np.column_stack([rng.uniform(0.45, 0.65, count), np.full(count, 0.15), rng.uniform(0.0, 0.4, count)])
    return np.concatenate([table, front, side]) + rng.normal(0.0, 0.002, (3 * count, 3))


@pytest.fixture(scope="module")
def setting() -> tuple:
    robot = load_robot("panda")
    leaf = NearestSurfaceAvoidance(spheres=moving_spheres(robot))
    config = PlannerConfig(goals=(GoalConfig(link="panda_hand"),), leaves=(leaf,), backend="vm")
    planners = [FabricPlanner(robot, config) for _ in range(2)]
    return robot, leaf, planners[0].parameters.leaves[leaf.name], planners[1].parameters.leaves[leaf.name]


def _configurations(robot, count: int, rng: np.random.Generator) -> np.ndarray:
    low, high = robot.kinematics.lower, robot.kinematics.upper
    return rng.uniform(low, high, (count, robot.dof))


@pytest.mark.parametrize("backend", ["vm", "c"])
def test_it_writes_what_the_surface_feed_writes(setting: tuple, backend: str) -> None:
    robot, leaf, views, reference_views = setting
    if backend == "c" and find_compiler() is None:
        pytest.skip("no C compiler")
    rng = np.random.default_rng(1)
    cloud = PointCloud.from_points(_table_and_box(rng), voxel=0.01)
    writer = NearestCloudPoints(robot, leaf, views, backend)
    reference = SurfaceFeed(robot, leaf, reference_views)
    active_seen = 0
    for q in _configurations(robot, 60, rng):
        writer.write(q, cloud)
        reference.write(q, (), (cloud,))
        for key in KEYS:
            np.testing.assert_allclose(views[key], reference_views[key], rtol=0.0, atol=1e-12, err_msg=key)
        active_seen += int(views["active"].sum())
    assert active_seen > 100  # the configurations brought many spheres near the cloud


def test_an_empty_cloud_leaves_every_sphere_inactive_with_normal_up(setting: tuple) -> None:
    robot, leaf, views, _ = setting
    writer = NearestCloudPoints(robot, leaf, views, "vm")
    writer.write(np.zeros(robot.dof), PointCloud.from_points(_table_and_box(np.random.default_rng(2))))
    writer.write(np.zeros(robot.dof), PointCloud(np.zeros((0, 3)), 0.01))
    assert not views["active"].any() and not views["points"].any() and not views["velocities"].any()
    assert np.array_equal(views["normals"].reshape(-1, 3), np.tile([0.0, 0.0, 1.0], (len(leaf.spheres), 1)))


def test_each_active_sphere_indexes_its_nearest_kept_point(setting: tuple) -> None:
    robot, leaf, views, _ = setting
    rng = np.random.default_rng(3)
    cloud = PointCloud.from_points(_table_and_box(rng), voxel=0.01)
    writer = NearestCloudPoints(robot, leaf, views, "vm")
    q = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 2.0, 0.8])  # the hand low over the table
    writer.write(q, cloud)
    active = views["active"].astype(bool)
    assert active.any()
    centres = np.asarray(robot.sphere_centers(q), dtype=float).reshape(-1, 3)[list(leaf.spheres)]
    np.testing.assert_allclose(writer.centres, centres, atol=1e-12)
    gaps, truth = cKDTree(cloud.points).query(centres[active])
    chosen = cloud.points[writer.index[active]]
    np.testing.assert_allclose(np.linalg.norm(centres[active] - chosen, axis=1), gaps, atol=1e-12)
    assert (writer.index[active] == truth).mean() > 0.9  # the same point, up to ties between lattice points


def test_a_configuration_of_the_wrong_length_is_refused(setting: tuple) -> None:
    robot, leaf, views, _ = setting
    writer = NearestCloudPoints(robot, leaf, views, "vm")
    with pytest.raises(ValueError, match=r"q must have shape \(7,\), got \(6,\)"):
        writer.write(np.zeros(6), PointCloud(np.zeros((0, 3)), 0.01))
