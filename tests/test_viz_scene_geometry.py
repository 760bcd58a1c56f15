"""Plots and the live view show mesh obstacles, point clouds and the depth camera (issue 20
item 5): the figure holds the mesh's triangles, the cloud's points and the frustum's edges
where the scenario puts them, in bounded number; the viser scene holds the same geometry."""

from __future__ import annotations

import dataclasses
import io
import json
import math
import socket
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from matplotlib.collections import PathCollection, PolyCollection
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from scipy.spatial import cKDTree

from dynfab.geometry.mesh_distance import nearest_on_mesh
from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import quaternion_matrix
from dynfab.perception.camera_spec import CameraSpec
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import load_scenario
from dynfab.viz.plots import draw_run
from dynfab.viz.result_plot import plot_result
from dynfab.viz.scene_samples import (
    FRUSTUM_DEPTH,
    MAX_DRAWN_FACES,
    MAX_DRAWN_POINTS,
    even_subset,
    frustum_corners,
    frustum_segments,
    placed_triangles,
)

START = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785]
CAMERA = CameraSpec(position=(1.6, -1.4, 1.4), look_at=(0.0, -0.3, 0.45), width=320, height=240, fov=70.0)
TURN = (math.cos(0.3), 0.0, 0.0, math.sin(0.3))  # 0.6 rad about z


def _shelf() -> trimesh.Trimesh:
    """Two boards and a back: an open surface (not watertight), 36 triangles."""
    boards = [trimesh.creation.box(extents=(0.4, 0.8, 0.02)).apply_translation((0, 0, z)) for z in (0.0, 0.35)]
    back = trimesh.creation.box(extents=(0.02, 0.8, 0.37)).apply_translation((0.2, 0, 0.175))
    return trimesh.util.concatenate([*boards, back])


