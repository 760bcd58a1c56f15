"""A scenario's controller under ``perception: camera``: the planner knows the scene only
through a depth camera.

The controller is the scenario's own (:func:`~dynfab.scenario.guided_controller.make_scenario_controller`:
guided, or the plain fabric with stall recovery) built as if the scene were empty, plus the
nearest-point leaf, which a :class:`~dynfab.perception.camera_feed.CameraFeed` writes every
tick from the camera's latest cloud (the robot filtered out, velocities for a dynamic
fabric). The file's obstacles stay in the physics and the metrics. The MuJoCo loop calls
:meth:`CameraController.capture` after every control period (the camera renders when a
frame is due); frames reach the planner ``delay`` later.

Until the first frame has arrived the robot knows nothing of its scene and holds still
(q̈ = 0; it starts at rest). Guidance plans its first path at the first frame, among the
points seen then, and each new cloud replaces the obstacles its later plans avoid.
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
from dynfab.perception.camera_feed import CameraFeed
from dynfab.perception.depth_camera import DepthCamera, DepthRender
from dynfab.robots.robot import Robot
from dynfab.scenario.guided_controller import GuidedController, make_scenario_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.schema import Scenario

__all__ = ["CameraController", "make_camera_controller"]


class CameraController:
    """The scenario's controller fed by a depth camera (module docstring).

    Attributes:
        inner: The scenario's controller, built for an empty scene.
        feed: The camera and what it writes into the planner.
    """

    def __init__(self, inner: Any, feed: CameraFeed) -> None:
        self.inner = inner
        self.feed = feed

    def __getattr__(self, name: str) -> Any:
        """The inner controller's attributes (status, solver times, ... for the metrics)."""
        if name in ("inner", "feed"):
            raise AttributeError(name)
        return getattr(self.inner, name)

    def capture(self, t: float, render: DepthRender, q: NDArray[np.float64]) -> None:
        """After a control period: the camera takes a frame at ``t`` [s] if one is due."""
        self.feed.capture(t, render, q)

    def __call__(self, t: float, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> NDArray[np.float64]:
        planner: FabricPlanner = self.inner.planner
        leaf = next(leaf for leaf in planner.config.leaves if isinstance(leaf, NearestSurfaceAvoidance))
        self.feed.attach(leaf, planner.parameters.leaves[leaf.name])
        new = self.feed.write(t, q, planner.config.dynamic)
        if self.feed.latest is None:
            return np.zeros_like(qdot)
        if new and isinstance(self.inner, GuidedController) and self.feed.cloud is not None:
            seen = () if self.feed.cloud.empty else (PlacedObstacle(self.feed.cloud, Placement((0.0, 0.0, 0.0))),)
            self.inner.guided.set_obstacles(seen)
        return self.inner(t, q, qdot)


def make_camera_controller(scenario: Scenario, robot: Robot, seed: int = 0) -> CameraController:
    """The controller of a ``perception: camera`` scenario (validated for ``robot``)."""
    assert scenario.camera is not None
    blind = dataclasses.replace(scenario, obstacles=())
    inner = make_scenario_controller(blind, robot, scenario_references(blind, robot))
    return CameraController(inner, CameraFeed(robot, DepthCamera(scenario.camera, robot, seed=seed)))
