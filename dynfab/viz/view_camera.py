"""The live view's depth camera: the scenario's camera images rendered by MuJoCo from the
view's own state.

The view simulates kinematically; for ``perception: camera`` it keeps a MuJoCo model of the
robot and the obstacles (every obstacle a mocap body, so that dragged ones move in the
camera's image too) and, when the planner's camera takes a frame
(:attr:`dynfab.viz.view_session.ViewSession.sensor`), puts the robot at ``q`` and the
obstacles where the view has them and renders the depth image. The planner's camera turns it
into points as in ``dynfab run`` (noise, the robot's pixels removed, ``delay``), and the view
shows the points the planner has.

MuJoCo is imported, and its OpenGL context made (``MUJOCO_GL=egl`` unless set), on the first
frame, in the thread that draws the view. A scene MuJoCo cannot hold (a mesh of more than
:data:`~dynfab.sim.mesh_parts.MAX_PARTS` convex parts) or a machine without offscreen OpenGL
raises :class:`CameraViewError`, which the view reports once and then shows the frustum alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from dynfab.viz.view_world import SceneState, ViewWorld

if TYPE_CHECKING:
    from dynfab.sim.depth_render import MujocoDepthRenderer
    from dynfab.sim.mujoco_state import RobotState

__all__ = ["CameraView", "CameraViewError"]


class CameraViewError(RuntimeError):
    """The camera's frames cannot be rendered here; the message says why."""


class CameraView:
    """Depth images of the scenario's camera rendered from the view's state (module docstring)."""

    def __init__(self, world: ViewWorld) -> None:
        """Raises:
            ValueError: The scenario has no camera.
        """
        if world.scenario.camera is None:
            raise ValueError("the scenario has no camera: block")
        self._world = world
        self._renderer: MujocoDepthRenderer | None = None
        self._state: RobotState | None = None
        self._mocap: tuple[int | None, ...] = ()

    def depth(self, state: SceneState) -> NDArray[np.floating]:
        """The camera's depth image (height, width) [m] of ``state`` (robot at ``state.q``,
        obstacles at ``state.obstacle_centres``); call it from one thread only.

        Raises:
            CameraViewError: MuJoCo cannot build the scene or render it here.
        """
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
        return self._renderer.render(data)

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
