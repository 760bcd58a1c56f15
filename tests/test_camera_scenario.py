"""Scenarios whose planner knows the scene only through a depth camera (``perception:
camera``): the schema and its errors, tracked moving clusters, and runs under MuJoCo (a
sphere in the way, a ball thrown at the hand)."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from dynfab.perception.motion_tracks import ClusterTracker
from dynfab.perception.workspace import robot_workspace
from dynfab.robots import load_robot
from dynfab.scenario.camera_controller import CameraController
from dynfab.scenario.fields import ScenarioError
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
from camera_experiments import CAMERA, thrown_scenario  # noqa: E402

BASE = {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 4.0,
        "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
        "goal": [{"type": "position", "link": "panda_hand", "position": [0.55, -0.35, 0.25], "tolerance": 0.05}],
        "obstacles": [{"type": "sphere", "position": [0.5, 0.15, 0.35], "radius": 0.15}]}


def with_camera(**changes: object) -> dict:
    return {**BASE, "simulator": "mujoco", "camera": CAMERA, "perception": "camera", **changes}


def test_the_camera_block_becomes_a_camera_spec() -> None:
    scenario = scenario_from_dict(with_camera())
    assert scenario.perception == "camera"
    assert scenario.camera.width == 320 and scenario.camera.rate == 30.0 and scenario.camera.delay == 0.033
    assert scenario_from_dict(BASE).perception == "truth" and scenario_from_dict(BASE).camera is None


@pytest.mark.parametrize(("changes", "message"), [
    ({"simulator": "kinematic"}, "camera: applies to simulator: mujoco only"),
    ({"camera": None, "perception": "camera"}, "perception: camera needs a camera: block"),
    ({"perception": "eyes"}, "perception: expected one of truth, camera; got str 'eyes'"),
    ({"planner": "mpc"}, "perception: camera needs a fabric planner"),
    ({"camera": {**CAMERA, "width": 0}}, "camera.width: must be positive, got 0"),
    ({"camera": {**CAMERA, "height": 240.5}}, "camera.height: must be a whole number of pixels > 0, got 240.5"),
    ({"camera": {**CAMERA, "fov": 180}}, r"camera.fov: must lie in \(0, 180\) degrees"),
    ({"camera": {**CAMERA, "rate": 0}}, "camera.rate: must be positive, got 0"),
    ({"camera": {**CAMERA, "noise": -1}}, "camera.noise: must be >= 0"),
    ({"camera": {**CAMERA, "position": [0, float("nan"), 1]}}, r"camera.position\[1\]: expected a finite number"),
    ({"camera": {**CAMERA, "look_at": CAMERA["position"]}}, "camera.look_at: must differ from position"),
    ({"camera": {**CAMERA, "zoom": 2}}, r"camera.zoom: unknown key"),
    ({"camera": {"look_at": [0, 0, 0]}}, "camera.position: missing required key"),
    ({"camera": {**CAMERA, "workspace_margin": -0.1}}, "camera.workspace_margin: must be >= 0 m"),
    ({"camera": {**CAMERA, "workspace_margin": "reach"}}, "camera.workspace_margin: expected a number"),
])
def test_bad_camera_scenarios_are_refused_naming_the_field(changes: dict, message: str) -> None:
    document = with_camera(**changes)
    if document["camera"] is None:
        del document["camera"]
    with pytest.raises(ScenarioError, match=message):
        scenario_from_dict(document)


def test_the_workspace_margin_crops_the_camera_to_the_robots_reach() -> None:
    """``camera.workspace_margin`` crops every frame to the Panda's reach plus the margin (the
    sphere in the way still avoided); a robot on a mobile base has no fixed reach: refused,
    naming the field."""
    scenario = scenario_from_dict(with_camera(camera={**CAMERA, "workspace_margin": 0.3}))
    assert scenario.camera_workspace_margin == 0.3 and scenario_from_dict(with_camera()).camera_workspace_margin is None
    result = run_scenario(dataclasses.replace(scenario, duration=3.0))
    assert result.metrics.goal_reached and not result.metrics.collision
    ball = robot_workspace(load_robot("panda"), 0.3)
    points = result.controller.feed.latest.points
    assert len(points) > 100  # the sphere in the way
    assert np.linalg.norm(points - ball.centre, axis=1).max() <= ball.radius + 0.01  # depth noise
    robot = load_robot("boxer-panda")
    document = with_camera(robot="boxer-panda", camera={**CAMERA, "workspace_margin": 0.3},
                           initial_state={"q": [float(value) for value in robot.default_q]})
    with pytest.raises(ScenarioError, match="camera.workspace_margin: robot 'boxer-panda' is on a mobile base"):
        validate_for_robot(scenario_from_dict(document), robot)


def test_moving_clusters_are_balls_that_hold_what_was_seen() -> None:
    """A ball's visible half moving at 0.5 m/s beside a static table: one moving cluster,
    whose ball holds the whole ball at the current time and carries its velocity."""
    rng = np.random.default_rng(0)
    tracker = ClusterTracker()
    velocity, radius = np.array([0.0, 0.5, 0.0]), 0.08
    camera = np.array([2.0, 0.0, 0.5])
    for k in range(6):
        t = k / 30.0
        centre = np.array([0.5, -0.4, 0.6]) + velocity * t
        directions = rng.normal(size=(2000, 3))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        cap = centre + radius * directions[directions @ (camera - centre) > 0]
        xs, ys = np.meshgrid(np.arange(-0.5, 0.5, 0.01), np.arange(-0.5, 0.5, 0.01))
        table = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 0.2)])
        tracker.update(t, np.vstack([cap, table]))
    moving = tracker.moving(0.1)
    assert len(moving) == 1
    ball = moving[0]
    now = 5 / 30.0 + 0.05
    truth = np.array([0.5, -0.4, 0.6]) + velocity * now
    assert np.linalg.norm(ball.at(now) - truth) + radius <= ball.radius  # holds the whole ball
    assert ball.radius < 2.5 * radius
    assert np.linalg.norm(ball.velocity - velocity) < 0.05


def test_a_sphere_in_the_way_seen_only_by_the_camera_is_avoided() -> None:
    scenario = scenario_from_dict(with_camera())
    result = run_scenario(scenario)
    assert result.metrics.goal_reached and not result.metrics.collision
    controller = result.controller
    assert isinstance(controller, CameraController)
    assert controller.feed.frames >= 4.0 * 30 - 2  # 30 Hz for 4 s, the last one still on its way
    assert result.metrics.clearance > 0.0
    radii = np.asarray(controller.planner.parameters.obstacle_radius)
    assert radii.shape == (3,) and np.all(radii == 0.0)  # its slots are for moving clusters; none moved


def test_a_ball_thrown_at_the_hand_seen_only_by_the_camera_is_avoided() -> None:
    document = thrown_scenario(1)
    document.update(simulator="mujoco", camera=CAMERA, perception="camera", guidance=False, duration=4.5)
    seeing = run_scenario(scenario_from_dict(document)).metrics
    assert seeing.goal_reached and not seeing.collision
    document["camera"] = {**CAMERA, "position": [0.0, 0.0, 3.0], "look_at": [0.0, 0.0, 10.0]}  # at the sky
    blind = run_scenario(scenario_from_dict(document)).metrics
    assert blind.collision  # the ball does hit a robot that does not see it


def test_space_behind_seen_surfaces_is_extended_along_the_rays() -> None:
    from dynfab.perception.occlusion import behind_surfaces

    points = np.array([[2.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    solid = behind_surfaces(points, (0.0, 0.0, 0.0), thickness=0.3, step=0.03)
    assert solid.shape == (11 * 2, 3)
    along_x = solid[np.abs(solid[:, 1]) + np.abs(solid[:, 2]) < 1e-12]
    np.testing.assert_allclose(np.sort(along_x[:, 0]), 2.0 + 0.03 * np.arange(11))
    np.testing.assert_allclose(solid[solid[:, 0] == 0.0][:, 2].max(), 1.3)
    with pytest.raises(ValueError, match="step > 0"):
        behind_surfaces(points, (0.0, 0.0, 0.0), thickness=0.3, step=0.0)


def test_the_camera_feed_is_evaluated_on_the_scenarios_backend(monkeypatch: pytest.MonkeyPatch) -> None:
    """``backend: vm`` reaches the per-tick nearest-point writer too: nothing is compiled,
    even where the library's default is the compiled backend."""
    from dynfab.fabric import c_backend
    from dynfab.scenario.camera_controller import make_camera_controller

    monkeypatch.setenv("DYNFAB_BACKEND", "c")
    monkeypatch.setattr(c_backend, "find_compiler", lambda *args, **kwargs: pytest.fail("the feed was compiled"))
    robot = load_robot("panda")
    scenario = validate_for_robot(scenario_from_dict(with_camera(backend="vm", planner="dynamic-fabric")), robot)
    controller = make_camera_controller(scenario, robot)
    q = np.array(BASE["initial_state"]["q"])
    assert np.all(controller(0.0, q, np.zeros(7)) == 0.0)   # no frame yet: at rest
    assert controller.feed.cloud is not None   # the feed was attached, on the VM
