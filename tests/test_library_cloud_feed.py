"""The library's per-tick cloud feed (PointCloudFeed, NearestCloudPoints) with the scenario
feed's representation: a braking leaf's reach grown by the spheres' stopping distances at the
given joint velocities, and a far-side slot per sphere (dynfab.perception.far_side_writer)."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.fabric.c_backend import find_compiler
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.perception.camera_feed import CameraFeed
from dynfab.perception.camera_spec import CameraSpec
from dynfab.perception.depth_camera import DepthCamera
from dynfab.perception.point_clouds import PointCloudFeed
from dynfab.perception.surfaces import SurfaceFeed
from dynfab.robots.builtin import load_robot

KEYS = ("points", "normals", "velocities", "active")
#: the guided fabric's leaf: range 0.1 m, braking at 4 m/s² (dynfab.scenario.guided_controller)
BRAKING = Barrier(geometry_gain=5.0, energy_gain=0.02, horizon=0.1, offset=0.005, braking=4.0)


def _cage(rng: np.random.Generator) -> np.ndarray:
    """Noisy points on a floor z = 0, a back wall x = 0.75 and a side wall y = 0.35: corners
    where a sphere's nearest point and its far-side point lie on different faces."""
    count = 15_000
    floor = np.column_stack([rng.uniform(0.2, 0.75, count), rng.uniform(-0.5, 0.35, count), np.zeros(count)])
    back = np.column_stack([np.full(count, 0.75), rng.uniform(-0.5, 0.35, count), rng.uniform(0.0, 0.8, count)])
    side = np.column_stack([rng.uniform(0.2, 0.75, count), np.full(count, 0.35), rng.uniform(0.0, 0.8, count)])
    return np.concatenate([floor, back, side]) + rng.normal(0.0, 0.002, (3 * count, 3))


@pytest.fixture(scope="module")
def panda_far_side() -> tuple:
    robot = load_robot("panda")
    leaf = NearestSurfaceAvoidance(spheres=moving_spheres(robot), barrier=BRAKING, far_side=True)
    config = PlannerConfig(goals=(GoalConfig(link="panda_hand"),), leaves=(leaf,), backend="vm")
    planners = [FabricPlanner(robot, config) for _ in range(2)]
    return robot, leaf, planners[0].parameters.leaves[leaf.name], planners[1].parameters.leaves[leaf.name]


@pytest.mark.parametrize("backend", ["vm", "c"])
def test_the_library_feed_writes_what_the_scenario_feed_writes_far_side_and_reach_included(
        panda_far_side: tuple, backend: str) -> None:
    robot, leaf, views, reference_views = panda_far_side
    if backend == "c" and find_compiler() is None:
        pytest.skip("no C compiler")
    rng = np.random.default_rng(4)
    feed = PointCloudFeed(robot, leaf, views, backend=backend)
    feed.update_points(_cage(rng), None)
    reference = SurfaceFeed(robot, leaf, reference_views)
    count = len(leaf.spheres)
    far_seen = grown_seen = 0
    low, high = robot.kinematics.lower, robot.kinematics.upper
    for q in rng.uniform(low, high, (80, robot.dof)):
        qdot = rng.uniform(-2.0, 2.0, robot.dof)
        feed.write(q, qdot)
        reference.write(q, (), (feed.cloud,), qdot=qdot)
        for key in KEYS:
            np.testing.assert_allclose(views[key], reference_views[key], rtol=0.0, atol=1e-12, err_msg=key)
        far_seen += int(views["active"][count:].sum())
        feed.write(q)   # at rest: the static reach
        grown_seen += int(reference_views["active"][:count].sum() - views["active"][:count].sum())
    assert far_seen > 20     # second sides were found and written
    assert grown_seen > 20   # the speeds reached points the static reach does not


