"""A braking nearest-point leaf against a point cloud: the feed reaches as far as each sphere's
stopping distance (:meth:`SurfaceFeed.braking_reach`), and every sphere gets a far-side point
(:mod:`dynfab.geometry.cloud_far_side`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import dynfab
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.goal import GoalAttractor
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance
from dynfab.geometry.cloud_far_side import FAR_SIDE_ANGLE, SphereMotion, far_side_points, segment_distances
from dynfab.geometry.point_cloud import PointCloud
from dynfab.perception.surfaces import SurfaceFeed
from dynfab.robots.robot import CollisionSphere

ARM = Path(__file__).resolve().parents[1] / "examples" / "custom_urdf" / "arm.urdf"
RADII = np.array([0.06, 0.06, 0.05])
#: the guided fabric's leaf: range 0.1 m, braking at 4 m/s² (dynfab.scenario.guided_controller)
BRAKING = Barrier(geometry_gain=5.0, energy_gain=0.02, horizon=0.1, offset=0.005, braking=4.0)
#: a wall of the plane y = 0.6, x in [0.3, 1.5], z in [-0.1, 0.3], sampled every 5 mm
WALL_LOW, WALL_HIGH = np.array([0.3, 0.6, -0.1]), np.array([1.5, 0.6, 0.3])


@pytest.fixture(scope="module")
def arm() -> dynfab.Robot:
    spheres = [CollisionSphere("link1", (0.5, 0.0, 0.0), RADII[0]), CollisionSphere("link2", (0.4, 0.0, 0.0), RADII[1]),
               CollisionSphere("tool", (0.0, 0.0, 0.0), RADII[2])]
    return dynfab.robot_from_urdf(ARM, goal_link="tool", spheres=spheres)


def _wall() -> PointCloud:
    x, z = np.meshgrid(np.arange(0.3, 1.5001, 0.005), np.arange(-0.1, 0.3001, 0.005))
    return PointCloud.from_points(np.column_stack([x.ravel(), np.full(x.size, 0.6), z.ravel()]), 0.01)


def _wall_clearance(centres: np.ndarray) -> float:
    """The least distance [m] of the arm's spheres from the true wall (a rectangle)."""
    outside = np.maximum(np.maximum(WALL_LOW - centres, centres - WALL_HIGH), 0.0)
    return float(np.min(np.linalg.norm(outside, axis=1) - RADII))


def _swing_into_the_wall(arm: dynfab.Robot, with_speeds: bool) -> float:
    """The arm's tool pulled across the wall from the arm's stretched pose; its least
    clearance from the true wall over 3 s [m]."""
    leaf = NearestSurfaceAvoidance(spheres=(0, 1, 2), barrier=BRAKING)
    planner = dynfab.FabricPlanner(arm, dynfab.PlannerConfig(
        goals=(dynfab.GoalConfig(link="tool", attractor=GoalAttractor(gain=5.0)),), leaves=(leaf,), backend="vm"))
    planner.parameters.goal_position[0][:] = [0.0, 1.2, 0.1]
    feed = SurfaceFeed(arm, leaf, planner.parameters.leaves["surfaces"])
    wall = _wall()
    q, qdot = np.zeros(3), np.zeros(3)
    worst = math.inf
    for _ in range(300):
        feed.write(q, [], [wall], qdot=qdot if with_speeds else None)
        q, qdot = planner.step(q, qdot)
        assert np.isfinite(q).all() and np.isfinite(qdot).all()
        worst = min(worst, _wall_clearance(np.asarray(arm.sphere_centers(q))))
    return worst


def test_a_braking_leaf_fed_the_spheres_speeds_keeps_a_fast_arm_off_the_true_wall(arm: dynfab.Robot) -> None:
    # without the speeds (the feed of e94d6d6) the leaf meets the wall within its 10 cm range,
    # too late to stop at 4 m/s², and the arm goes into it; with them it brakes in time
    assert _swing_into_the_wall(arm, with_speeds=False) < -0.005
    assert _swing_into_the_wall(arm, with_speeds=True) > 0.005


