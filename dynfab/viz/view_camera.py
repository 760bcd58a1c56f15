"""What the scenario's depth camera sees, for the live view: its frames rendered by MuJoCo
from the view's own state.

The view simulates kinematically; to show the camera's points it keeps a MuJoCo model of
the robot and the obstacles (every obstacle a mocap body, so that dragged ones move in the
camera's image too) and, whenever a frame is due at the camera's ``rate`` of the view's
time, puts the robot at ``q`` and the obstacles where the view has them, renders the depth
image and turns it into points as the planner's camera does
(:class:`~dynfab.perception.depth_camera.DepthCamera`: noise, the robot's pixels removed).
The points shown are the frame's, without its ``delay``; the view's planner is not fed them.
When the view's time goes back (a reset), the camera's schedule starts again.

MuJoCo is imported, and its OpenGL context made (``MUJOCO_GL=egl`` unless set), on the first
frame, in the thread that draws the view. A scene MuJoCo cannot hold (a mesh of more than
:data:`~dynfab.sim.mesh_parts.MAX_PARTS` convex parts) or a machine without offscreen OpenGL
raises :class:`CameraViewError`, which the view reports once and then shows the frustum alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.perception.depth_camera import DepthCamera
from dynfab.viz.view_world import SceneState, ViewWorld

if TYPE_CHECKING:
    from dynfab.sim.depth_render import MujocoDepthRenderer
    from dynfab.sim.mujoco_state import RobotState

__all__ = ["CameraView", "CameraViewError"]


class CameraViewError(RuntimeError):
    """The camera's frames cannot be rendered here; the message says why."""


class CameraView:
    """Frames of the scenario's camera taken from the view's state (module docstring).

    Attributes:
        camera: The frames' camera (its rate, noise and robot filter).
    """

    def __init__(self, world: ViewWorld) -> None:
        """Raises:
            ValueError: The scenario has no camera.
        """
        if world.scenario.camera is None:
            raise ValueError("the scenario has no camera: block")
        self._world = world
        self.camera = DepthCamera(world.scenario.camera, world.robot)
        self._renderer: MujocoDepthRenderer | None = None
        self._state: RobotState | None = None
        self._mocap: tuple[int | None, ...] = ()
        self._last = -np.inf

    def points(self, state: SceneState) -> NDArray[np.float64] | None:
        """The points (N, 3) [m] of a frame taken at ``state.t`` if one is due, else None.

        Raises:
            CameraViewError: MuJoCo cannot build the scene or render it here.
        """
        if state.t < self._last:  # the view was reset: frames are due from its new time on
            self.camera = DepthCamera(self.camera.spec, self._world.robot)
        self._last = state.t
        if not self.camera.due(state.t):
            return None
        if self._renderer is None:
            self._open()
        assert self._state is not None and self._renderer is not None
        data = self._state.data
        self._state.write(np.asarray(state.q, dtype=float), np.zeros(self._world.robot.dof))
        for k, index in enumerate(self._mocap):
            if index is not None:
                data.mocap_pos[index] = state.obstacle_centres[k]
        import mujoco

        mujoco.mj_forward(self._state.scene.model, data)
        renderer = self._renderer
        frame = self.camera.tick(state.t, lambda: renderer.render(data), state.q)
        return None if frame is None else np.asarray(frame.points)

    def close(self) -> None:
        """Free the OpenGL context (if one was made)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def _open(self) -> None:
        """Build the MuJoCo scene and its renderer (module docstring)."""
        from dynfab.viz.mujoco_video import prepare_headless_rendering

        prepare_headless_rendering()
        try:
            import mujoco

            from dynfab.robots.builtin_meshes import builtin_collision_meshes
            from dynfab.sim.depth_render import MujocoDepthRenderer
            from dynfab.sim.mujoco_model import SceneObstacle, build_scene
            from dynfab.sim.mujoco_state import RobotState
        except ImportError as error:
            raise CameraViewError(f"mujoco is not installed ({error.name})") from None
        world = self._world
        centres = world.obstacle_centres(0.0)
        obstacles = [SceneObstacle(o.shape, tuple(float(x) for x in centres[k]), o.orientation, True)
                     for k, o in enumerate(world.scenario.obstacles)]
        camera = world.scenario.camera
        assert camera is not None
        try:
            scene = build_scene(world.robot, obstacles, (), builtin_collision_meshes(world.robot), cameras=(camera,))
            self._renderer = MujocoDepthRenderer(scene.model, camera)
        except Exception as error:  # MuJoCo's compiler and OpenGL raise many kinds of errors
            first = str(error).splitlines()[0] if str(error) else type(error).__name__
            raise CameraViewError(first) from None
        self._state = RobotState(scene, mujoco.MjData(scene.model))
        self._mocap = scene.mocap
