"""Goals free on the robot's meshes but refused by its spheres (issue 20: MotionBenchMaker's
mesh-scene goals are millimetres from the meshes): the mesh check and guidance's inverse
kinematics falling back on it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Box, Placement
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import GuidanceError, GuidanceSettings, JointGuidance
from dynfab.motion.inverse_kinematics import IkSettings
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.mesh_collision import mesh_collision_model, moving_part
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes
from wall_scene import hand_pose_targets
from coarse_panda import panda_on_planning_spheres

Q = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])
#: a 2 cm cube that touches panda_link2's sphere at Q (2.6 mm deep) and clears its mesh by 1.7 cm
BESIDE_LINK2 = PlacedObstacle(Box((0.02, 0.02, 0.02)), Placement((-0.01947183, -0.08098174, 0.47577751)))


@pytest.fixture(scope="module")
def panda():
    return panda_on_planning_spheres()


@pytest.fixture(scope="module")
def check(panda) -> MeshGoalCheck:
    model = mesh_collision_model(panda.kinematics, panda.default_q, builtin_collision_meshes(panda))
    assert model is not None
    return MeshGoalCheck(model, 0.003)


def test_a_box_the_spheres_touch_and_the_meshes_clear_is_free_on_the_meshes(panda, check) -> None:
    assert ConfigurationChecker(panda, (BESIDE_LINK2,)).clearances(Q)[0] < 0.0
    check.set_obstacles((BESIDE_LINK2,))
    obstacle, itself = check.clearance(Q)
    assert 0.01 < obstacle < 0.03 and itself > 0.0
    assert check.free(Q)
    stricter = MeshGoalCheck(check.model, obstacle + 0.001)
    stricter.set_obstacles((BESIDE_LINK2,))
    assert not stricter.free(Q)   # the margin is kept


def test_a_cloud_is_measured_less_its_voxel_half_diagonal(check) -> None:
    box = BESIDE_LINK2.placement.position
    corners = np.array(box) + 0.01 * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    cloud = PointCloud.from_points(corners, voxel=0.01)
    at_origin = Placement((0.0, 0.0, 0.0))
    check.set_obstacles((PlacedObstacle(cloud, at_origin),))
    kept = sweep_meshes(check.model, Q[None], [PlacedShape("cloud", cloud, (at_origin,))]).clearance
    assert check.clearance(Q)[0] == pytest.approx(kept - cloud.lowering)
    check.set_obstacles(())
    assert check.clearance(Q)[0] == np.inf


def test_a_bad_margin_is_refused_by_name(check) -> None:
    with pytest.raises(ValueError, match="margin"):
        MeshGoalCheck(check.model, -0.001)


def test_guidance_keeps_an_ik_solution_the_spheres_refuse_if_the_meshes_are_free(panda) -> None:
    only_here = IkSettings(seeds=1)   # the current configuration alone: Q, which reaches the pose
    settings = GuidanceSettings(ik=only_here, ik_retry=only_here)
    guidance = JointGuidance(panda, settings)
    guidance.checker.set_obstacles((BESIDE_LINK2,))
    np.testing.assert_allclose(guidance.goal_configuration(hand_pose_targets(panda, Q), Q), Q, atol=1e-9)
    strict = JointGuidance(panda, replace(settings, mesh_margin=0.05, mesh_goal_floor=0.05))
    strict.checker.set_obstacles((BESIDE_LINK2,))
    with pytest.raises(GuidanceError) as failure:
        strict.goal_configuration(hand_pose_targets(panda, Q), Q)
    assert failure.value.reason == "no_ik_solution"


def test_a_segment_whose_middle_meets_a_box_is_not_free_though_its_ends_are(panda, check) -> None:
    a, b = Q.copy(), Q.copy()
    a[0], b[0] = 0.5, 1.5   # the arm swings about its base; the hand passes Q's place halfway
    in_the_way = PlacedObstacle(Box((0.05, 0.05, 0.05)), Placement(tuple(panda.link_position(Q, "panda_hand"))))
    check.set_obstacles((in_the_way,))
    assert check.free(a) and check.free(b)
    assert not check.segment_free(a, b, 0.015)
    assert check.segment_free(a, a, 0.015)
    deepest = check.clearance(np.linspace(a, b, 68))[0]   # the same samples: 1 rad in 67 steps of at most 0.015
    assert deepest < 0.0
    assert check.segment_free(a, b, 0.015, floor=deepest)   # a goal as deep as that may be approached
    assert not check.segment_free(a, b, 0.015, floor=deepest + 1e-4)


def test_an_obstacle_beside_the_base_alone_blocks_no_configuration(panda, check) -> None:
    """The base's distance is the same at every configuration (development kitchen/0015,
    seed 1: the Panda's base 1.9 mm from a dishwasher door refused every goal solution)."""
    base = check.model.links.index("panda_link0")
    front = max(float(part.vertices[:, 0].max()) for part in builtin_collision_meshes(panda)["panda_link0"])
    beside = PlacedObstacle(Box((0.02, 0.2, 0.05)), Placement((front + 0.001 + 0.01, 0.0, 0.03)))
    full = sweep_meshes(check.model, Q[None], [PlacedShape("box", beside.shape, (beside.placement,))])
    assert [c.first for c in full.obstacle_contacts] == [] and full.clearance == pytest.approx(0.001, abs=5e-4)
    assert check.model.links[base] == "panda_link0" and "panda_link0" not in moving_part(check.model).links
    check.set_obstacles((beside,))
    assert check.clearance(Q)[0] > check.margin and check.free(Q)
    assert check.segment_free(Q, Q + 0.05, 0.01)
    check.set_obstacles((beside, BESIDE_LINK2))   # a moving link's obstacle still counts
    assert check.clearance(Q)[0] < 0.03
