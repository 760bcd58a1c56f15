"""The live view's simulation, without any browser: a scenario's robot driven by a
planner in closed loop, step by step, with goals and obstacles the user moves.

Each control period ``dt`` the active controller (``dynamic-fabric``, ``static-fabric`` or
``mpc``, built by :mod:`dynfab.scenario.controllers` when first chosen) gives the command
``u̇``, held over the period and integrated by the embedded simulator's motion model
(:mod:`dynfab.sim.models`; a differential-drive base in ``BASE_SUBSTEPS`` arcs), exactly as
``dynfab run`` does with the kinematic simulator. :meth:`ViewSession.advance` runs as many
periods as wall time times the time scale asks for. The view runs past the scenario's
duration until paused; it uses the kinematic simulator whatever the scenario's
``simulator`` says, and no stall recovery.

Moving a goal or an obstacle (:meth:`ViewSession.move_goal`) writes the new reference into
the running planner's parameters at once (:meth:`FabricController.retarget`); the MPC uses
it from its next solve.

With ``perception: camera`` the planner knows the scene only through the scenario's camera,
as in ``dynfab run`` (:class:`~dynfab.scenario.camera_controller.CameraController` around the
view's fabric, without guidance): at the start of every period the camera takes a frame if
one is due, rendered by :attr:`ViewSession.sensor` from the view's state (the robot at ``q``,
dragged obstacles where they were dragged to), and its points reach the planner ``delay``
later. A moved obstacle is therefore known only once the camera has seen it; without a
sensor the planner sees nothing and holds still. The MPC is not offered.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from numpy.typing import NDArray

from dynfab.motion.references import References
from dynfab.mpc import MpcController
from dynfab.robots.robot import Robot
from dynfab.scenario.camera_controller import CameraController, blind_scenario, camera_feed
from dynfab.scenario.controllers import Controller, FabricController, make_controller, planner_references
from dynfab.scenario.metrics import clearance_over_time, shape_clearance_over_time
from dynfab.scenario.references import goal_axes, scenario_references
from dynfab.scenario.runner import BASE_SUBSTEPS
from dynfab.scenario.schema import Scenario, ScenarioError
from dynfab.sim import RunStopped, motion_model_for
from dynfab.viz.view_world import SceneState, ViewWorld

#: Planners the view offers; ``mpc`` only for scenarios whose obstacles are all spheres.
VIEW_PLANNERS = ("dynamic-fabric", "static-fabric", "mpc")
#: Most simulated time one :meth:`ViewSession.advance` runs [s]; a slower planner makes the
#: view run slower than real time instead of piling up work.
MAX_ADVANCE = 0.1
#: Controller calls averaged in the step time.
STEP_TIME_WINDOW = 100


@dataclass(frozen=True)
class ViewStatus:
    """The panel's numbers.

    Attributes:
        t: simulated time [s].
        planner: the active planner.
        clearance: smallest distance between robot spheres and obstacles now [m] (inf
            without obstacles; negative: in collision).
        goal_distance: distance of the primary goal's point (or configuration) to its
            reference now [m or rad]; None for an axis goal.
        step_time_ms: mean wall time of the last controller calls [ms] (nan before any).
        message: why the simulation stopped, or "" while it runs.
    """

    t: float
    planner: str
    clearance: float
    goal_distance: float | None
    step_time_ms: float
    message: str = ""


class ViewSession:
    """A scenario simulated live (module docstring).

    Attributes:
        world: robot, scenario and the references with the user's offsets.
        planner: the active planner's name.
        time_scale: simulated seconds per wall second (> 0).
        playing: False while paused.
        steps: control periods run since the start; q, qdot: the robot's state
            (velocity coordinates).
        message: why the simulation stopped ("" while it can run).
        sensor: ``perception: camera`` only: renders the camera's depth image [m] of a scene
            state (the live view sets it: :meth:`dynfab.viz.view_camera.CameraView.depth`);
            None: the planner sees nothing.
    """

    def __init__(self, scenario: Scenario, robot: Robot | None = None) -> None:
        """Build the robot, the references and the scenario's own planner.

        Raises:
            ScenarioError: the scenario does not fit its robot or its planner.
        """
        self.world = ViewWorld(scenario, robot)
        self.planner = self.world.scenario.planner
        self.time_scale = 1.0
        self.playing = True
        self.message = ""
        self._controllers: dict[str, Controller | CameraController] = {}
        self.sensor: Callable[[SceneState], NDArray[np.floating]] | None = None
        self._step_times: deque[float] = deque(maxlen=STEP_TIME_WINDOW)
        self._budget = 0.0
        robot = self.world.robot
        self._model = motion_model_for(robot.base is not None)
        self._substeps = 1 if robot.base is None else BASE_SUBSTEPS
        self._measures = _Measures(self.world)
        self.reset()
        self._controller(self.planner)

    @property
    def t(self) -> float:
        """Simulated time [s]: control periods run times ``dt``."""
        return self.steps * self.scenario.dt

    @property
    def robot(self) -> Robot:
        return self.world.robot

    @property
    def scenario(self) -> Scenario:
        return self.world.scenario

    @property
    def planners(self) -> tuple[str, ...]:
        """The planners this scenario can use (the MPC knows its obstacles exactly: not under
        ``perception: camera``)."""
        spheres_only = all(o.type == "sphere" for o in self.scenario.obstacles) and self.scenario.perception != "camera"
        return tuple(p for p in VIEW_PLANNERS if p != "mpc" or spheres_only)

    def reset(self) -> None:
        """Back to the initial state at t = 0 (moved goals and obstacles stay where they are)."""
        start = self.scenario.initial_state
        self.steps = 0
        self.q = np.array(start.q, dtype=float)
        self.qdot = np.array(start.qdot, dtype=float)
        self._budget = 0.0
        self.message = ""
        self._step_times.clear()
        for name, controller in self._controllers.items():
            if isinstance(controller, MpcController):  # its plan belongs to the old times
                self._controllers[name] = MpcController(controller.problem, controller.references,
                                                        controller.obstacle_radii, controller.control_period)
            elif isinstance(controller, CameraController):  # so do its frames
                self._controllers[name] = CameraController(controller.inner, camera_feed(self.scenario, self.robot))
        self._retarget()

    def switch_planner(self, name: str) -> None:
        """Drive the robot with ``name`` from the current state on (built on first use).

        Raises:
            ScenarioError: an unknown planner, or one this scenario cannot use.
        """
        if name not in self.planners:
            raise ScenarioError("planner", f"{name!r} is not available here; choose from {', '.join(self.planners)}")
        self._controller(name)
        self.planner = name
        self._step_times.clear()
        self._retarget()

    def move_goal(self, k: int, point: np.ndarray) -> None:
        """Put goal ``k`` at the world point ``point`` (3,) [m] now; the planner follows."""
        self.world.move_goal(k, point, self.t)
        self._retarget()

    def move_obstacle(self, k: int, point: np.ndarray) -> None:
        """Put obstacle ``k``'s centre at ``point`` (3,) [m] now; the planner avoids it there."""
        self.world.move_obstacle(k, point, self.t)
        self._retarget()

    def restore_references(self) -> None:
        """Every goal and obstacle back on its scenario reference, for the planner too."""
        self.world.clear_offsets()
        self._retarget()

    def step(self) -> bool:
        """One control period; False (and :attr:`message` says why) if the run stopped."""
        if self.message:
            return False
        controller = self._controller(self.planner)
        if isinstance(controller, CameraController) and self.sensor is not None:
            sensor = self.sensor   # the scene's state is built only when a frame is due
            controller.capture(self.t, lambda: sensor(self.scene()), self.q.copy())
        start = time.perf_counter()
        try:
            command = np.asarray(controller(self.t, self.q.copy(), self.qdot.copy()), dtype=float)
        except RunStopped as stop:
            self.message = str(stop)
            return False
        self._step_times.append(time.perf_counter() - start)
        if not np.isfinite(command).all():
            self.message = f"the {self.planner} planner returned a non-finite command at t = {self.t:.3f} s"
            return False
        h = self.scenario.dt / self._substeps
        for _ in range(self._substeps):
            self.q, self.qdot = self._model.step(self.q, self.qdot, command, h)
        self.steps += 1
        return True

    def advance(self, wall_seconds: float) -> int:
        """Simulate ``wall_seconds × time_scale`` (at most :data:`MAX_ADVANCE`) when playing;
        returns the control periods run."""
        if not self.playing:
            return 0
        dt = self.scenario.dt
        self._budget = min(self._budget + wall_seconds * self.time_scale, MAX_ADVANCE)
        steps = 0
        while self._budget >= dt and self.step():
            self._budget -= dt
            steps += 1
        return steps

    def scene(self) -> SceneState:
        """What to draw now."""
        return self.world.state(self.t, self.q)

    def perceived_points(self) -> NDArray[np.float64] | None:
        """``perception: camera``: the points (N, 3) [m] of the latest frame the planner has
        (the robot filtered out); None before the first, or without a camera."""
        controller = self._controllers.get(self.planner)
        if not isinstance(controller, CameraController) or controller.feed.latest is None:
            return None
        return np.asarray(controller.feed.latest.points, dtype=float)

    def status(self) -> ViewStatus:
        """The panel's numbers now."""
        step_ms = 1e3 * float(np.mean(self._step_times)) if self._step_times else math.nan
        return ViewStatus(self.t, self.planner, self._measures.clearance(self.q, self.world.obstacle_centres(self.t)),
                          self._measures.goal_distance(self.q, self.t), step_ms, self.message)

    def _controller(self, name: str) -> Controller | CameraController:
        """The controller of planner ``name``, built on first use (module docstring)."""
        if name not in self._controllers:
            scenario = dataclasses.replace(self.scenario, planner=name)
            if scenario.perception == "camera":
                blind = blind_scenario(scenario)
                inner = make_controller(blind, self.robot, scenario_references(blind, self.robot))
                self._controllers[name] = CameraController(inner, camera_feed(scenario, self.robot))
            else:
                self._controllers[name] = make_controller(scenario, self.robot, self.world.references())
        return self._controllers[name]

    def _retarget(self) -> None:
        """Hand the current references to the active controller (under ``perception:
        camera`` its goals only: the obstacles it knows are the camera's)."""
        controller = self._controllers.get(self.planner)
        references = planner_references(self.scenario, self.world.references())
        if isinstance(controller, CameraController):
            controller = controller.inner
            references = References(references.goals, ())
        if isinstance(controller, FabricController):
            controller.retarget(references, self.t)
        elif isinstance(controller, MpcController):
            controller.references = references


