"""The boolean mesh contact check (issue 20): the same answer as the exact mesh distances
at every margin, point clouds and bad margins refused by name."""

from __future__ import annotations

import numpy as np
import pytest

import trimesh

from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Placement, Plane, Sphere
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.robots import load_robot
from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.mesh_collision import mesh_collision_model
from dynfab.robots.mesh_contact import MeshContactCheck
from test_mesh_goal_check import BESIDE_LINK2, Q   # a cube the spheres touch at Q, the meshes clear by 1.7 cm

#: a table-top slab under the hand's reach
SLAB = PlacedObstacle(Box((0.6, 0.6, 0.05)), Placement((0.5, 0.0, 0.25)))


@pytest.fixture(scope="module")
def model():
    panda = load_robot("panda")
    built = mesh_collision_model(panda.kinematics, panda.default_q, builtin_collision_meshes(panda))
    assert built is not None
    return built


def _both_answers(model, obstacles, margin: float, configurations: np.ndarray) -> tuple[MeshContactCheck, list[bool]]:
    """The contact check at ``margin`` among ``obstacles``, and the exact distances' answer
    at each configuration (obstacles farther than ``margin``, no link pair touching)."""
    exact = MeshGoalCheck(model, 0.0)
    exact.set_obstacles(obstacles)
    contact = MeshContactCheck(model, margin)
    contact.set_obstacles(obstacles)
    truth = []
    for q in configurations:
        obstacle, itself = exact.clearance(q)
        truth.append(obstacle > margin and itself > 0.0)
    return contact, truth


@pytest.mark.parametrize("margin", [0.0, 0.003, 0.01])
def test_it_agrees_with_the_exact_distances(model, margin: float) -> None:
    """Also where the cube lies wholly inside panda_link2's mesh (no triangles cross)."""
    configurations = Q + np.random.default_rng(3).normal(0.0, 0.4, (60, 7))
    contact, truth = _both_answers(model, (SLAB, BESIDE_LINK2), margin, configurations)
    assert [contact.free(q) for q in configurations] == truth
    assert 5 < sum(truth) < 55   # both answers are asked for
    assert contact.checks == len(configurations)


def _tilted(shape: object, position: tuple[float, float, float], seed: int) -> PlacedObstacle:
    """``shape`` at ``position`` in a random orientation."""
    return PlacedObstacle(shape, Placement(position, tuple(np.random.default_rng(seed).normal(size=4))))


#: every kind of shape, tilted, about the arm at Q; the mesh's box lies off its frame's origin
#: (the pre-test's bounding box must follow it)
SHAPES = (_tilted(Sphere(0.05), (0.35, 0.1, 0.6), 1),
          _tilted(Box((0.3, 0.04, 0.1)), (0.4, -0.15, 0.45), 2),
          _tilted(Cylinder(0.03, 0.3), (0.2, 0.2, 0.5), 3),
          _tilted(Capsule(0.02, 0.25), (0.3, -0.3, 0.7), 4),
          _tilted(Mesh(trimesh.creation.box(extents=(0.05, 0.2, 0.05)).vertices + np.array([0.15, 0.0, 0.0]),
                       trimesh.creation.box(extents=(0.05, 0.2, 0.05)).faces), (0.1, 0.0, 0.8), 5),
          PlacedObstacle(Plane(), Placement((0.0, 0.0, 0.05))))


@pytest.mark.parametrize("margin", [0.0, 0.005])
def test_every_shape_agrees_with_the_exact_distances(model, margin: float) -> None:
    """Spheres, boxes, cylinders, capsules, a mesh off its origin and a plane, tilted: the
    bounding boxes that skip pairs never skip a touching one."""
    configurations = Q + np.random.default_rng(7).normal(0.0, 0.5, (150, 7))
    contact, truth = _both_answers(model, SHAPES, margin, configurations)
    assert [contact.free(q) for q in configurations] == truth
    assert 20 < sum(truth) < 130   # both answers are asked for


def test_the_margin_decides_near_a_mesh(model) -> None:
    exact = MeshGoalCheck(model, 0.0)
    exact.set_obstacles((BESIDE_LINK2,))
    clearance = exact.clearance(Q)[0]
    near, far = MeshContactCheck(model, clearance + 0.001), MeshContactCheck(model, clearance - 0.001)
    for check in (near, far):
        check.set_obstacles((BESIDE_LINK2,))
    assert far.free(Q) and not near.free(Q)
    assert far.motion_free(Q, Q, 0.01) and not near.motion_free(Q - 0.05, Q, 0.01)


def test_clouds_and_bad_margins_are_refused_by_name(model) -> None:
    cloud = PointCloud.from_points(np.array([[0.5, 0.0, 0.5], [0.5, 0.1, 0.5]]), voxel=0.01)
    with pytest.raises(ValueError, match=r"obstacles\[1\]"):
        MeshContactCheck(model, 0.0).set_obstacles((SLAB, PlacedObstacle(cloud, Placement((0.0, 0.0, 0.0)))))
    with pytest.raises(ValueError, match="margin"):
        MeshContactCheck(model, -0.001)
    with pytest.raises(ValueError, match="step"):
        MeshContactCheck(model, 0.0).motion_free(Q, Q, 0.0)
