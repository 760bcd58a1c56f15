"""The viewer's 3-D scene in viser: robot meshes, collision spheres, obstacles, goals and
reference paths, updated from a :class:`~dynfab.viz.view_world.SceneState`.

Scene tree: ``/robot/L`` one frame per link L that carries meshes (its pose from the
kinematics at ``q``); ``/spheres/i`` the collision spheres (hidden until asked for);
``/obstacles/k`` and ``/goals/k`` (drag handles when ``draggable``, with the shape as a
child ``/obstacles/k/shape``, so that the browser moves the shape with the handle at once;
a mesh's triangles and a point cloud's points as :mod:`dynfab.viz.view_sensing` bounds
them; a cloud, static for the planner, gets no handle); ``/paths/...`` the reference paths
of path goals and moving obstacles over the scenario's duration; ``/camera`` the depth
camera's frustum (with ``/camera_axis`` its optical axis) and ``/camera_points`` the points
of the planner's latest camera frame (:meth:`ViewScene.show_camera_points`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.point_cloud import PointCloud
from dynfab.viz.robot_visuals import LinkPoses, RobotLook
from dynfab.viz.shape_meshes import shape_mesh
from dynfab.viz.view_sensing import CAMERA_POINTS_COLOR, MIN_POINT_SIZE, add_camera, add_cloud, add_mesh
from dynfab.viz.view_world import SceneState, ViewWorld

if TYPE_CHECKING:
    import viser

#: Colours (RGB 0..255).
OBSTACLE_COLOR = (60, 110, 230)
GOAL_COLOR = (40, 180, 70)
SPHERE_COLOR = (230, 60, 60)
PATH_SAMPLES = 200
GOAL_MARKER_RADIUS = 0.03  # [m]
HANDLE_SCALE = 0.2  # [m] length of a drag handle's arrows
CAMERA_DIRECTION = np.array([1.0, -1.2, 0.8])  # from the scene's centre to the camera
CAMERA_DISTANCE = 1.5  # times the scene's size
GRID_SIZE = 4.0  # [m]

Dragged = Callable[[int, np.ndarray], None]
"""``(index, world point)``: called when the user drags a goal or obstacle handle."""


class ViewScene:
    """The viser scene of one scenario (module docstring).

    Attributes:
        goal_handles: per draggable goal index, its drag handle (live view only).
        obstacle_handles: per obstacle index, its drag handle (live view only).
        obstacle_shapes: per obstacle, the node of its geometry (a mesh or a point cloud).
        camera: the depth camera's frustum node, or None without a camera.
        camera_points: the node of the camera's latest points, or None before a frame.
    """

    def __init__(self, server: viser.ViserServer, world: ViewWorld, look: RobotLook,
                 goal_dragged: Dragged | None = None, obstacle_dragged: Dragged | None = None) -> None:
        """Add everything to ``server``'s scene; handles call ``goal_dragged`` /
        ``obstacle_dragged`` (without them: no handles, as in a replay)."""
        self._server = server
        self._world = world
        scene = server.scene
        links = tuple(dict.fromkeys(v.link for v in look.visuals))
        self._poses = LinkPoses(world.robot, links)
        self._link_frames = [scene.add_frame(f"/robot/{link}", show_axes=False) for link in links]
        for j, visual in enumerate(look.visuals):
            scene.add_mesh_simple(f"/robot/{visual.link}/mesh{j}", np.asarray(visual.mesh.vertices, dtype=np.float32),
                                  np.asarray(visual.mesh.faces, dtype=np.uint32), color=_rgb255(visual.color))
        spheres = world.robot.collision_spheres
        self._sphere_links = LinkPoses(world.robot, tuple(s.link for s in spheres))
        self._sphere_nodes = [scene.add_icosphere(f"/spheres/{i}", radius=s.radius, color=SPHERE_COLOR, opacity=0.5,
                                                  visible=False) for i, s in enumerate(spheres)]
        self.goal_handles: dict[int, viser.TransformControlsHandle] = {}
        self.obstacle_handles: dict[int, viser.TransformControlsHandle] = {}
        self.obstacle_shapes: list[viser.SceneNodeHandle] = []
        self._obstacle_nodes = [self._add_obstacle(k, obstacle_dragged) for k in range(len(world.scenario.obstacles))]
        camera = world.scenario.camera
        self.camera = None if camera is None else add_camera(scene, "/camera", camera)
        self.camera_points: viser.PointCloudHandle | None = None
        self._goal_nodes = {k: self._add_goal(k, goal_dragged) for k in range(len(world.scenario.goals))
                            if world.draggable_goal(k)}
        self.draw_paths()
        self._frame_scene(world.state(0.0, np.asarray(world.scenario.initial_state.q)))

    def set_spheres_visible(self, visible: bool) -> None:
        for node in self._sphere_nodes:
            node.visible = visible

    def draw_paths(self) -> None:
        """(Re)draw the reference paths over the scenario's duration, offsets included."""
        times = np.linspace(0.0, self._world.scenario.duration, PATH_SAMPLES)
        for k in range(len(self._world.scenario.goals)):
            self._add_path(f"/paths/goal{k}", self._world.goal_path(k, times), GOAL_COLOR)
        for k in range(len(self._world.scenario.obstacles)):
            self._add_path(f"/paths/obstacle{k}", self._world.obstacle_path(k, times), OBSTACLE_COLOR)

    def update(self, state: SceneState, moving_only: bool) -> None:
        """Put the robot at ``state.q`` and goals and obstacles where ``state`` has them
        (with ``moving_only`` only those the scenario moves, so as not to fight a handle
        the user holds)."""
        from viser import transforms

        poses = self._poses(state.q)
        sphere_frames = self._sphere_links(state.q)
        with self._server.atomic():
            for frame, pose in zip(self._link_frames, poses):
                frame.position = pose[:3, 3]
                frame.wxyz = transforms.SO3.from_matrix(pose[:3, :3]).wxyz
            for node, sphere, pose in zip(self._sphere_nodes, self._world.robot.collision_spheres, sphere_frames):
                node.position = pose[:3, :3] @ np.asarray(sphere.center) + pose[:3, 3]
            for k, node in enumerate(self._obstacle_nodes):
                if not moving_only or self._world.obstacle_moves(k):
                    node.position = state.obstacle_centres[k]
            for k, node in self._goal_nodes.items():
                point = state.goal_points[k]
                if point is not None and (not moving_only or self._world.goal_moves(k)):
                    node.position = point

    def show_camera_points(self, points: NDArray[np.float64] | None) -> None:
        """Show ``points`` (N, 3) [m] as the camera's (the planner's latest frame); None keeps
        what is shown."""
        if points is None:
            return
        drawn = points.astype(np.float32).reshape(-1, 3)
        if self.camera_points is None:
            self.camera_points = self._server.scene.add_point_cloud(
                "/camera_points", drawn, CAMERA_POINTS_COLOR, point_size=MIN_POINT_SIZE, precision="float32")
        else:
            self.camera_points.points = drawn

    def _frame_scene(self, state: SceneState) -> None:
        """A floor grid under the robot, goals and obstacles (twice the size of the box
        around them, at least :data:`GRID_SIZE`), and the browser's camera looking at them
        from the front right and above, from :data:`CAMERA_DISTANCE` times the box's size
        (at least 1 m)."""
        points = [pose[:3, 3] for pose in self._poses(state.q)]
        points += [p for p in state.goal_points if p is not None] + list(state.obstacle_centres)
        if self._world.scenario.camera is not None:
            points.append(np.asarray(self._world.scenario.camera.position))
        low, high = np.min(points, axis=0), np.max(points, axis=0)
        centre = 0.5 * (low + high)
        size = max(float(np.max(high - low)), 1.0)
        grid = max(GRID_SIZE, 2.0 * np.ceil(size))
        self._server.scene.add_grid("/grid", width=grid, height=grid, cell_size=0.25,
                                    position=(float(np.round(centre[0])), float(np.round(centre[1])), 0.0))
        camera = self._server.initial_camera
        camera.look_at = centre
        camera.position = centre + CAMERA_DISTANCE * size * CAMERA_DIRECTION / np.linalg.norm(CAMERA_DIRECTION)

    def _anchor(self, name: str, position: np.ndarray, k: int, dragged: Dragged | None,
                handles: dict[int, viser.TransformControlsHandle]) -> viser.SceneNodeHandle:
        """The node item ``k`` hangs from: a plain frame, or with ``dragged`` a translation
        handle (in the plane for planar robots) that reports its position and is kept in
        ``handles``."""
        if dragged is None:
            return self._server.scene.add_frame(name, show_axes=False, position=position)
        planar_axes = (True, True, not self._world.robot.planar)
        node = self._server.scene.add_transform_controls(name, scale=HANDLE_SCALE, position=position,
                                                         disable_rotations=True, active_axes=planar_axes)
        node.on_update(lambda event: dragged(k, np.array(event.target.position)))
        handles[k] = node
        return node

    def _add_obstacle(self, k: int, dragged: Dragged | None) -> viser.SceneNodeHandle:
        obstacle = self._world.scenario.obstacles[k]
        centre = self._world.obstacle_centres(0.0)[k]
        planar = self._world.robot.planar and obstacle.type == "sphere"
        name = f"/obstacles/{k}"
        shape, scene, wxyz = obstacle.shape, self._server.scene, np.asarray(obstacle.orientation)
        node = self._anchor(name, centre, k, None if isinstance(shape, PointCloud) else dragged, self.obstacle_handles)
        opacity = 0.4 if obstacle.type == "plane" else 0.8
        if isinstance(shape, PointCloud):
            self.obstacle_shapes.append(add_cloud(scene, f"{name}/shape", shape, wxyz))
        elif isinstance(shape, Mesh):
            self.obstacle_shapes.append(add_mesh(scene, f"{name}/shape", shape, wxyz, OBSTACLE_COLOR, opacity))
        else:
            mesh = shape_mesh(shape, planar)
            self.obstacle_shapes.append(scene.add_mesh_simple(
                f"{name}/shape", np.asarray(mesh.vertices, dtype=np.float32), np.asarray(mesh.faces, dtype=np.uint32),
                color=OBSTACLE_COLOR, opacity=opacity, wxyz=wxyz))
        return node

    def _add_goal(self, k: int, dragged: Dragged | None) -> viser.SceneNodeHandle:
        point = self._world.goal_point(k, 0.0)
        name = f"/goals/{k}"
        node = self._anchor(name, point, k, dragged, self.goal_handles)
        tolerance = self._world.scenario.goals[k].tolerance
        self._server.scene.add_icosphere(f"{name}/marker", radius=max(GOAL_MARKER_RADIUS, tolerance),
                                         color=GOAL_COLOR, opacity=0.6)
        return node

    def _add_path(self, name: str, points: np.ndarray | None, color: tuple[int, int, int]) -> None:
        if points is None:
            return
        segments = np.stack([points[:-1], points[1:]], axis=1).astype(np.float32)
        self._server.scene.add_line_segments(name, segments, color, thickness=0.005)


def _rgb255(color: tuple[float, float, float]) -> tuple[int, int, int]:
    r, g, b = (int(round(255 * min(max(c, 0.0), 1.0))) for c in color)
    return (r, g, b)
