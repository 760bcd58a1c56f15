"""The boolean mesh contact check (issue 20): the same answer as the exact mesh distances
at every margin, point clouds and bad margins refused by name."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Box, Placement
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


@pytest.mark.parametrize("margin", [0.0, 0.003, 0.01])
def test_it_agrees_with_the_exact_distances(model, margin: float) -> None:
    """Also where the cube lies wholly inside panda_link2's mesh (no triangles cross)."""
    exact = MeshGoalCheck(model, 0.0)
    exact.set_obstacles((SLAB, BESIDE_LINK2))
    contact = MeshContactCheck(model, margin)
    contact.set_obstacles((SLAB, BESIDE_LINK2))
    rng = np.random.default_rng(3)
    configurations = Q + rng.normal(0.0, 0.4, (60, 7))
    truth = []
    for q in configurations:
        obstacle, itself = exact.clearance(q)
        truth.append(obstacle > margin and itself > 0.0)
    assert [contact.free(q) for q in configurations] == truth
    assert 5 < sum(truth) < 55   # both answers are asked for
    assert contact.checks == len(configurations)


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