def test_a_sphere_in_a_corner_gets_the_other_wall_in_its_far_side_slot(panda_far_side: tuple) -> None:
    robot, leaf, views, _ = panda_far_side
    q = np.array([0.0, 0.3, 0.0, -2.0, 0.0, 2.3, 0.8])
    hand = int(np.argmax(np.asarray(robot.sphere_centers(q))[list(leaf.spheres), 0]))   # the sphere farthest forward
    centre = np.asarray(robot.sphere_centers(q))[leaf.spheres[hand]]
    x, z = np.meshgrid(np.arange(-0.3, 0.3001, 0.005), np.arange(-0.3, 0.3001, 0.005))
    front = np.column_stack([np.full(x.size, 0.10), x.ravel(), z.ravel()])   # 10 cm ahead of the sphere
    below = np.column_stack([x.ravel(), z.ravel(), np.full(x.size, -0.115)])  # 11.5 cm below it
    feed = PointCloudFeed(robot, leaf, views, backend="vm")
    feed.update_points(np.concatenate([front, below]) + centre, None)
    feed.write(q)
    count = len(leaf.spheres)
    normals = views["normals"].reshape(-1, 3)
    assert views["active"][hand] == 1.0 and views["active"][count + hand] == 1.0
    assert normals[hand] @ (-1.0, 0.0, 0.0) > 0.95        # the nearer face, ahead
    assert normals[count + hand] @ (0.0, 0.0, 1.0) > 0.9   # the other one, below
    far_point = views["points"].reshape(-1, 3)[count + hand]
    assert far_point[2] - centre[2] == pytest.approx(-0.115, abs=feed.cloud.lowering + 0.006)


def test_a_far_side_slot_stays_empty_above_a_plain_floor(panda_far_side: tuple) -> None:
    robot, leaf, views, _ = panda_far_side
    q = np.array([0.0, 0.3, 0.0, -2.0, 0.0, 2.3, 0.8])
    x, y = np.meshgrid(np.arange(-0.2, 0.9, 0.005), np.arange(-0.6, 0.6, 0.005))
    spheres = list(leaf.spheres)
    lowest = float(np.min(np.asarray(robot.sphere_centers(q))[spheres, 2] - np.asarray(robot.sphere_radii)[spheres]))
    feed = PointCloudFeed(robot, leaf, views, backend="vm")
    feed.update_points(np.column_stack([x.ravel(), y.ravel(), np.full(x.size, lowest - 0.05)]), None)
    feed.write(q)
    count = len(leaf.spheres)
    assert views["active"][:count].sum() > 0 and views["active"][count:].sum() == 0


def test_a_fast_sphere_sees_a_point_beyond_its_static_reach_a_resting_one_does_not(panda_far_side: tuple) -> None:
    robot, leaf, views, _ = panda_far_side
    feed = PointCloudFeed(robot, leaf, views, backend="vm")
    q = np.array([0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.8])
    qdot = np.array([2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])   # the whole arm turning about the base
    tip = int(np.argmax(np.linalg.norm(np.asarray(robot.sphere_centers(q))[list(leaf.spheres), :2], axis=1)))
    centre = np.asarray(robot.sphere_centers(q))[leaf.spheres[tip]]
    static = feed.nearest.reach[tip]
    speed = 2.0 * float(np.linalg.norm(centre[:2]))
    assert static + speed**2 / 8.0 > static + 0.05   # the stop takes more than 5 cm
    outward = np.array([centre[0], centre[1], 0.0]) / np.linalg.norm(centre[:2])
    feed.update_points((centre + (static + 0.04 + feed.cloud.lowering) * outward)[None], None)
    feed.write(q)
    assert views["active"][tip] == 0.0
    feed.write(q, qdot)
    assert views["active"][tip] == 1.0


def test_the_feed_refuses_a_qdot_of_the_wrong_length(panda_far_side: tuple) -> None:
    robot, leaf, views, _ = panda_far_side
    feed = PointCloudFeed(robot, leaf, views, backend="vm")
    with pytest.raises(ValueError, match="qdot"):
        feed.write(np.zeros(robot.dof), np.zeros(robot.dof + 1))


def test_a_cameras_feed_refuses_a_far_side_leaf(panda_far_side: tuple) -> None:
    robot, leaf, views, _ = panda_far_side
    feed = CameraFeed(robot, DepthCamera(CameraSpec(position=(1.5, 0.0, 1.0), look_at=(0.0, 0.0, 0.3)), robot))
    with pytest.raises(ValueError, match="far_side"):
        feed.attach(leaf, views)
