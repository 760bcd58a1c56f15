"""Robot mesh models (robots/mesh_collision.py) and run sweeps (robots/mesh_sweep.py)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from robot_files import arm_urdf, folded_configuration

from dynfab.geometry.exact_collision import exact_distance, placement_matrix, shape_geometry
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Box, Placement, Plane, Sphere, quaternion_from_rpy
from dynfab.robots import Kinematics, load_urdf, parse_urdf
from dynfab.robots.mesh_collision import adjacent_links, mesh_collision_model
from dynfab.robots.mesh_sweep import PlacedShape, clearance_per_sample, sweep_meshes


def _box_link(name: str, size: float = 0.1, z: float = 0.0) -> str:
    return (f"<link name='{name}'><collision><origin xyz='0 0 {z}'/><geometry><box size='{size} {size} {size}'/>"
            f"</geometry></collision></link>")


def _joint(name: str, kind: str, parent: str, child: str, xyz: str) -> str:
    limit = "<limit lower='-3' upper='3' effort='1' velocity='1'/>" if kind != "fixed" else ""
    return (f"<joint name='{name}' type='{kind}'><parent link='{parent}'/><child link='{child}'/>"
            f"<origin xyz='{xyz}'/><axis xyz='0 1 0'/>{limit}</joint>")


#: base =fixed= plate -rev- a -rev- ghost (no geometry) -rev- b -rev- c, 0.3 m apart along z;
#: d hangs from c down to b and overlaps b by 0.01 m at the default configuration.
CHAIN = ("<robot name='chain'>" + _box_link("base") + _box_link("plate", z=0.1) + _box_link("a") + "<link name='ghost'/>"
         + _box_link("b") + _box_link("c") + _box_link("d", size=0.32)
         + _joint("weld", "fixed", "base", "plate", "0 0 0.1") + _joint("j1", "revolute", "plate", "a", "0 0 0.3")
         + _joint("j2", "revolute", "a", "ghost", "0 0 0.3") + _joint("j3", "revolute", "ghost", "b", "0 0 0.0")
         + _joint("j4", "revolute", "b", "c", "0 0 0.3") + _joint("j5", "revolute", "c", "d", "0 0 -0.1")
         + "</robot>")


def test_adjacency_welds_fixed_joints_and_skips_links_without_geometry() -> None:
    kinematics = Kinematics(parse_urdf(CHAIN))
    adjacent = adjacent_links(kinematics, {"base", "plate", "a", "b", "c", "d"})
    expected = {("base", "plate"), ("base", "a"), ("plate", "a"), ("a", "b"), ("b", "c"), ("c", "d")}
    named = {tuple(sorted(pair)) for pair in adjacent if "ghost" not in pair}
    assert named == {tuple(sorted(pair)) for pair in expected}


def test_checked_pairs_leave_out_adjacent_and_touching_links() -> None:
    kinematics = Kinematics(parse_urdf(CHAIN))
    model = mesh_collision_model(kinematics, np.zeros(kinematics.dof))
    assert model is not None and model.links == ("base", "plate", "a", "b", "c", "d")
    pairs = {(model.links[i], model.links[j]) for i, j in model.pairs}
    # b-d: not adjacent but touching at the default configuration, so never checked
    assert pairs == {("base", "b"), ("base", "c"), ("base", "d"), ("plate", "b"), ("plate", "c"),
                     ("plate", "d"), ("a", "c"), ("a", "d")}
    bent = mesh_collision_model(kinematics, np.array([0.0, 0.0, 0.0, 1.5, 0.0]))  # c turned away
    assert bent is not None and ("b", "d") in {(bent.links[i], bent.links[j]) for i, j in bent.pairs}


def test_a_robot_without_collision_geometry_has_no_mesh_model() -> None:
    kinematics = Kinematics(parse_urdf("<robot name='r'><link name='a'/><link name='b'/>"
                                       + _joint("j", "revolute", "a", "b", "0 0 1") + "</robot>"))
    assert mesh_collision_model(kinematics, np.zeros(1)) is None


@pytest.fixture(scope="module")
def ur5():  # type: ignore[no-untyped-def]
    kinematics = Kinematics(load_urdf(arm_urdf("ur5")))
    model = mesh_collision_model(kinematics, np.zeros(kinematics.dof))
    assert model is not None
    return model


def test_link_poses_are_the_kinematics_transforms(ur5) -> None:  # type: ignore[no-untyped-def]
    qs = np.random.default_rng(0).uniform(-3.0, 3.0, (4, 6))
    poses = ur5.link_poses(qs)
    assert poses.shape == (4, len(ur5.links), 4, 4)
    for k, q in enumerate(qs):
        for i, link in enumerate(ur5.links):
            np.testing.assert_allclose(poses[k, i], np.array(ur5.kinematics.transform(q, link)), atol=1e-12)


def _brute_force(model, qs, obstacles):  # type: ignore[no-untyped-def]
    """Every (sample, link, obstacle) and (sample, pair) distance, no bounds."""
    poses = model.link_poses(qs)
    obstacle = np.full((len(qs), len(model.links), len(obstacles)), np.inf)
    for t, (i, o) in itertools.product(range(len(qs)), itertools.product(range(len(model.links)),
                                                                            range(len(obstacles)))):
        placement = obstacles[o].placements[t if len(obstacles[o].placements) > 1 else 0]
        obstacle[t, i, o] = exact_distance(model.meshes[i], poses[t, i], shape_geometry(obstacles[o].shape),
                                           placement_matrix(placement))
    pairs = np.array([[exact_distance(model.meshes[i], poses[t, i], model.meshes[j], poses[t, j])
                       for i, j in model.pairs] for t in range(len(qs))])
    return obstacle, pairs


def test_sweep_minima_and_contacts_are_those_of_brute_force(ur5) -> None:  # type: ignore[no-untyped-def]
    start, end = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0]), np.array([2.0, -0.6, 2.6, -2.5, 0.4, 1.0])
    qs = start + np.linspace(0.0, 1.0, 40)[:, None] * (end - start)
    angles = np.linspace(0.0, 2.0, 40)
    obstacles = [
        PlacedShape("box", Box((0.1, 0.3, 0.2)), (Placement((0.1, 0.35, 0.45), quaternion_from_rpy((0.2, 0.0, 0.5))),)),
        PlacedShape("ball", Sphere(0.06), tuple(Placement((0.4 * np.cos(a), 0.4 * np.sin(a), 0.5)) for a in angles)),
        PlacedShape("floor", Plane(), (Placement((0.0, 0.0, 0.02)),)),
    ]
    sweep = sweep_meshes(ur5, qs, obstacles)
    obstacle, pairs = _brute_force(ur5, qs, obstacles)
    assert sweep.clearance == pytest.approx(obstacle.min(), abs=1e-12)
    assert sweep.min_self_distance == pytest.approx(pairs.min(), abs=1e-12)
    found = {(c.first, c.second, c.samples) for c in sweep.obstacle_contacts}
    expected = {(ur5.links[i], obstacles[o].name, tuple(np.flatnonzero(obstacle[:, i, o] <= 0.0)))
                for i, o in itertools.product(range(len(ur5.links)), range(3)) if (obstacle[:, i, o] <= 0.0).any()}
    assert found == expected and len(found) >= 2  # the run does hit something


def test_per_sample_clearance_is_brute_forces_and_a_cap_bounds_it(ur5) -> None:  # type: ignore[no-untyped-def]
    start, end = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0]), np.array([2.0, -0.6, 2.6, -2.5, 0.4, 1.0])
    qs = start + np.linspace(0.0, 1.0, 30)[:, None] * (end - start)
    obstacles = [
        PlacedShape("box", Box((0.1, 0.3, 0.2)), (Placement((0.1, 0.35, 0.45), quaternion_from_rpy((0.2, 0.0, 0.5))),)),
        PlacedShape("floor", Plane(), (Placement((0.0, 0.0, 0.02)),)),
    ]
    exact = _brute_force(ur5, qs, obstacles)[0].min(axis=(1, 2))
    np.testing.assert_allclose(clearance_per_sample(ur5, qs, obstacles), exact, atol=1e-12)
    cap = float(np.median(exact))   # half the samples farther
    np.testing.assert_allclose(clearance_per_sample(ur5, qs, obstacles, cap=cap), np.minimum(exact, cap), atol=1e-12)


def test_an_arm_folded_into_itself_is_a_self_collision(ur5) -> None:  # type: ignore[no-untyped-def]
    q, depths = folded_configuration(ur5, seed=7)
    sweep = sweep_meshes(ur5, np.vstack([np.zeros(6), q]), [])
    assert sweep.clearance is None
    assert sweep.min_self_distance == pytest.approx(min(depths), abs=1e-12)
    deepest = ur5.pairs[int(np.argmin(depths))]
    contact = next(c for c in sweep.self_contacts if (c.first, c.second) == tuple(ur5.links[k] for k in deepest))
    assert contact.samples == (1,) and contact.depth == pytest.approx(min(depths))


def test_placements_must_cover_the_run(ur5) -> None:  # type: ignore[no-untyped-def]
    ball = PlacedShape("obstacles[0]", Sphere(0.1), (Placement((1, 0, 0)), Placement((1, 0, 0))))
    with pytest.raises(ValueError, match=r"obstacles\[0\]: 2 placements for a run of 3 samples"):
        sweep_meshes(ur5, np.zeros((3, 6)), [ball])


def test_a_cloud_is_swept_to_its_exact_minimum_less_its_lowering(ur5) -> None:  # type: ignore[no-untyped-def]
    start, end = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0]), np.array([2.0, -0.6, 2.6, -2.5, 0.4, 1.0])
    qs = start + np.linspace(0.0, 1.0, 30)[:, None] * (end - start)
    rng = np.random.default_rng(5)
    wall = np.column_stack([np.full(4000, 0.3), rng.uniform(-0.6, 0.6, 4000), rng.uniform(0.0, 0.8, 4000)])
    cloud = PointCloud.from_points(wall, voxel=0.01)
    placement = Placement((0.0, 0.05, 0.0), quaternion_from_rpy((0.0, 0.0, 0.4)))
    sweep = sweep_meshes(ur5, qs, [PlacedShape("wall", cloud, (placement,), lowering=cloud.lowering)])
    poses, geometry, pose = ur5.link_poses(qs), shape_geometry(cloud), placement_matrix(placement)
    exact = np.array([[exact_distance(ur5.meshes[i], poses[t, i], geometry, pose) for i in range(len(ur5.links))]
                      for t in range(len(qs))]) - cloud.lowering
    assert sweep.clearance == pytest.approx(exact.min(), abs=1e-12)
    found = {(c.first, c.samples) for c in sweep.obstacle_contacts}
    expected = {(ur5.links[i], tuple(np.flatnonzero(exact[:, i] <= 0.0))) for i in range(len(ur5.links))
                if (exact[:, i] <= 0.0).any()}
    assert found == expected and found  # the arm sweeps through the wall
