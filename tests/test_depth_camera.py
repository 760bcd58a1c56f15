"""The depth camera: intrinsics, occlusion, the robot filtered out, rate and delay, noise, bad
input; rendered by MuJoCo where the scene matters."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from dynfab.geometry.shapes import Box, Sphere
from dynfab.perception.camera_spec import CameraSpec, CameraSpecError
from dynfab.perception.depth_camera import DepthCamera
from dynfab.perception.depth_image import DepthProjector
from dynfab.robots import load_robot
from dynfab.robots.robot import Robot
from dynfab.sim.depth_render import MujocoDepthRenderer
from dynfab.sim.mujoco_model import SceneObstacle, build_scene

IDENTITY = (1.0, 0.0, 0.0, 0.0)


@pytest.fixture(scope="module")
def panda() -> Robot:
    return load_robot("panda")


def render(robot: Robot, spec: CameraSpec, obstacles: list[SceneObstacle], q: np.ndarray | None = None
           ) -> np.ndarray:
    """One depth image of ``robot`` (at ``q``, default its default configuration) among
    ``obstacles`` from the camera ``spec``."""
    scene = build_scene(robot, obstacles, cameras=[spec])
    data = mujoco.MjData(scene.model)
    data.qpos[scene.joint_qpos] = robot.default_q if q is None else q
    mujoco.mj_forward(scene.model, data)
    renderer = MujocoDepthRenderer(scene.model, spec)
    try:
        return renderer.render(data)
    finally:
        renderer.close()


def box(size: tuple[float, float, float], position: tuple[float, float, float]) -> SceneObstacle:
    return SceneObstacle(Box(size), position, IDENTITY, False)


def test_a_plane_at_known_distance_gives_points_at_that_distance(panda: Robot) -> None:
    """A camera 1.5 m above a box's top face (away from the robot) sees every pixel on it."""
    spec = CameraSpec(position=(3.0, 0.0, 2.0), look_at=(3.0, 0.0, 0.0), width=160, height=120, fov=60)
    depth = render(panda, spec, [box((3.0, 3.0, 1.0), (3.0, 0.0, 0.0))])
    np.testing.assert_allclose(depth, 1.5, atol=1e-5)
    frame = DepthCamera(spec, panda).frame(0.0, depth, panda.default_q)
    assert frame.points.shape == (160 * 120, 3) and frame.robot_points == 0
    np.testing.assert_allclose(frame.points[:, 2], 0.5, atol=1e-5)
    half_height = 1.5 * math.tan(math.radians(30.0))  # the field of view's footprint on the plane
    half_width = half_height * 160 / 120
    footprint = 1.5 / spec.focal
    assert np.ptp(frame.points[:, 1]) == pytest.approx(2 * half_height - footprint, abs=1e-4)
    assert np.ptp(frame.points[:, 0]) == pytest.approx(2 * half_width - footprint, abs=1e-4)


def test_a_box_face_back_projects_to_its_place_within_a_pixel(panda: Robot) -> None:
    """An oblique camera: the points of a box's top face span the face to within one pixel's
    footprint, and no point lies off the box's surface."""
    spec = CameraSpec(position=(2.6, -0.5, 1.4), look_at=(3.0, 0.1, 0.2), width=320, height=240, fov=50)
    size, centre = np.array([0.3, 0.2, 0.4]), np.array([3.0, 0.1, 0.2])
    depth = render(panda, spec, [box(tuple(size), tuple(centre))])
    points = DepthCamera(spec, panda).frame(0.0, depth, panda.default_q).points
    local = np.abs(points - centre) - size / 2
    assert np.all(local.max(axis=1) <= 1e-4)  # inside the box's closure
    np.testing.assert_allclose(local.max(axis=1), 0.0, atol=1e-4)  # on its surface
    top = points[np.abs(points[:, 2] - (centre[2] + size[2] / 2)) < 1e-4]
    footprint = np.linalg.norm(np.subtract(spec.position, centre)) * 1.5 / spec.focal  # a pixel, obliquely
    for axis in (0, 1):
        assert top[:, axis].min() == pytest.approx(centre[axis] - size[axis] / 2, abs=footprint)
        assert top[:, axis].max() == pytest.approx(centre[axis] + size[axis] / 2, abs=footprint)


