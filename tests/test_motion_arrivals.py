"""The velocity tracker driven by what arrived in a depth camera's frame: the pixels that
came nearer (dynfab.perception.depth_changes), the clusters around them
(dynfab.perception.arrival_clusters), and a ball moving above a floor in MuJoCo."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from dynfab.geometry.shapes import Box, Sphere
from dynfab.perception.arrival_clusters import arrival_clusters
from dynfab.perception.camera_spec import CameraSpec
from dynfab.perception.depth_camera import DepthCamera
from dynfab.perception.depth_changes import DepthChanges
from dynfab.perception.motion_tracks import ClusterTracker
from dynfab.robots import load_robot
from dynfab.sim.depth_render import MujocoDepthRenderer
from dynfab.sim.mujoco_model import SceneObstacle, build_scene

IDENTITY = (1.0, 0.0, 0.0, 0.0)


def test_only_pixels_that_came_nearer_arrive() -> None:
    """A noisy static wall reads no arrival (σ = 2 mm: the threshold is 6√2σ = 1.7 cm, below
    it 2 cm); a patch 10 cm nearer arrives, one 10 cm farther does not; the robot's pixels of
    this frame never arrive, those of the previous frame when nearer than the robot was
    there; where nothing returned before, anything arrives."""
    rng = np.random.default_rng(0)
    changes = DepthChanges(noise=0.002)
    assert changes.threshold == pytest.approx(0.02)
    assert DepthChanges(noise=0.005).threshold == pytest.approx(6 * np.sqrt(2) * 0.005)
    wall = lambda: (2.0 + rng.normal(0.0, 0.002, (120, 160))).astype(np.float32)  # noqa: E731
    kept, nobody = np.ones((120, 160), dtype=bool), np.zeros((120, 160), dtype=bool)
    assert not changes.arrived(wall(), kept, kept).any()  # no previous frame
    assert not changes.arrived(wall(), kept, kept).any()
    before = wall()
    before[0:10, 0:10] = np.inf  # no return
    robot_before = nobody.copy()
    robot_before[100:110, 100:110] = True
    before[robot_before] = 1.0  # the arm in front of the wall
    changes.arrived(before, ~np.isinf(before), ~np.isinf(before) & ~robot_before)
    depth = wall()
    depth[0:10, 0:10] = 1.5
    depth[20:30, 20:30] -= 0.1  # came nearer
    depth[40:50, 40:50] += 0.1  # went away
    depth[100:110, 100:105] = 1.5  # farther than the arm was: uncovered
    depth[100:110, 105:110] = 0.9  # nearer than the arm was: a thing passing in front of it
    robot_now = nobody.copy()
    robot_now[60:70, 60:70] = True
    depth[60:70, 60:70] -= 0.5  # the robot's now
    arrived = changes.arrived(depth, kept, kept & ~robot_now)
    expected = nobody.copy()
    expected[0:10, 0:10] = expected[20:30, 20:30] = expected[100:110, 105:110] = True
    assert np.array_equal(arrived, expected)
    with pytest.raises(ValueError, match="noise must be"):
        DepthChanges(noise=float("nan"))


def plane(z: float, half: float, step: float = 0.01) -> np.ndarray:
    xs, ys = np.meshgrid(np.arange(-half, half, step), np.arange(-half, half, step))
    return np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, z)])


def test_arrival_clusters_keep_what_holds_arrivals_and_is_not_cut() -> None:
    """A ball above a large plane: arrivals on the ball's front give the whole ball (its points
    within 0.3 m of them) and not the plane; arrivals on the plane give nothing (the plane
    goes on beyond the region); fewer arrivals than ``min_seeds`` give nothing."""
    rng = np.random.default_rng(1)
    directions = rng.normal(size=(600, 3))
    ball = np.array([0.2, 0.0, 0.6]) + 0.08 * directions / np.linalg.norm(directions, axis=1, keepdims=True)
    floor = plane(0.0, 2.0)
    points = np.vstack([ball, floor])
    arrived = np.zeros(len(points), dtype=bool)
    arrived[np.flatnonzero(ball[:, 1] > 0.06)] = True  # the leading cap, moving along +y
    rows, labels, count = arrival_clusters(points, arrived, 0.03, 0.3, 5)
    assert count == 1 and np.array_equal(np.sort(rows), np.arange(len(ball)))
    on_floor = np.zeros(len(points), dtype=bool)
    on_floor[len(ball) + np.arange(0, 400, 20)] = True
    assert arrival_clusters(points, on_floor, 0.03, 0.3, 5)[2] == 0
    few = np.zeros(len(points), dtype=bool)
    few[np.flatnonzero(arrived)[:4]] = True
    assert arrival_clusters(points, few, 0.03, 0.3, 5)[2] == 0
    with pytest.raises(ValueError, match=r"arrived: expected one flag per point \(1000,\)"):
        arrival_clusters(points[:1000], arrived, 0.03, 0.3, 5)
    with pytest.raises(ValueError, match="reach >= 0, min_seeds >= 1 and hold_speed >= 0"):
        ClusterTracker(min_seeds=0)


def test_a_ball_moving_above_a_floor_is_tracked_from_its_arrivals_alone() -> None:
    """MuJoCo renders an 8 cm ball moving at 0.5 m/s above a 6 m floor (320 x 240, 2 mm noise,
    30 Hz). The tracker given the frames' arrivals measures the ball within 5 cm/s after its
    window fills, every floor point reads 0, and ``velocity_at`` gives the ball's points its
    velocity; once the ball stops nothing arrives, and once its velocity reads 0 over the
    window it is no longer followed."""
    robot = load_robot("panda")
    spec = CameraSpec(position=(1.6, -1.4, 1.3), look_at=(0.2, -0.2, 0.35), width=320, height=240, fov=60,
                      noise=0.002)
    obstacles = [SceneObstacle(Sphere(0.08), (0.5, -0.6, 0.6), IDENTITY, True),
                 SceneObstacle(Box((6.0, 6.0, 0.1)), (0.0, 0.0, -0.05), IDENTITY, False)]
    scene = build_scene(robot, obstacles, cameras=[spec])
    data = mujoco.MjData(scene.model)
    data.qpos[scene.joint_qpos] = robot.default_q
    renderer = MujocoDepthRenderer(scene.model, spec)
    camera, tracker = DepthCamera(spec, robot), ClusterTracker()
    velocity = np.array([0.0, 0.5, 0.0])
    centre = np.array([0.5, -0.6, 0.6])
    for k in range(16):
        t = k / 30.0
        if k < 10:
            centre = np.array([0.5, -0.6, 0.6]) + velocity * t
        data.mocap_pos[scene.mocap[0]] = centre
        mujoco.mj_forward(scene.model, data)
        frame = camera.frame(t, camera.sensed(renderer.render(data)), robot.default_q)
        velocities = tracker.update(t, frame.points, frame.arrived)
        on_ball = np.linalg.norm(frame.points - centre, axis=1) < 0.09
        assert on_ball.sum() > 100 and len(frame.points) > 20 * on_ball.sum()  # the floor dominates
        assert np.all(velocities[~on_ball] == 0.0)
        if tracker.window + 1 <= k < 10:
            assert np.linalg.norm(velocities[on_ball].mean(axis=0) - velocity) <= 0.05
            near = tracker.velocity_at(frame.points[on_ball])
            assert np.linalg.norm(near.mean(axis=0) - velocity) <= 0.05
            assert np.all(tracker.velocity_at(np.array([[0.0, 0.0, 0.0]])) == 0.0)
        if k >= 11:  # stopped at frame 10: no arrival from frame 11 on
            assert not frame.arrived.any()
        if k >= 11 + tracker.window:  # its velocity read 0 over the window: no longer followed
            assert tracker.tracks == []
    renderer.close()
