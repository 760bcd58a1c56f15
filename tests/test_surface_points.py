"""The nearest-point leaf (meshes, later clouds): its pullback against finite differences, and
a fabric fed by :class:`SurfaceFeed` keeping a robot off a mesh it is driven into."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest
import trimesh

import dynfab
from dynfab.fabric.leaf import LeafContext
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance, moving_spheres
from dynfab.geometry.distance import box_distance
from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.shapes import Placement
from dynfab.geometry.point_cloud import PointCloud
from dynfab.perception.surfaces import PlacedMesh, SurfaceFeed, surface_clearance
from dynfab.robots.robot import CollisionSphere

ARM = Path(__file__).resolve().parents[1] / "examples" / "custom_urdf" / "arm.urdf"


@pytest.fixture(scope="module")
def arm() -> dynfab.Robot:
    spheres = [CollisionSphere("link1", (0.5, 0.0, 0.0), 0.06), CollisionSphere("link2", (0.4, 0.0, 0.0), 0.06),
               CollisionSphere("tool", (0.0, 0.0, 0.0), 0.05)]
    return dynfab.robot_from_urdf(ARM, goal_link="tool", spheres=spheres)


def _leaf_function(arm: dynfab.Robot, leaf: NearestSurfaceAvoidance) -> ca.Function:
    n = arm.kinematics.dof
    q, qdot = ca.SX.sym("q", n), ca.SX.sym("qdot", n)
    symbols = {key: ca.SX.sym(key, size) for key, size in leaf.parameter_sizes().items()}
    term = leaf.geometry(LeafContext(arm, q, qdot, symbols))
    return ca.Function("leaf", [q, qdot, *symbols.values()], [term.M, term.f_geometry, term.f_energy])


def test_the_pullback_matches_finite_differences_of_the_tangent_plane_clearance(arm: dynfab.Robot) -> None:
    leaf = NearestSurfaceAvoidance(spheres=(2,))
    function = _leaf_function(arm, leaf)
    q, qdot = np.array([0.3, -0.4, 0.5]), np.array([0.4, -0.7, 0.2])
    centre = lambda q: np.asarray(arm.sphere_centers(q))[2]  # noqa: E731
    normal = np.array([0.6, 0.0, 0.8])
    point = centre(q) - 0.12 * normal  # clearance 0.12 - 0.05 = 0.07 m
    velocity = np.array([0.1, -0.2, 0.05])
    M, f_geometry, _ = (np.asarray(v) for v in function(q, qdot, point, normal, velocity, 1.0))
    h = 1e-6
    jacobian = np.array([(centre(q + h * e) - centre(q - h * e)) / (2 * h) for e in np.eye(3)]).T
    curvature = (jacobian_at(centre, q + h * qdot) - jacobian_at(centre, q - h * qdot)) / (2 * h) @ qdot
    x = normal @ (centre(q) - point) - 0.05
    xdot = normal @ (jacobian @ qdot - velocity)
    assert x == pytest.approx(0.07, abs=1e-12)
    barrier = leaf.barrier.weighted_geometry()
    m, f = (float(v) for v in ca.Function("b", [barrier.x, barrier.xdot], [barrier.M, barrier.f_geometry])(x, xdot))
    row = normal @ jacobian
    np.testing.assert_allclose(M, m * np.outer(row, row), rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(f_geometry.ravel(), row * (f + m * normal @ curvature), rtol=1e-4)  # J̇q̇ by nested differences
    assert m > 0  # approaching (ẋ < 0) within range: the leaf acts


def jacobian_at(centre, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    return np.array([(centre(q + h * e) - centre(q - h * e)) / (2 * h) for e in np.eye(len(q))]).T


def test_an_inactive_sphere_contributes_nothing(arm: dynfab.Robot) -> None:
    function = _leaf_function(arm, NearestSurfaceAvoidance(spheres=(0, 1, 2)))
    q, qdot = np.array([0.3, -0.4, 0.5]), np.array([0.4, -0.7, 0.2])
    M, f_geometry, f_energy = function(q, qdot, np.zeros(9), np.tile([0.0, 0.0, 1.0], 3), np.zeros(9), np.zeros(3))
    assert np.abs(np.asarray(M)).max() == 0 and np.abs(np.asarray(f_geometry)).max() == 0


def test_moving_spheres_leave_out_spheres_no_joint_moves(arm: dynfab.Robot) -> None:
    assert moving_spheres(arm) == (0, 1, 2)


def test_feed_writes_the_exact_nearest_points_of_a_placed_mesh(arm: dynfab.Robot) -> None:
    box = trimesh.creation.box(extents=(0.2, 0.4, 0.3))
    mesh = Mesh(box.vertices, box.faces, "box")
    leaf = NearestSurfaceAvoidance(spheres=(0, 1, 2))
    planner = dynfab.FabricPlanner(arm, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="tool"),), leaves=(leaf,),
                                                             backend="vm"))
    feed = SurfaceFeed(arm, leaf, planner.parameters.leaves["surfaces"])
    q = np.array([0.2, 0.3, -0.2])
    centres = np.asarray(arm.sphere_centers(q))
    placement = Placement((float(centres[2, 0]) + 0.2, float(centres[2, 1]), 0.0), (0.9659, 0.0, 0.0, 0.2588))
    feed.write(q, [PlacedMesh(mesh, placement, (0.1, 0.0, 0.0))])
    views = planner.parameters.leaves["surfaces"]
    active = views["active"].astype(bool)
    assert active[2]
    points, normals = views["points"].reshape(-1, 3), views["normals"].reshape(-1, 3)
    exact = box_distance(placement.to_local(centres), (0.2, 0.4, 0.3))
    np.testing.assert_allclose(np.einsum("ij,ij->i", normals, centres - points)[active], exact[active], atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(centres - points, axis=1)[active], exact[active], atol=1e-9)
    np.testing.assert_allclose(views["velocities"].reshape(-1, 3)[active], [[0.1, 0.0, 0.0]] * int(active.sum()))
    assert (exact[~active] > feed.reach[~active]).all()


def _feed_beside_a_box(arm: dynfab.Robot) -> tuple[SurfaceFeed, dict, Mesh, Placement, np.ndarray]:
    box = trimesh.creation.box(extents=(0.2, 0.4, 0.3))
    mesh = Mesh(box.vertices, box.faces, "box")
    leaf = NearestSurfaceAvoidance(spheres=(0, 1, 2))
    planner = dynfab.FabricPlanner(arm, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="tool"),), leaves=(leaf,),
                                                             backend="vm"))
    views = planner.parameters.leaves["surfaces"]
    feed = SurfaceFeed(arm, leaf, views)
    q = np.array([0.2, 0.3, -0.2])
    centres = np.asarray(arm.sphere_centers(q))
    placement = Placement((float(centres[2, 0]) + 0.15, float(centres[2, 1]), 0.0))
    return feed, views, mesh, placement, q


def test_an_allowance_writes_the_nearest_point_that_much_deeper_along_its_normal(arm: dynfab.Robot) -> None:
    feed, views, mesh, placement, q = _feed_beside_a_box(arm)
    centres = np.asarray(arm.sphere_centers(q))
    feed.write(q, [PlacedMesh(mesh, placement)])
    before_points, before_normals = views["points"].reshape(-1, 3).copy(), views["normals"].reshape(-1, 3).copy()
    active = views["active"].astype(bool).copy()
    assert active[2]
    feed.write(q, [PlacedMesh(mesh, placement, allowance=0.02)])
    points, normals = views["points"].reshape(-1, 3), views["normals"].reshape(-1, 3)
    np.testing.assert_allclose(normals[active], before_normals[active])
    np.testing.assert_allclose(points[active], before_points[active] - 0.02 * before_normals[active], atol=1e-12)
    seen = np.einsum("ij,ij->i", normals, centres - points)  # the leaf's clearance plus the radius
    exact = box_distance(placement.to_local(centres), (0.2, 0.4, 0.3))
    np.testing.assert_allclose(seen[active], exact[active] + 0.02, atol=1e-9)


def test_surfaces_compete_by_their_clearance_less_the_allowance(arm: dynfab.Robot) -> None:
    feed, views, mesh, placement, q = _feed_beside_a_box(arm)
    farther = Placement((placement.position[0] + 0.03, placement.position[1], placement.position[2]))
    feed.write(q, [PlacedMesh(mesh, placement, allowance=0.05), PlacedMesh(mesh, farther)])
    centres = np.asarray(arm.sphere_centers(q))
    exact_far = box_distance(farther.to_local(centres), (0.2, 0.4, 0.3))
    points, normals = views["points"].reshape(-1, 3), views["normals"].reshape(-1, 3)
    # the nearer box, entered by 5 cm, counts 2 cm farther than the other, which is written
    assert np.dot(normals[2], centres[2] - points[2]) == pytest.approx(exact_far[2], abs=1e-9)


def test_surface_clearance_is_the_least_sphere_clearance_from_a_mesh_or_a_cloud(arm: dynfab.Robot) -> None:
    _, _, mesh, placement, q = _feed_beside_a_box(arm)
    centres = np.asarray(arm.sphere_centers(q))
    radii = arm.sphere_radii
    exact = box_distance(placement.to_local(centres), (0.2, 0.4, 0.3)) - radii
    assert surface_clearance(centres, radii, mesh, placement) == pytest.approx(float(exact.min()), abs=1e-9)
    points = np.asarray(placement.position) + np.array([[-0.1, 0.0, 0.0], [-0.1, 0.05, 0.02]])
    cloud = PointCloud.from_points(points, voxel=0.01)
    expected = np.linalg.norm(centres[:, None] - cloud.points[None], axis=2).min(axis=1) - cloud.lowering - radii
    assert surface_clearance(centres, radii, cloud, Placement((0.0, 0.0, 0.0))) == pytest.approx(float(expected.min()))