def test_a_box_hidden_behind_another_gives_no_points(panda: Robot) -> None:
    spec = CameraSpec(position=(3.0, 0.0, 2.0), look_at=(3.0, 0.0, 0.0), width=160, height=120)
    hidden = box((0.1, 0.1, 0.1), (3.0, 0.0, 0.3))
    cover = box((0.4, 0.4, 0.05), (3.0, 0.0, 0.8))
    camera = DepthCamera(spec, panda)
    near_hidden = lambda points: np.all(np.abs(points - (3.0, 0.0, 0.3)) <= 0.05 + 1e-4, axis=1)  # noqa: E731
    seen = camera.frame(0.0, render(panda, spec, [hidden]), panda.default_q).points
    assert near_hidden(seen).sum() > 30  # alone, the camera sees it
    covered = camera.frame(0.0, render(panda, spec, [hidden, cover]), panda.default_q).points
    assert not near_hidden(covered).any()
    assert np.all(covered[:, 2] == pytest.approx(0.825, abs=1e-4))  # only the cover's top face


def test_the_robot_is_filtered_out_at_the_frames_configuration(panda: Robot) -> None:
    """The Panda (collision spheres as geoms) in front of a wall: none of its points remain,
    the wall's do; filtered at another configuration, the robot's points stay."""
    spec = CameraSpec(position=(1.8, 0.0, 0.6), look_at=(0.0, 0.0, 0.5), width=320, height=240, fov=60)
    wall = box((0.1, 3.0, 2.0), (-0.6, 0.0, 0.5))
    depth = render(panda, spec, [wall])
    camera = DepthCamera(spec, panda, margin=0.02)
    frame = camera.frame(0.0, depth, panda.default_q)
    assert frame.robot_points > 2000
    centres, radii = panda.sphere_centers(panda.default_q), panda.sphere_radii
    distances = np.linalg.norm(frame.points[:, None, :] - centres[None], axis=2) - radii
    assert distances.min() > 0.02 - 1e-4  # nothing within the margin of a sphere
    assert np.all(frame.points[:, 0] == pytest.approx(-0.55, abs=1e-4))  # all that remains is the wall
    assert len(frame.points) + frame.robot_points == np.isfinite(depth).sum()
    elsewhere = panda.default_q + np.array([1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    stale = camera.frame(0.0, depth, elsewhere)
    assert stale.robot_points < frame.robot_points / 2
    assert np.sum(stale.points[:, 0] > -0.5) > 1000  # the robot's own points, left in


def test_the_filter_matches_a_brute_force_test_of_every_pixel(panda: Robot) -> None:
    """The windowed test of :func:`robot_pixels` finds exactly the pixels a test of every
    pixel against every sphere finds."""
    spec = CameraSpec(position=(1.2, -0.8, 1.0), look_at=(0.2, 0.0, 0.4), width=160, height=120, fov=70)
    depth = render(panda, spec, [box((3.0, 3.0, 0.1), (0.0, 0.0, -0.1))])
    camera = DepthCamera(spec, panda, margin=0.03)
    frame = camera.frame(0.0, depth, panda.default_q)
    projector = DepthProjector(spec)
    returns = DepthProjector.returns(depth)
    every = projector.points(depth, returns)
    centres, radii = panda.sphere_centers(panda.default_q), panda.sphere_radii + 0.03
    inside = np.any(np.linalg.norm(every[:, None, :] - centres[None], axis=2) <= radii, axis=1)
    assert frame.robot_points == inside.sum() > 500
    np.testing.assert_allclose(frame.points, every[~inside], atol=1e-6)


class Counter:
    """A renderer of a constant depth image that counts its calls."""

    def __init__(self, spec: CameraSpec, depth: float = 2.0) -> None:
        self.image = np.full((spec.height, spec.width), depth, dtype=np.float32)
        self.calls = 0

    def __call__(self) -> np.ndarray:
        self.calls += 1
        return self.image


def test_frames_are_taken_at_the_rate_and_released_after_the_delay() -> None:
    robot = load_robot("point")
    spec = CameraSpec(position=(0, 0, 3), look_at=(0, 0, 0), width=8, height=6, rate=30.0, delay=0.05)
    camera = DepthCamera(spec, robot)
    render = Counter(spec)
    taken, released = [], []
    for k in range(100):  # 1 s of 10 ms ticks
        t = k * 0.01
        frame = camera.tick(t, render, np.zeros(2))
        if frame is not None:
            taken.append(frame.time)
        released += [(t, frame.time) for frame in camera.release(t)]
    assert render.calls == len(taken) == 30  # 30 Hz for 1 s: renders only when due
    expected = np.ceil(np.arange(30) / 30 / 0.01 - 1e-6) * 0.01  # the first tick at or after k/30
    np.testing.assert_allclose(taken, expected, atol=1e-12)
    assert [time for _, time in released] == taken[:len(released)]  # each once, in order
    for t, time in released:
        assert t >= time + 0.05 - 1e-9 and t < time + 0.05 + 0.01  # at the first tick after the delay
    assert taken[-1] > released[-1][1]  # the last frames are still on their way


def test_a_slow_control_loop_takes_a_frame_every_tick_without_bursts() -> None:
    spec = CameraSpec(position=(0, 0, 3), look_at=(0, 0, 0), width=4, height=4, rate=200.0)
    camera = DepthCamera(spec, load_robot("point"))
    render = Counter(spec)
    times = [camera.tick(k * 0.02, render, np.zeros(2)).time for k in range(10)]
    np.testing.assert_allclose(times, np.arange(10) * 0.02)
    assert render.calls == 10


def test_depth_noise_is_gaussian_with_the_given_sigma_and_seeded() -> None:
    robot = load_robot("point")
    spec = CameraSpec(position=(0, 0, 3), look_at=(0, 0, 0), width=200, height=150, noise=0.01)
    depth = Counter(spec, 2.0).image
    camera = DepthCamera(spec, robot, seed=4)
    clean = camera.frame(0.0, depth, np.zeros(2)).points  # a sensor's image is taken as it is
    np.testing.assert_allclose(3.0 - clean[:, 2], 2.0, atol=1e-6)
    points = camera.frame(0.0, camera.sensed(depth), np.zeros(2)).points
    measured = 3.0 - points[:, 2]  # the depth along the optical axis (−z)
    assert measured.mean() == pytest.approx(2.0, abs=4 * 0.01 / math.sqrt(measured.size))
    assert measured.std() == pytest.approx(0.01, rel=0.02)
    assert abs(float(np.mean(((measured - 2.0) / 0.01) ** 3))) < 0.05  # symmetric
    assert np.mean(((measured - 2.0) / 0.01) ** 4) == pytest.approx(3.0, abs=0.1)  # Gaussian tails
    again, other = (DepthCamera(spec, robot, seed=seed) for seed in (4, 5))
    again, other = (camera.frame(0.0, camera.sensed(depth), np.zeros(2)).points for camera in (again, other))
    np.testing.assert_array_equal(points, again)
    assert not np.array_equal(points, other)


def test_pixels_without_a_return_give_no_points() -> None:
    spec = CameraSpec(position=(0, 0, 3), look_at=(0, 0, 0), width=4, height=3)
    depth = np.array([[1.0, np.inf, np.nan, 0.0], [-1.0, 2.0, 2.0, 2.0], [2.0, 2.0, 2.0, np.inf]],
                     dtype=np.float32)
    frame = DepthCamera(spec, load_robot("point")).frame(0.0, depth, np.zeros(2))
    assert len(frame.points) == 7
    with pytest.raises(ValueError, match=r"depth image: expected shape \(3, 4\), got \(4, 3\)"):
        DepthCamera(spec, load_robot("point")).frame(0.0, depth.T, np.zeros(2))


def test_the_model_carries_the_camera_and_a_large_enough_buffer(panda: Robot) -> None:
    spec = CameraSpec(position=(1.0, 1.0, 1.0), look_at=(0.0, 0.0, 0.5), width=1600, height=900, fov=45)
    model = build_scene(panda, cameras=[spec]).model
    camera = model.camera("depth_camera0")
    assert model.cam_fovy[camera.id] == pytest.approx(45.0)
    np.testing.assert_allclose(model.cam_pos[camera.id], spec.position)
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, model.cam_quat[camera.id])
    np.testing.assert_allclose(rotation.reshape(3, 3), spec.rotation, atol=1e-9)
    assert (model.vis.global_.offwidth, model.vis.global_.offheight) == (1600, 900)


@pytest.mark.parametrize(("field", "value", "message"), [
    ("width", 0, r"width: must be a whole number of pixels > 0, got 0"),
    ("height", -3, r"height: must be a whole number of pixels > 0, got -3"),
    ("width", 3.5, r"width: must be a whole number of pixels > 0, got 3.5"),
    ("fov", 0.0, r"fov: must lie in \(0, 180\) degrees, got 0.0"),
    ("fov", 180.0, r"fov: must lie in \(0, 180\) degrees, got 180.0"),
    ("fov", float("nan"), r"fov: expected a finite number, got nan"),
    ("rate", 0.0, r"rate: must be > 0 Hz, got 0.0"),
    ("rate", -30, r"rate: must be > 0 Hz, got -30"),
    ("noise", -0.001, r"noise: must be >= 0, got -0.001"),
    ("delay", -0.1, r"delay: must be >= 0, got -0.1"),
    ("delay", "soon", r"delay: expected a number, got 'soon'"),
    ("position", (0.0, float("nan"), 1.0), r"position\[1\]: expected a finite number, got nan"),
    ("look_at", (0.0, 1.0, float("inf")), r"look_at\[2\]: expected a finite number, got inf"),
    ("position", (1.0, 2.0), r"position: expected three numbers \[x, y, z\], got 2"),
    ("look_at", (1.0, 1.0, 1.0), r"look_at: must differ from position, both are \[1.0, 1.0, 1.0\]"),
])
def test_bad_camera_fields_are_refused_naming_the_field(field: str, value: object, message: str) -> None:
    fields = {"position": (1.0, 1.0, 1.0), "look_at": (0.0, 0.0, 0.0), field: value}
    with pytest.raises(CameraSpecError, match=f"^{message}$"):
        CameraSpec(**fields)


def test_a_vertical_view_has_a_right_handed_frame_with_image_up_along_y() -> None:
    rotation = CameraSpec(position=(0, 0, 2), look_at=(0, 0, 0)).rotation
    np.testing.assert_allclose(rotation, np.eye(3), atol=1e-12)
    oblique = CameraSpec(position=(1, 2, 3), look_at=(0, 0.5, 0)).rotation
    np.testing.assert_allclose(oblique.T @ oblique, np.eye(3), atol=1e-12)
    assert np.linalg.det(oblique) == pytest.approx(1.0)
    assert oblique[2, 1] > 0  # image up points up in the world
    assert oblique[2, 0] == pytest.approx(0.0, abs=1e-12)  # image right is horizontal


def test_a_moving_sphere_is_seen_where_it_is_at_the_frames_time(panda: Robot) -> None:
    """A mocap sphere: the points of the frame taken at t lie on the sphere's surface at t."""
    spec = CameraSpec(position=(3.0, -1.5, 1.0), look_at=(3.0, 0.0, 0.5), width=160, height=120)
    scene = build_scene(panda, [SceneObstacle(Sphere(0.1), (3.0, 0.0, 0.5), IDENTITY, True)], cameras=[spec])
    data = mujoco.MjData(scene.model)
    renderer = MujocoDepthRenderer(scene.model, spec)
    camera = DepthCamera(spec, panda)
    for x in (2.8, 3.0, 3.2):
        data.mocap_pos[scene.mocap[0]] = (x, 0.0, 0.5)
        mujoco.mj_forward(scene.model, data)
        points = camera.frame(0.0, renderer.render(data), panda.default_q).points
        np.testing.assert_allclose(np.linalg.norm(points - (x, 0.0, 0.5), axis=1), 0.1, atol=2e-3)
    renderer.close()


def test_the_panda_rendered_by_its_meshes_is_filtered_out_by_its_spheres(panda: Robot) -> None:
    """Under MuJoCo the built-in Panda collides, and is seen, by Franka's meshes, which the
    fitted spheres cover to within millimetres: at ten configurations nothing of it remains
    with the default 2 cm margin, while without a margin its mesh surfaces poke through."""
    from dynfab.robots.builtin_meshes import builtin_collision_meshes

    meshes = builtin_collision_meshes(panda)
    if meshes is None:
        pytest.skip("example-robot-data is not installed: the Panda has no meshes")
    spec = CameraSpec(position=(1.6, -1.4, 1.4), look_at=(0.0, -0.3, 0.45), width=160, height=120, fov=70)
    scene = build_scene(panda, (), link_meshes=meshes, cameras=[spec])
    data = mujoco.MjData(scene.model)
    renderer = MujocoDepthRenderer(scene.model, spec)
    rng = np.random.default_rng(0)
    kinematics = panda.kinematics
    left, bare = [], []
    for k in range(10):
        q = np.clip(panda.default_q + (rng.uniform(-0.6, 0.6, 7) if k else 0.0), kinematics.lower, kinematics.upper)
        data.qpos[scene.joint_qpos] = q
        mujoco.mj_forward(scene.model, data)
        depth = renderer.render(data)
        left.append(len(DepthCamera(spec, panda).frame(0.0, depth, q).points))
        bare.append(len(DepthCamera(spec, panda, margin=0.0).frame(0.0, depth, q).points))
    renderer.close()
    assert left == [0] * 10
    assert min(bare) > 0