def test_the_braking_reach_grows_by_each_spheres_stopping_distance(arm: dynfab.Robot) -> None:
    leaf = NearestSurfaceAvoidance(spheres=(0, 1, 2), barrier=BRAKING)
    planner = dynfab.FabricPlanner(arm, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="tool"),), leaves=(leaf,),
                                                             backend="vm"))
    views = planner.parameters.leaves["surfaces"]
    feed = SurfaceFeed(arm, leaf, views)
    q, qdot = np.array([0.9, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])   # the whole arm turning at 1 rad/s
    speeds = np.array([0.5, 0.9, 1.2])   # the spheres' distances from the first joint's axis [m/s]
    velocities = feed.sphere_velocities(q, qdot)
    np.testing.assert_allclose(np.linalg.norm(velocities, axis=1), speeds, rtol=1e-9)
    np.testing.assert_allclose(feed.braking_reach(velocities), feed.reach + speeds**2 / 8.0, rtol=1e-9)
    assert feed.sphere_velocities(q, None) is None
    np.testing.assert_allclose(feed.braking_reach(None), feed.reach)
    # the tool 0.26 m from the wall (a clearance of 0.2 m, twice the range): seen only moving
    tool = np.asarray(arm.sphere_centers(q))[2]
    wall = PointCloud.from_points(np.array([[tool[0] + 0.26, tool[1], tool[2]]]), 0.01)
    feed.write(q, [], [wall])
    assert views["active"][2] == 0.0
    feed.write(q, [], [wall], qdot=np.array([0.0, 0.0, 3.0]))   # 0.9 m/s: 0.1 m to stop
    assert views["active"][2] == 1.0
    assert views["active"][0] == 0.0   # the others do not move


def _floor_and_wall(wall_y: float) -> PointCloud:
    x, y = np.meshgrid(np.arange(-0.5, 0.5001, 0.005), np.arange(-0.5, wall_y, 0.005))
    floor = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    x, z = np.meshgrid(np.arange(-0.5, 0.5001, 0.005), np.arange(0.0, 0.5001, 0.005))
    wall = np.column_stack([x.ravel(), np.full(x.size, wall_y), z.ravel()])
    return PointCloud.from_points(np.concatenate([floor, wall]), 0.01)


def _first(cloud: PointCloud, centres: np.ndarray):
    found = cloud.nearest(centres)
    return found.points, found.normals, found.found


@pytest.mark.parametrize("wall", [0.11, 0.16])
def test_a_sphere_near_a_floor_gets_the_wall_beside_it_as_its_far_side_point(wall: float) -> None:
    cloud = _floor_and_wall(wall)
    centre = np.array([[0.0, 0.0, 0.1]])   # 0.1 m above the floor
    points, normals, found = _first(cloud, centre)
    assert normals[0] @ (0.0, 0.0, 1.0) > 0.99   # the floor is the nearer
    far = far_side_points(cloud, centre, points, normals, found, np.array([0.3]))
    assert far.found[0]
    assert far.points[0, 1] == pytest.approx(wall, abs=cloud.lowering + 0.005)   # on the wall
    assert far.normals[0] @ normals[0] < math.cos(FAR_SIDE_ANGLE)
    np.testing.assert_allclose(np.linalg.norm(centre[0] - far.points[0]), far.distances[0], atol=1e-12)
    on_wall = cloud.points[np.abs(cloud.points[:, 1] - wall) < 0.01]
    nearest_on_wall = float(np.min(np.linalg.norm(on_wall - centre[0], axis=1))) - cloud.lowering
    assert far.distances[0] >= nearest_on_wall - 1e-12
    if wall < 1.25 * 0.1:   # found by the short shift: nearly the wall's nearest point (a shift of 2.5 cm)
        assert far.normals[0] @ (0.0, -1.0, 0.0) > 0.97
        assert far.distances[0] <= nearest_on_wall + 0.003
    else:   # by the mirror, 0.1 m above the sphere: no farther than the wall's point level with it
        assert far.distances[0] <= math.hypot(nearest_on_wall + cloud.lowering, 0.1)


def test_a_sphere_above_a_plain_floor_has_no_far_side_point() -> None:
    x, y = np.meshgrid(np.arange(-0.5, 0.5001, 0.005), np.arange(-0.5, 0.5001, 0.005))
    cloud = PointCloud.from_points(np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)]), 0.01)
    centres = np.array([[0.0, 0.0, 0.1], [0.2, -0.1, 0.05]])
    far = far_side_points(cloud, centres, *_first(cloud, centres), np.array([0.3, 0.3]))
    assert not far.found.any()


def test_a_far_wall_beyond_the_reach_is_not_written() -> None:
    cloud = _floor_and_wall(0.13)
    centre = np.array([[0.0, 0.0, 0.1]])
    far = far_side_points(cloud, centre, *_first(cloud, centre), np.array([0.05]))
    assert not far.found[0]


def _slot_between_walls_over_a_floor(other_wall: float) -> PointCloud:
    """Walls y = 0.05 and y = ``other_wall`` (x, z in [-0.3, 0.3] x [0, 0.4]) over the floor z = 0,
    sampled every 5 mm."""
    a, b = np.meshgrid(np.arange(-0.3, 0.3001, 0.005), np.arange(0.0, 0.4001, 0.005))
    walls = [np.column_stack([a.ravel(), np.full(a.size, y), b.ravel()]) for y in (0.05, other_wall)]
    x, y = np.meshgrid(np.arange(-0.3, 0.3001, 0.005), np.arange(other_wall, 0.0501, 0.005))
    return PointCloud.from_points(np.concatenate([*walls, np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])]),
                                  0.01)