def _wall(count: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    return np.column_stack([np.full(count, -0.5), rng.uniform(-0.4, 0.4, count), rng.uniform(0.0, 0.8, count)])


def test_an_even_subset_keeps_all_or_at_most_the_bound_spread_end_to_end() -> None:
    assert even_subset(5, 10).tolist() == [0, 1, 2, 3, 4]
    subset = even_subset(1_000_000, 4000)
    assert len(subset) == 4000 and subset[0] == 0 and subset[-1] == 999_999
    assert np.ptp(np.diff(subset)) <= 1  # evenly spaced
    with pytest.raises(ValueError, match="most must be at least 1"):
        even_subset(3, 0)


def test_placed_triangles_are_the_mesh_turned_and_moved_and_bounded() -> None:
    mesh = Mesh(_shelf().vertices, _shelf().faces)
    triangles = placed_triangles(mesh, TURN, (0.7, 0.1, 0.2))
    expected = mesh.vertices[mesh.faces] @ quaternion_matrix(TURN).T + (0.7, 0.1, 0.2)
    np.testing.assert_allclose(triangles, expected)
    big = Mesh(*(lambda m: (m.vertices, m.faces))(trimesh.creation.icosphere(subdivisions=5)))  # 20480 faces
    assert len(placed_triangles(big, TURN, (0, 0, 0))) == MAX_DRAWN_FACES


def test_the_frustum_opens_by_the_field_of_view_toward_look_at() -> None:
    segments = frustum_segments(CAMERA)
    corners = frustum_corners(CAMERA)
    assert segments.shape == (8, 2, 3)
    np.testing.assert_allclose(segments[:4, 0], np.tile(CAMERA.position, (4, 1)))
    np.testing.assert_allclose(segments[:4, 1], corners)
    np.testing.assert_allclose(segments[4:, 0], corners)
    axis = np.subtract(CAMERA.look_at, CAMERA.position)
    axis /= np.linalg.norm(axis)
    centre = corners.mean(axis=0)
    np.testing.assert_allclose(centre, np.asarray(CAMERA.position) + FRUSTUM_DEPTH * axis, atol=1e-12)
    top_middle = (corners[0] + corners[1]) / 2 - CAMERA.position
    vertical = math.degrees(math.acos(top_middle @ axis / np.linalg.norm(top_middle)))
    assert vertical == pytest.approx(CAMERA.fov / 2)
    width, height = np.linalg.norm(corners[0] - corners[1]), np.linalg.norm(corners[1] - corners[2])
    assert width / height == pytest.approx(320 / 240)
    assert (corners[0] - corners[1]) @ (centre - corners[2]) > 0  # top edge above: image up has world +z
    near = CameraSpec(position=(0.0, 0.0, 1.0), look_at=(0.0, 0.1, 0.9))  # closer than FRUSTUM_DEPTH
    np.testing.assert_allclose(frustum_corners(near).mean(axis=0), near.look_at, atol=1e-12)


def _drawn_figure(cloud_points: int) -> tuple[Figure, Mesh, PointCloud, np.ndarray]:
    mesh = Mesh(_shelf().vertices, _shelf().faces)
    cloud = PointCloud(_wall(cloud_points))
    centres = np.linspace([0.6, -0.2, 0.3], [0.7, 0.1, 0.2], 50)  # a mesh moving
    figure = Figure(figsize=(16, 10))
    path = np.linspace([0.3, 0.0, 0.5], [0.4, 0.0, 0.4], 20)
    draw_run(figure, path, [(np.array([0.4, 0.0, 0.4]), 0.05)], np.zeros((50, 0, 3)), [], planar=False,
             shapes=[(mesh, TURN, centres), (cloud, (1.0, 0.0, 0.0, 0.0), np.zeros((50, 3)))], camera=CAMERA)
    figure.savefig(io.BytesIO(), format="png")  # draws: projects the 3-D collections
    return figure, mesh, cloud, centres


def test_the_run_plot_draws_the_mesh_triangles_the_cloud_and_the_frustum_where_they_are() -> None:
    figure, mesh, cloud, centres = _drawn_figure(3000)
    view, top = figure.axes[0], next(ax for ax in figure.axes if ax.get_title() == "top (x-y)")
    triangles = placed_triangles(mesh, TURN, centres[-1])
    [solid] = [c for c in view.collections if isinstance(c, Poly3DCollection)]
    assert len(solid.get_paths()) == len(mesh.faces) == 36
    [flat] = [c for c in top.collections if isinstance(c, PolyCollection) and not isinstance(c, PathCollection)]
    drawn = np.array([path.vertices[:3] for path in flat.get_paths()])
    np.testing.assert_allclose(drawn, triangles[:, :, :2])  # at the end of the mesh's track
    [scatter] = [c for c in top.collections if isinstance(c, PathCollection) and c.get_label() == "point cloud"]
    np.testing.assert_allclose(scatter.get_offsets(), cloud.points[:, :2])
    camera_lines = [line for line in top.lines if line.get_color() == "0.35" and line.get_linestyle() == "-"]
    assert len(camera_lines) == 8
    ends = np.array([line.get_xydata() for line in camera_lines])
    np.testing.assert_allclose(ends, frustum_segments(CAMERA)[:, :, :2])
    labels = top.get_legend_handles_labels()[1]
    assert {"mesh", "point cloud", "camera"} <= set(labels)


def test_a_large_cloud_is_drawn_as_a_bounded_sample_of_its_points() -> None:
    figure, _, cloud, _ = _drawn_figure(100_000)
    for ax in figure.axes[:4]:
        [scatter] = [c for c in ax.collections if isinstance(c, PathCollection) and c.get_label() == "point cloud"]
        assert len(scatter.get_offsets()) == MAX_DRAWN_POINTS
    sample = next(c for c in figure.axes[1].collections if c.get_label() == "point cloud").get_offsets()
    assert (cKDTree(cloud.points[:, :2]).query(sample)[0] == 0.0).all()  # the cloud's own points
    np.testing.assert_allclose(np.ptp(sample, axis=0), np.ptp(cloud.points[:, :2], axis=0), rtol=0.01)  # all over it


@pytest.fixture(scope="module")
def scene_files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A shelf mesh, a wall cloud, a scenario among both (``scene.yaml``) and the same with a
    camera (``camera.yaml``; a camera needs ``simulator: mujoco``)."""
    folder = tmp_path_factory.mktemp("viz")
    _shelf().export(folder / "shelf.stl")
    np.save(folder / "wall.npy", _wall(5000))
    scenario = {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 0.2,
                "initial_state": {"q": START},
                "goal": [{"type": "position", "link": "panda_hand", "position": [0.45, 0.0, 0.4], "tolerance": 0.05}],
                "obstacles": [{"type": "mesh", "file": "shelf.stl", "position": [0.95, 0.0, 0.25], "orientation": TURN},
                              {"type": "points", "file": "wall.npy", "voxel": 0.02}]}
    (folder / "scene.yaml").write_text(json.dumps(scenario))
    camera = {"position": list(CAMERA.position), "look_at": list(CAMERA.look_at), "fov": CAMERA.fov}
    (folder / "camera.yaml").write_text(json.dumps({**scenario, "simulator": "mujoco", "camera": camera}))
    return folder


def test_a_run_among_a_mesh_and_a_cloud_plots_both_and_its_camera(scene_files: Path, tmp_path: Path) -> None:
    scenario = load_scenario(scene_files / "scene.yaml")
    result = run_scenario(scenario)
    seen = dataclasses.replace(result, scenario=dataclasses.replace(result.scenario, camera=CAMERA))
    figure = plot_result(seen, tmp_path / "run.png")
    assert (tmp_path / "run.png").stat().st_size > 0
    view, top = figure.axes[0], figure.axes[1]
    assert any(isinstance(c, Poly3DCollection) and len(c.get_paths()) == 36 for c in view.collections)
    cloud = scenario.obstacles[1].cloud
    [scatter] = [c for c in top.collections if c.get_label() == "point cloud"]
    np.testing.assert_allclose(scatter.get_offsets(), cloud.points[:, :2])
    assert "camera" in top.get_legend_handles_labels()[1]


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_the_live_view_holds_the_mesh_the_cloud_and_the_frustum(scene_files: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    """The nodes' geometry is the scenario's; the view's camera renders the mesh (MuJoCo
    holds it), and the points of its image drawn lie on the mesh."""
    viser = pytest.importorskip("viser")
    from dynfab.perception.depth_camera import DepthCamera
    from dynfab.viz.robot_visuals import robot_look
    from dynfab.viz.view_camera import CameraView
    from dynfab.viz.view_scene import ViewScene
    from dynfab.viz.view_world import ViewWorld

    world = ViewWorld(load_scenario(scene_files / "camera.yaml"))
    server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    camera_view = CameraView(world)
    try:
        scene = ViewScene(server, world, robot_look(world.robot), obstacle_dragged=lambda k, p: None)
        mesh_node, cloud_node = scene.obstacle_shapes
        mesh, cloud = world.scenario.obstacles[0].mesh, world.scenario.obstacles[1].cloud
        np.testing.assert_allclose(mesh_node.vertices, mesh.vertices, atol=1e-6)
        np.testing.assert_array_equal(mesh_node.faces, mesh.faces)
        np.testing.assert_allclose(mesh_node.wxyz, TURN, atol=1e-12)
        np.testing.assert_allclose(scene.obstacle_handles[0].position, (0.95, 0.0, 0.25))
        assert set(scene.obstacle_handles) == {0}  # a cloud is static for the planner: no handle
        np.testing.assert_allclose(cloud_node.points, cloud.points, atol=1e-6)
        assert cloud_node.point_size == pytest.approx(0.02)
        frustum = scene.camera
        assert frustum is not None and frustum.fov == pytest.approx(math.radians(CAMERA.fov))
        assert frustum.aspect == pytest.approx(320 / 240)
        np.testing.assert_allclose(frustum.position, CAMERA.position)
        np.testing.assert_allclose(_browser_corners(frustum), frustum_corners(CAMERA), atol=1e-9)
        assert world.scenario.camera is not None
        depth = camera_view.depth(world.state(0.0, np.array(START)))
        scene.show_camera_points(DepthCamera(world.scenario.camera, world.robot).frame(0.0, depth, START).points)
        assert scene.camera_points is not None
        # MuJoCo holds the mesh (the cloud is no solid, nothing renders it): every point is on the shelf
        local = (np.asarray(scene.camera_points.points, dtype=float) - (0.95, 0.0, 0.25)) @ quaternion_matrix(TURN)
        assert len(local) > 100 and nearest_on_mesh(mesh, local).distances.max() < 5e-3
    finally:
        camera_view.close()
        server.stop()


def _browser_corners(frustum: object) -> np.ndarray:
    """The far corners of a viser frustum as its browser client draws them
    (client/src/CameraFrustumVariants.tsx: the pyramid of unit depth normalised to a fixed
    volume, then scaled; OpenCV axes) in the world, ordered as :func:`frustum_corners`."""
    y = math.tan(frustum.fov / 2.0)
    x = y * frustum.aspect
    volume = (x * y / 3.0) ** (1.0 / 3.0)
    x, y, z = (frustum.scale * v / volume for v in (x, y, 1.0))
    local = np.array([[x, -y, z], [-x, -y, z], [-x, y, z], [x, y, z]])  # OpenCV: y down
    w, *vector = frustum.wxyz
    return local @ quaternion_matrix((w, *vector)).T + np.asarray(frustum.position)


def test_the_live_views_planner_knows_the_scene_only_through_its_camera(tmp_path: Path) -> None:
    """With ``perception: camera`` the view's planner is fed by the camera rendered from the
    view's state, as in a run: the robot holds still until the first frame reaches the
    planner ``delay`` later, the points it has lie on the sphere in view (none on the robot),
    a sphere moved (as a drag does) is known where it was moved to only once a later frame
    has arrived, and the running live view shows the planner's points."""
    viser = pytest.importorskip("viser")
    from dynfab.viz.robot_visuals import robot_look
    from dynfab.viz.view_camera import CameraView
    from dynfab.viz.view_server import LiveView
    from dynfab.viz.view_session import ViewSession

    ball = np.array([0.5, -0.4, 0.5])
    scenario = {"robot": "panda", "planner": "dynamic-fabric", "dt": 0.01, "duration": 1.0, "simulator": "mujoco",
                "initial_state": {"q": START}, "perception": "camera",
                "goal": [{"type": "position", "link": "panda_hand", "position": [0.45, 0.0, 0.4], "tolerance": 0.05}],
                "obstacles": [{"type": "sphere", "radius": 0.1, "position": ball.tolist()}],
                "camera": {"position": [1.6, -1.4, 1.4], "look_at": [0.3, -0.2, 0.45], "width": 160, "height": 120,
                           "fov": 60, "rate": 10, "delay": 0.05}}
    (tmp_path / "camera.yaml").write_text(json.dumps(scenario))
    session = ViewSession(load_scenario(tmp_path / "camera.yaml"))
    assert session.planners == ("dynamic-fabric", "static-fabric")  # the MPC would know the sphere exactly
    camera_view = CameraView(session.world)
    session.sensor = camera_view.depth
    try:
        while session.t < 0.045:  # the first frame (t = 0) reaches the planner at 0.05 s
            assert session.step()
        assert session.perceived_points() is None
        np.testing.assert_array_equal(session.q, START)
        while session.t < 0.095:
            assert session.step()
        seen = session.perceived_points()
        assert seen is not None and len(seen) > 100
        assert np.abs(np.linalg.norm(seen - ball, axis=1) - 0.1).max() < 0.005
        assert np.linalg.norm(session.q - START) > 0.0  # it moves once it knows its scene
        moved = ball + [0.0, 0.1, 0.0]
        session.move_obstacle(0, moved)  # there one period later: seen at 0.2 s, known at 0.25 s
        while session.t < 0.245:
            assert session.step()
        assert np.abs(np.linalg.norm(session.perceived_points() - ball, axis=1) - 0.1).max() < 0.005
        while session.t < 0.255:
            assert session.step()
        assert np.abs(np.linalg.norm(session.perceived_points() - moved, axis=1) - 0.1).max() < 0.005
    finally:
        camera_view.close()
    world = session.world
    live = LiveView(ViewSession(world.scenario), robot_look(world.robot), _free_port())
    assert live.session.sensor is not None
    live.start()  # frames are rendered in the loop's thread, where MuJoCo's context lives
    try:
        for _ in range(600):
            if live._scene.camera_points is not None:
                break
            time.sleep(0.1)
        seen = np.array(live._scene.camera_points.points, dtype=float)
        assert len(seen) > 100 and np.abs(np.linalg.norm(seen - ball, axis=1) - 0.1).max() < 0.005
        for _ in range(600):  # three more frames
            if live.session.t >= 0.35 or not live._thread.is_alive():
                break
            time.sleep(0.1)
        assert live.session.t >= 0.35, live.session.message
        assert live._thread.is_alive()  # rendering in the loop's thread raised nothing
    finally:
        live.stop()
