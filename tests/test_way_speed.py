"""The reference slows where its way is tight: velocity limits scaled along the path
(``time_path(..., speed_scale)``) and guidance's ``σ(q) = clip(c(q) / slow_clearance,
slow_speed, 1)``."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Placement
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.guidance import JointGuidance, JointTarget
from dynfab.motion.guidance_settings import GuidanceSettings
from dynfab.motion.joint_trajectory import time_path
from dynfab.motion.mesh_goal_check import MeshGoalCheck, robot_mesh_model
from dynfab.robots import load_robot
from wall_scene import MESH_WALL, START, WALL

WAYPOINTS = np.array([[0.0, 0.0], [1.0, 0.5], [1.2, -0.4], [2.0, 0.0]])
VELOCITY = np.array([1.0, 0.8])
ACCELERATION = np.array([2.0, 3.0])


def _slow_in_the_middle(qs: np.ndarray) -> np.ndarray:
    """0.2 where ``q_0`` is within 0.3 of 1.1, else 1."""
    return np.where(np.abs(qs[:, 0] - 1.1) < 0.3, 0.2, 1.0)


def test_a_scaled_timing_keeps_the_scaled_limits_and_is_the_plain_one_where_the_scale_is_one() -> None:
    plain = time_path(WAYPOINTS, VELOCITY, ACCELERATION)
    scaled = time_path(WAYPOINTS, VELOCITY, ACCELERATION, speed_scale=_slow_in_the_middle)
    times = np.linspace(0.0, scaled.duration, 4001)
    q, qdot, qddot = scaled.sample(times)
    inner = np.abs(q[:, 0] - 1.1) < 0.25   # off the scale's steps
    used = np.max(np.abs(qdot[inner]) / (0.2 * VELOCITY), axis=1)   # of the scaled limits
    assert np.median(used) <= 1.0   # kept at TOPP-RA's grid points, over it between them
    assert used.max() <= 1.2        # (most at the sharp corner (1.2, -0.4))
    assert np.all(np.abs(qdot) <= VELOCITY * (1 + 1e-9)) and np.all(np.abs(qddot) <= ACCELERATION * (1 + 1e-9))
    np.testing.assert_allclose(q[-1], WAYPOINTS[-1], atol=1e-6)
    assert scaled.duration > plain.duration + 1.0   # the middle is crossed at a fifth of the speed
    same = time_path(WAYPOINTS, VELOCITY, ACCELERATION, speed_scale=lambda qs: np.ones(len(qs)))
    assert same.duration == pytest.approx(plain.duration, rel=1e-9)


#: the mesh wall 3 cm farther from the base: the goal behind it, where the base's spheres are
#: 12 mm from the box, reads 9.5 mm on the mesh's grid, within the planner's 1 cm margin
FARTHER_WALL = replace(MESH_WALL, placement=Placement((0.48, 0.0, 0.35)))


def test_guidance_slows_its_reference_where_the_way_passes_close_to_a_mesh_wall() -> None:
    panda = load_robot("panda")
    goal = START.copy()
    goal[0] = -1.3   # behind the wall: the way goes around it
    settings = GuidanceSettings()
    slow, fast = JointGuidance(panda, settings), JointGuidance(panda, replace(settings, slow_clearance=0.0))
    plan = slow.plan(START, JointTarget(goal), [FARTHER_WALL])
    times = np.linspace(0.0, plan.trajectory.duration, 3001)
    q, qdot, _ = plan.trajectory.sample(times)
    ratio = np.max(np.abs(qdot) / panda.limits.velocity, axis=1)   # fraction of the limits used
    scale = slow.speed_scale(q)
    assert scale.min() < 1.0   # the way does pass within slow_clearance of the wall
    assert np.all(ratio <= settings.speed * np.maximum(scale, settings.slow_speed) + 0.03)
    unslowed = fast.plan(START, JointTarget(goal), [FARTHER_WALL])
    np.testing.assert_allclose(unslowed.trajectory.waypoints, plan.trajectory.waypoints)   # the same path
    assert plan.trajectory.duration > unslowed.trajectory.duration


def _expected_scale(guidance: JointGuidance, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """σ from the meshes' clearance measured at every row of ``q`` where the spheres come
    within ``slow_clearance`` (each configuration alone, with coal), and σ from the spheres."""
    settings = guidance.settings
    spheres = guidance.checker.batch(q)[:, 0]
    meshes = MeshGoalCheck(robot_mesh_model(guidance.robot), 0.0)
    meshes.set_obstacles(guidance.checker.obstacles)
    exact = np.array([meshes.clearance(row)[0] for row in q])
    by_meshes = np.where(spheres < settings.slow_clearance,
                         np.clip(exact / settings.slow_clearance, settings.slow_speed, 1.0), 1.0)
    return by_meshes, np.clip(spheres / settings.slow_clearance, settings.slow_speed, 1.0)


def test_the_way_is_slowed_by_the_meshes_clearance_where_the_spheres_come_near() -> None:
    panda = load_robot("panda")
    guidance = JointGuidance(panda)
    guidance.set_obstacles((FARTHER_WALL,))
    q = np.tile(START, (100, 1))
    q[:, 0] = np.linspace(1.0, -1.3, 100)   # the hand swept through the wall's plane
    by_meshes, by_spheres = _expected_scale(guidance, q)
    scale = guidance.speed_scale(q)
    np.testing.assert_allclose(scale, by_meshes, atol=1e-9)   # measured at every configuration near the wall
    assert scale.min() == guidance.settings.slow_speed   # through the wall: the slowest
    assert np.any(scale > by_spheres + 0.05)             # the meshes have room where the spheres read little


def test_point_clouds_and_primitives_do_not_slow_the_way_and_the_meshes_beside_them_do() -> None:
    panda = load_robot("panda")
    guidance = JointGuidance(panda)
    hand = np.asarray(panda.link_position(START, "panda_hand")).ravel()
    points = hand + np.random.default_rng(0).uniform(-0.1, 0.1, (400, 2)) @ np.array([[1.0, 0.0, 0.0],
                                                                                      [0.0, 1.0, 0.0]])
    points[:, 2] -= 0.07   # a patch of floor 7 cm under the hand
    cloud = PlacedObstacle(PointCloud.from_points(points, voxel=0.01), Placement((0.0, 0.0, 0.0)))
    q = np.tile(START, (5, 1)) + np.linspace(0.0, 0.4, 5)[:, None]
    guidance.set_obstacles((cloud,))
    assert guidance.checker.batch(q)[:, 0].min() < guidance.settings.slow_clearance   # near it: it would slow
    np.testing.assert_array_equal(guidance.speed_scale(q), np.ones(5))
    guidance.set_obstacles((WALL,))   # the box (in_sight guards the way among primitives)
    assert guidance.checker.batch(q)[:, 0].min() < guidance.settings.slow_clearance
    np.testing.assert_array_equal(guidance.speed_scale(q), np.ones(5))
    guidance.set_obstacles((cloud, WALL, MESH_WALL))
    alone = JointGuidance(panda)
    alone.set_obstacles((MESH_WALL,))
    scale = alone.speed_scale(q)
    assert scale.min() < 1.0
    np.testing.assert_array_equal(guidance.speed_scale(q), scale)   # the mesh's, on the planning spheres
