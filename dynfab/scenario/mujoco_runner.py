"""The MuJoCo branch of :func:`dynfab.scenario.runner.run_scenario`.

Builds the robot and the scenario's obstacles into a MuJoCo model
(:mod:`dynfab.sim.mujoco_model`) and runs the controller in it
(:mod:`dynfab.sim.mujoco_sim`) with the scenario's ``control``, ``delay`` and ``noise``.
A robot measured by collision meshes collides by its meshes, with the link pairs its mesh
model checks for self-collision: a URDF robot by its own, the built-in ``panda`` and
``boxer-panda`` by Franka's (:mod:`dynfab.robots.builtin_meshes`), so that MuJoCo's contacts,
between two links as with an obstacle, are those of the meshes the metrics measure. The
others collide by their collision spheres and sphere pairs.

Under ``perception: camera`` the scenario's camera is a ``<camera>`` of the model; after
every control period (and at t = 0) the controller (:class:`~dynfab.scenario.camera_controller.CameraController`)
is given the chance to take a frame: MuJoCo renders its depth image then
(:class:`~dynfab.sim.depth_render.MujocoDepthRenderer`), with the robot at its true
configuration of that instant.
"""

from __future__ import annotations

import dataclasses

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.link_meshes import LinkMeshError
from dynfab.robots.mesh_collision import MeshCollisionModel
from dynfab.robots.robot import Robot
from dynfab.scenario.camera_controller import CameraController
from dynfab.scenario.fields import ScenarioError
from dynfab.scenario.schema import Scenario
from dynfab.sim.simulator import Controller, ProgressCallback

if TYPE_CHECKING:
    import mujoco

    from dynfab.sim.depth_render import MujocoDepthRenderer
    from dynfab.sim.mujoco_model import MujocoScene
    from dynfab.sim.mujoco_state import RobotState
    from dynfab.sim.mujoco_sim import MujocoRun, StepObserver

__all__ = ["run_mujoco"]

ObstacleCentres = Callable[[np.ndarray], np.ndarray]


def run_mujoco(scenario: Scenario, robot: Robot, controller: Controller, centres: ObstacleCentres,
               mesh_model: MeshCollisionModel | None, progress: ProgressCallback | None = None,
               observer: StepObserver | None = None) -> MujocoRun:
    """Simulate ``scenario`` under MuJoCo (imported here: ``mujoco`` is an optional extra).

    Args:
        scenario: The scenario, validated for ``robot``.
        robot: The robot.
        controller: The planner's controller.
        centres: ``times (T,) -> (T, m, 3)`` obstacle centres [m].
        mesh_model: The robot's collision meshes, or None for robots measured by spheres.
        progress: Optional ``(step, n_steps)`` callback.
        observer: Optional ``(t, data)`` callback after each control period (videos).

    Raises:
        ScenarioError: MuJoCo is not installed (``simulator``), the robot cannot be
            simulated (``robot``), or ``dt`` is not a whole number of 1 ms physics steps.
    """
    try:
        from dynfab.sim.mujoco_model import PHYSICS_TIMESTEP, MujocoModelError, SceneObstacle, build_scene
        from dynfab.sim.depth_render import MujocoDepthRenderer
        from dynfab.sim.mujoco_sim import simulate_mujoco
    except ImportError as error:
        raise ScenarioError("simulator", f"mujoco is not installed ({error.name}); pip install 'dynfab[mujoco]'") from None
    steps = scenario.dt / PHYSICS_TIMESTEP
    if abs(steps - round(steps)) > 1e-9 * steps:
        raise ScenarioError("dt", f"under MuJoCo must be a whole number of {PHYSICS_TIMESTEP * 1e3:g} ms physics "
                            f"steps, got {scenario.dt:g}")
    start = centres(np.zeros(1))[0]
    obstacles = [SceneObstacle(o.shape, tuple(float(x) for x in start[k]), o.orientation, o.trajectory is not None,
                               o.name(k)) for k, o in enumerate(scenario.obstacles)]
    pairs = () if mesh_model is None else tuple((mesh_model.links[i], mesh_model.links[j])
                                                for i, j in mesh_model.pairs)
    # the base's drive stops its set-point where the planner plans to (less the headroom), as
    # a drive's maximum speed is configured below the hardware's
    driven = dataclasses.replace(robot, limits=scenario.planning_limits(robot.limits))
    try:
        scene = build_scene(driven, obstacles, pairs, None if mesh_model is None else builtin_collision_meshes(robot),
                            cameras=() if scenario.camera is None else (scenario.camera,))
    except (MujocoModelError, LinkMeshError) as error:
        raise ScenarioError("robot", str(error).splitlines()[0]) from None
    simulation = scenario.simulation
    state = scenario.initial_state
    camera = None
    if isinstance(controller, CameraController):
        camera = _CameraObserver(controller, MujocoDepthRenderer(scene.model, controller.feed.camera.spec), scene,
                                 observer)
        observer = camera
    try:
        return simulate_mujoco(controller, scene, state.q, state.qdot, scenario.dt, scenario.duration,
                               control=simulation.control, delay=simulation.delay, noise=simulation.noise,
                               obstacle_centres=centres, progress=progress, observer=observer)
    finally:
        if camera is not None:
            camera.renderer.close()


class _CameraObserver:
    """After each control period: the camera's chance to take a frame (the robot at its true
    configuration), then the caller's observer."""

    def __init__(self, controller: CameraController, renderer: MujocoDepthRenderer, scene: MujocoScene,
                 observer: StepObserver | None) -> None:
        self.controller, self.renderer, self.scene, self.observer = controller, renderer, scene, observer
        self._state: RobotState | None = None

    def __call__(self, t: float, data: mujoco.MjData) -> None:
        if self._state is None:
            from dynfab.sim.mujoco_state import RobotState

            self._state = RobotState(self.scene, data)
        self.controller.capture(t, lambda: self.renderer.render(data), self._state.read()[0])
        if self.observer is not None:
            self.observer(t, data)
