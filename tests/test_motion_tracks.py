"""Clusters of points and their velocities from frame to frame: synthetic frames of a sphere
moving at a known velocity (its visible cap, with noise), static clutter, occlusion; and a
sphere moving in a MuJoCo scene, seen by the depth camera."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from dynfab.geometry.shapes import Box, Sphere
from dynfab.perception.camera_spec import CameraSpec
from dynfab.perception.clusters import voxel_clusters
from dynfab.perception.depth_camera import DepthCamera
from dynfab.perception.motion_tracks import ClusterTracker
from dynfab.robots import load_robot
from dynfab.sim.depth_render import MujocoDepthRenderer
from dynfab.sim.mujoco_model import SceneObstacle, build_scene

CAMERA = np.array([0.0, -2.0, 1.0])


def visible_cap(centre: np.ndarray, radius: float, rng: np.random.Generator, count: int = 800,
                noise: float = 0.002) -> np.ndarray:
    """Points of the half of a sphere's surface facing :data:`CAMERA`, with Gaussian noise."""
    directions = rng.normal(size=(3 * count, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    facing = directions[directions @ (CAMERA - centre) > 0][:count]
    return centre + radius * facing + rng.normal(0.0, noise, (len(facing), 3))


def table(rng: np.random.Generator, x_max: float = 0.6, noise: float = 0.002) -> np.ndarray:
    """A table top at z = 0.2: points on a 5 mm grid, x in [−0.6, x_max], y in [−0.4, 0.4]."""
    xs, ys = np.meshgrid(np.arange(-0.6, x_max, 0.005), np.arange(-0.4, 0.4, 0.005))
    points = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 0.2)])
    return points + rng.normal(0.0, noise, points.shape)


def test_voxel_clusters_separate_what_is_apart_and_join_what_touches() -> None:
    rng = np.random.default_rng(0)
    a = rng.uniform(0.0, 0.1, (200, 3))
    b = rng.uniform(0.0, 0.1, (200, 3)) + (0.3, 0.0, 0.0)
    labels, count = voxel_clusters(np.vstack([a, b]), 0.03)
    assert count == 2 and len(set(labels[:200])) == 1 and len(set(labels[200:])) == 1 and labels[0] != labels[200]
    diagonal = np.array([[0.0, 0.0, 0.0], [0.029, 0.029, 0.029]])  # neighbouring voxels by a corner
    assert voxel_clusters(diagonal + 0.001, 0.03)[1] == 1
    apart = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.061]])  # two voxels in between
    assert voxel_clusters(apart + 0.001, 0.03)[1] == 2
    assert voxel_clusters(np.zeros((0, 3)), 0.03)[1] == 0


@pytest.mark.parametrize("velocity", [(0.5, 0.0, 0.0), (0.0, -0.5, 0.0), (0.3, 0.3, -0.2)])
def test_a_sphere_moving_at_a_known_velocity_is_measured_within_ten_percent(velocity: tuple[float, ...]) -> None:
    """30 Hz frames of a 6 cm ball's visible cap (2 mm noise) above a static table: after the
    window fills, the ball's points carry its velocity within 10 %, the table's ~0."""
    rng = np.random.default_rng(1)
    v = np.array(velocity)
    tracker = ClusterTracker()
    for k in range(12):
        t = k / 30.0
        ball = visible_cap(np.array([-0.2, 0.0, 0.6]) + v * t, 0.06, rng)
        clutter = table(rng)
        velocities = tracker.update(t, np.vstack([ball, clutter]))
        if k >= tracker.window:
            measured = velocities[:len(ball)]
            assert np.all(measured == measured[0])  # one velocity per cluster
            assert np.linalg.norm(measured[0] - v) <= 0.1 * np.linalg.norm(v)
            assert np.abs(velocities[len(ball):]).max() < 0.05


def test_a_static_cluster_that_is_occluded_bit_by_bit_reads_no_motion() -> None:
    """The table's far end disappears (an arm passing in front) at 0.6 m/s: its centroid moves,
    its near end does not, so it is not taken for moving."""
    rng = np.random.default_rng(2)
    tracker = ClusterTracker()
    for k in range(10):
        t = k / 30.0
        velocities = tracker.update(t, table(rng, x_max=0.6 - 0.6 * t))
        assert np.abs(velocities).max() < 0.05


def test_a_new_cluster_reads_zero_and_small_clusters_are_not_tracked() -> None:
    rng = np.random.default_rng(3)
    tracker = ClusterTracker(min_points=20)
    first = tracker.update(0.0, visible_cap(np.zeros(3), 0.05, rng))
    assert np.all(first == 0.0)
    specks = rng.uniform(-1.0, 1.0, (10, 3)) * 10  # far apart: ten clusters of one point
    tracker.update(1 / 30, specks)
    assert np.all(tracker.update(2 / 30, specks + 0.01) == 0.0) and tracker.tracks == []
    with pytest.raises(ValueError, match="frames must come in time order"):
        tracker.update(2 / 30, specks)


def test_a_ball_moving_in_the_camera_view_gets_its_velocity() -> None:
    """MuJoCo renders a 5 cm ball moving at 0.5 m/s across the view of a 320 x 240 camera (2 mm
    noise, 30 Hz); the tracker's estimate from the frames is within 10 %."""
    robot = load_robot("panda")
    spec = CameraSpec(position=(1.6, 0.0, 0.9), look_at=(0.4, 0.0, 0.4), width=320, height=240, fov=60,
                      noise=0.002)
    obstacles = [SceneObstacle(Sphere(0.05), (0.6, -0.4, 0.5), (1.0, 0.0, 0.0, 0.0), True),
                 SceneObstacle(Box((1.5, 1.5, 0.1)), (0.4, 0.0, -0.05), (1.0, 0.0, 0.0, 0.0), False)]
    scene = build_scene(robot, obstacles, cameras=[spec])
    data = mujoco.MjData(scene.model)
    data.qpos[scene.joint_qpos] = robot.default_q
    renderer = MujocoDepthRenderer(scene.model, spec)
    camera, tracker = DepthCamera(spec, robot), ClusterTracker()
    velocity = np.array([0.0, 0.5, 0.0])
    estimates = []
    for k in range(10):
        t = k / 30.0
        centre = np.array([0.6, -0.4, 0.5]) + velocity * t
        data.mocap_pos[scene.mocap[0]] = centre
        mujoco.mj_forward(scene.model, data)
        frame = camera.frame(t, camera.sensed(renderer.render(data)), robot.default_q)
        velocities = tracker.update(t, frame.points)
        on_ball = np.linalg.norm(frame.points - centre, axis=1) < 0.06
        assert on_ball.sum() > 50
        estimates.append(velocities[on_ball].mean(axis=0))
    renderer.close()
    for estimate in estimates[tracker.window:]:
        assert np.linalg.norm(estimate - velocity) <= 0.05