class _Measures:
    """Clearance and goal distance at one configuration (numbers for the panel)."""

    def __init__(self, world: ViewWorld) -> None:
        self._world = world
        robot, scenario = world.robot, world.scenario
        q = ca.SX.sym("q", robot.dof)
        self._radii = robot.sphere_radii
        centres = ca.reshape(robot.sphere_centers(q).T, 3 * len(self._radii), 1) if len(self._radii) else ca.SX(0, 1)
        self._centres = ca.Function("sphere_centres", [q], [centres])
        goal = scenario.goals[0] if scenario.goals else None
        self._goal = goal
        if goal is not None and goal.type in ("position", "pose", "path"):
            point = robot.kinematics.position(q, goal.link, parent=goal.parent_link, offset=goal.offset)
            self._goal_point = ca.Function("goal_point", [q], [point[goal_axes(goal, robot)]])
        obstacles = scenario.obstacles
        self._spheres = [k for k, o in enumerate(obstacles) if o.type == "sphere"]
        self._shapes = [k for k, o in enumerate(obstacles) if o.type != "sphere"]

    def clearance(self, q: np.ndarray, obstacle_centres: np.ndarray) -> float:
        obstacles = self._world.scenario.obstacles
        centres = np.array(self._centres(q)).reshape(1, -1, 3)
        planar = self._world.robot.planar
        spheres = clearance_over_time(centres, self._radii, obstacle_centres[None, self._spheres],
                                      [obstacles[k].radius for k in self._spheres], planar=planar)
        shapes = shape_clearance_over_time(centres, self._radii, [obstacles[k].shape for k in self._shapes],
                                           [obstacles[k].orientation for k in self._shapes],
                                           obstacle_centres[None, self._shapes], planar=planar)
        return float(min(spheres[0], shapes[0]))

    def goal_distance(self, q: np.ndarray, t: float) -> float | None:
        goal = self._goal
        if goal is None or goal.type == "axis":
            return None
        target = self._world.references().goals[0].evaluate(t).position
        current = q if goal.type == "joint" else np.array(self._goal_point(q)).reshape(-1)
        return float(np.linalg.norm(current - target))
