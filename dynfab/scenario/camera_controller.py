"""A scenario's controller under ``perception: camera``: the planner knows the scene only
through a depth camera.

The controller is the scenario's own (:func:`~dynfab.scenario.guided_controller.make_scenario_controller`:
guided, or the plain fabric with stall recovery) built as if the scene were empty, plus the
nearest-point leaf, which a :class:`~dynfab.perception.camera_feed.CameraFeed` writes every
tick from the camera's latest cloud (the robot filtered out, velocities for a dynamic
fabric). The file's obstacles stay in the physics and the metrics. The MuJoCo loop calls
:meth:`CameraController.capture` after every control period (the camera renders when a
frame is due); frames reach the planner ``delay`` later.

What moves is also tracked: each cluster of the cloud faster than :data:`MIN_SPEED`
(:meth:`~dynfab.perception.motion_tracks.ClusterTracker.moving`, fastest first) takes one of
:data:`TRACKED_SLOTS` sphere obstacle slots of the planner, as the ball that holds what was
seen of it, moved to the current time at its estimated velocity (which a dynamic fabric is
given too); free slots are inactive (radius 0). Where the ``fabric:`` block leaves them unset,
these slots keep the plain fabric's obstacle barrier (:data:`TRACKED_BARRIER`: range 0.2 m,
``λ`` 0.5) under guidance too, whose own obstacle barrier (range 0.1 m) is made for a scene
its plan already avoids, not for a ball coming at 0.5 m/s. The paper's dynamic fabrics avoid tracked
obstacles that way, and the nearest-point leaf alone did not keep a ball thrown at
0.5 m/s off the hand, even fed the ball's true surface and velocity.

Until the first frame has arrived the robot knows nothing of its scene and holds still
(q̈ = 0; it starts at rest). Guidance plans its first path at the first frame, and its
plans avoid the latest frame's points as renewed every :data:`GUIDANCE_PERIOD`, each
extended :data:`BEHIND` away from the camera (:func:`~dynfab.perception.occlusion.behind_surfaces`:
what lies behind a seen surface is unknown, so a plan must not route the arm through the
unseen back of an obstacle), at 1 cm voxels.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance
from dynfab.fabric.planner import FabricPlanner
from dynfab.geometry.shapes import Placement
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.geometry.point_cloud import PointCloud
from dynfab.perception.camera_feed import CameraFeed
from dynfab.perception.occlusion import behind_surfaces
from dynfab.perception.depth_camera import DepthCamera, DepthRender
from dynfab.perception.workspace import robot_workspace
from dynfab.robots.robot import Robot
from dynfab.scenario.guided_controller import GuidedController, make_scenario_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.fabric_schema import BarrierSpec
from dynfab.scenario.obstacle_schema import ObstacleSpec
from dynfab.scenario.schema import Scenario

__all__ = ["BEHIND", "GUIDANCE_PERIOD", "MIN_SPEED", "TRACKED_BARRIER", "TRACKED_SLOTS", "CameraController", "blind_scenario",
           "camera_feed", "make_camera_controller"]

#: How far behind the seen surfaces the global planner takes space as solid [m] (the
#: diameter of Experiment 1's spheres), and the step of that extension [m].
BEHIND, BEHIND_STEP = 0.3, 0.03
#: How often the global planner's cloud is renewed [s] (its plans are made at the first frame
#: and when the robot stalls; a grid is built per plan).
GUIDANCE_PERIOD = 0.5
#: Sphere obstacle slots for tracked moving clusters.
TRACKED_SLOTS = 3
#: A cluster slower than this [m/s] is not tracked as moving (static clutter reads a few cm/s).
MIN_SPEED = 0.1
#: The tracked slots' barrier where the scenario's ``fabric.obstacle`` leaves it unset: the
#: plain fabric's defaults (:class:`~dynfab.fabric.leaves.obstacle.SphereObstacleAvoidance`).
TRACKED_BARRIER = BarrierSpec(energy_gain=0.5, range=0.2)
#: What holds a tracked slot's place in the scenario the controller is built from: a 1 mm
#: sphere 100 m below the robot (the slots are written every tick).
_SLOT = ObstacleSpec(type="sphere", radius=1e-3, position=(0.0, 0.0, -100.0))


class CameraController:
    """The scenario's controller fed by a depth camera (module docstring).

    Attributes:
        inner: The scenario's controller, built for an empty scene.
        feed: The camera and what it writes into the planner.
    """

    def __init__(self, inner: Any, feed: CameraFeed) -> None:
        self.inner = inner
        self.feed = feed
        self._guidance_due = 0.0

    def __getattr__(self, name: str) -> Any:
        """The inner controller's attributes (status, solver times, ... for the metrics)."""
        if name in ("inner", "feed", "_guidance_due"):
            raise AttributeError(name)
        return getattr(self.inner, name)

    def capture(self, t: float, render: DepthRender, q: NDArray[np.float64]) -> None:
        """After a control period: the camera takes a frame at ``t`` [s] if one is due."""
        self.feed.capture(t, render, q)

    def __call__(self, t: float, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> NDArray[np.float64]:
        planner: FabricPlanner = self.inner.planner
        leaf = next(leaf for leaf in planner.config.leaves if isinstance(leaf, NearestSurfaceAvoidance))
        self.feed.attach(leaf, planner.parameters.leaves[leaf.name])
        self.feed.write(t, q, planner.config.dynamic)
        if self.feed.latest is None:
            return np.zeros_like(qdot)
        self._track(t, planner)
        if isinstance(self.inner, GuidedController) and t >= self._guidance_due:
            self._guidance_due = t + GUIDANCE_PERIOD
            self.inner.guided.set_obstacles(self._guidance_obstacles())
        return self.inner(t, q, qdot)


    def _guidance_obstacles(self) -> tuple[PlacedObstacle, ...]:
        """The latest frame's points, extended behind the seen surfaces, as one cloud."""
        frame = self.feed.latest
        assert frame is not None
        if len(frame.points) == 0:
            return ()
        solid = behind_surfaces(frame.points, self.feed.camera.spec.position, BEHIND, BEHIND_STEP)
        cloud = PointCloud.from_points(solid, source="camera")
        return (PlacedObstacle(cloud, Placement((0.0, 0.0, 0.0))),)

    def _track(self, t: float, planner: FabricPlanner) -> None:
        """Write the fastest moving clusters into the sphere slots, the others inactive."""
        params = planner.parameters
        moving = self.feed.tracker.moving(MIN_SPEED)[:TRACKED_SLOTS]
        for k in range(TRACKED_SLOTS):
            if k < len(moving):
                params.obstacle_position[k] = moving[k].at(t)
                params.obstacle_radius[k] = moving[k].radius
                velocity = moving[k].velocity
            else:
                params.obstacle_radius[k] = 0.0
                velocity = np.zeros(3)
            if planner.config.dynamic:
                params.obstacle_velocity[k] = velocity


def make_camera_controller(scenario: Scenario, robot: Robot, seed: int = 0) -> CameraController:
    """The controller of a ``perception: camera`` scenario (validated for ``robot``)."""
    blind = blind_scenario(scenario)
    inner = make_scenario_controller(blind, robot, scenario_references(blind, robot))
    return CameraController(inner, camera_feed(scenario, robot, seed))


def blind_scenario(scenario: Scenario) -> Scenario:
    """What the inner controller of a ``perception: camera`` scenario is built from: no
    obstacles but the :data:`TRACKED_SLOTS` sphere slots, whose barrier is the scenario's
    ``fabric.obstacle`` with :data:`TRACKED_BARRIER` where it leaves a value unset."""
    barrier = scenario.fabric.obstacle
    tracked = BarrierSpec(gain=barrier.gain, energy_gain=TRACKED_BARRIER.energy_gain if barrier.energy_gain is None
                          else barrier.energy_gain, range=TRACKED_BARRIER.range if barrier.range is None else barrier.range)
    return dataclasses.replace(scenario, obstacles=(_SLOT,) * TRACKED_SLOTS,
                               fabric=dataclasses.replace(scenario.fabric, obstacle=tracked))


def camera_feed(scenario: Scenario, robot: Robot, seed: int = 0) -> CameraFeed:
    """The scenario's camera (its noise drawn from ``seed``) and what writes its clouds into
    a planner."""
    assert scenario.camera is not None
    margin = scenario.camera_workspace_margin
    workspace = None if margin is None else robot_workspace(robot, margin)
    camera = DepthCamera(scenario.camera, robot, seed=seed, workspace=workspace)
    return CameraFeed(robot, camera, backend=scenario.backend)