@pytest.mark.parametrize("other_wall", [-0.06, -0.3])
def test_a_sphere_falling_between_two_walls_gets_the_floor_ahead_as_its_far_side_point(other_wall: float) -> None:
    # table_pick/0089 as a cloud (--seed 8): a hand descending between two objects saw only their
    # sides and met the table top when it was the nearest point, too fast to stop
    cloud = _slot_between_walls_over_a_floor(other_wall)
    centre = np.array([[0.0, 0.01, 0.15]])   # 4 cm from the wall y = 0.05, 15 cm above the floor
    points, normals, found = _first(cloud, centre)
    assert normals[0] @ (0.0, -1.0, 0.0) > 0.97   # the wall (voxel centres: not quite square)
    reach = np.array([0.35])
    at_rest = far_side_points(cloud, centre, points, normals, found, reach)
    if other_wall > -0.1:   # at rest the other wall is the far side; far away, there is none
        assert at_rest.found[0] and at_rest.normals[0] @ (0.0, 1.0, 0.0) > 0.97
    else:
        assert not at_rest.found[0]
    falling = np.array([[0.0, 0.0, -1.2]])   # stops 18 cm lower at 4 m/s²: under the floor
    moving = far_side_points(cloud, centre, points, normals, found, reach,
                             SphereMotion(falling, np.array([0.02]), BRAKING.braking))
    assert moving.found[0]
    assert moving.normals[0] @ (0.0, 0.0, 1.0) > 0.97   # the floor
    assert moving.distances[0] == pytest.approx(0.15 - cloud.lowering, abs=0.006)
    # rising along the wall: the wall's point ahead is no threat, the rest's choice stands
    rising = far_side_points(cloud, centre, points, normals, found, reach,
                             SphereMotion(-falling, np.array([0.02]), BRAKING.braking))
    assert rising.found[0] == at_rest.found[0]
    np.testing.assert_array_equal(rising.points[rising.found], at_rest.points[at_rest.found])


def test_the_scenario_leaf_of_a_cloud_has_a_far_side_slot_per_sphere_and_the_cloud_writer_writes_it_too(
        arm: dynfab.Robot) -> None:
    from dynfab.perception.nearest_cloud_points import NearestCloudPoints

    leaf = NearestSurfaceAvoidance(spheres=(0, 1, 2), barrier=BRAKING, far_side=True)
    assert leaf.slots == (0, 1, 2, 0, 1, 2)
    assert leaf.parameter_sizes()["active"] == 6
    planner = dynfab.FabricPlanner(arm, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="tool"),), leaves=(leaf,),
                                                             backend="vm"))
    views = planner.parameters.leaves["surfaces"]
    q = np.array([0.5, 0.0, 0.0])
    tool = np.asarray(arm.sphere_centers(q))[2]
    corner = _floor_and_wall(0.11).points + (tool - (0.0, 0.0, 0.1))   # the floor 0.1 m below the tool
    SurfaceFeed(arm, leaf, views).write(q, [], [PointCloud(corner, 0.01)])
    active, normals = views["active"], views["normals"].reshape(-1, 3)
    assert active[2] == 1.0 and active[5] == 1.0
    assert normals[2] @ (0.0, 0.0, 1.0) > 0.98 and normals[5] @ (0.0, -1.0, 0.0) > 0.95
    written = {key: views[key].copy() for key in ("points", "normals", "velocities", "active")}
    for key in written:
        views[key][:] = 0.0
    NearestCloudPoints(arm, leaf, views, backend="vm").write(q, PointCloud(corner, 0.01))
    for key, expected in written.items():
        np.testing.assert_allclose(views[key], expected, rtol=0.0, atol=1e-12, err_msg=key)


def test_segment_distances_match_a_dense_sampling_of_each_segment() -> None:
    rng = np.random.default_rng(11)
    starts, ends, points = rng.normal(size=(3, 50, 3))
    ends[0] = starts[0]   # a segment of length 0: the distance to its point
    t = np.linspace(0.0, 1.0, 20001)
    sampled = starts[:, None, :] + t[None, :, None] * (ends - starts)[:, None, :]
    expected = np.min(np.linalg.norm(sampled - points[:, None, :], axis=2), axis=1)
    np.testing.assert_allclose(segment_distances(starts, ends, points), expected, atol=1e-6)
