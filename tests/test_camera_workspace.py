"""A camera's workspace crop: the Panda's reach ball holds every sphere in every sampled
configuration, the per-pixel depth range keeps exactly the points in the ball, a cropped
frame is the uncropped one's points in the ball, and bad input is refused naming the field."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.perception.camera_spec import CameraSpec
from dynfab.perception.depth_camera import DepthCamera
from dynfab.perception.depth_image import DepthProjector
from dynfab.perception.workspace import Workspace, robot_workspace
from dynfab.robots import load_robot

SPEC = CameraSpec(position=(1.6, -1.4, 1.3), look_at=(0.2, -0.2, 0.35), width=160, height=120, fov=60.0)


def _floor_depth(projector: DepthProjector) -> np.ndarray:
    """Depth of the plane z = 0 seen by the camera (inf where a ray does not go down)."""
    rays_z = projector.rays[..., 2].astype(float)
    with np.errstate(divide="ignore"):
        depth = np.where(rays_z < 0.0, -projector.origin[2] / rays_z, np.inf)
    return depth.astype(np.float32)


def test_the_panda_reach_ball_holds_every_sphere_in_every_sampled_configuration() -> None:
    robot = load_robot("panda")
    ball = robot_workspace(robot, margin=0.0)
    rng = np.random.default_rng(0)
    farthest = 0.0
    for q in rng.uniform(robot.kinematics.lower, robot.kinematics.upper, (300, robot.dof)):
        centres = np.asarray(robot.sphere_centers(q), dtype=float).reshape(-1, 3)
        farthest = max(farthest, float((np.linalg.norm(centres - ball.centre, axis=1) + robot.sphere_radii).max()))
    assert farthest <= ball.radius
    assert ball.radius < 1.5 * farthest  # a bound, not a vacuous one
    assert robot_workspace(robot, margin=0.3).radius == pytest.approx(ball.radius + 0.3)


def test_the_depth_range_keeps_exactly_the_points_in_the_ball() -> None:
    projector = DepthProjector(SPEC)
    centre, radius = np.array([0.1, -0.2, 0.3]), 0.9
    near, far = projector.ball_depths(centre, radius)
    depth = _floor_depth(projector)
    kept = (depth >= near) & (depth <= far)
    points = projector.points(depth, np.isfinite(depth))
    inside = np.linalg.norm(points - centre, axis=1) <= radius
    assert np.isfinite(depth).sum() > 1000 and 0 < inside.sum() < len(points)
    borderline = np.abs(np.linalg.norm(points - centre, axis=1) - radius) < 1e-5  # float32 depths
    assert np.array_equal(kept[np.isfinite(depth)][~borderline], inside[~borderline])


def test_a_cropped_frame_is_the_full_frame_within_the_workspace() -> None:
    robot = load_robot("panda")
    ball = robot_workspace(robot, margin=0.3)
    depth = _floor_depth(DepthProjector(SPEC))
    full = DepthCamera(SPEC, robot).frame(0.0, depth, robot.default_q).points
    cropped = DepthCamera(SPEC, robot, workspace=ball).frame(0.0, depth, robot.default_q).points
    inside = np.linalg.norm(full - ball.centre, axis=1) <= ball.radius
    assert 0 < len(cropped) < len(full)
    assert abs(len(cropped) - inside.sum()) <= 2  # pixels on the sphere's edge, float32 depths
    assert np.linalg.norm(cropped - ball.centre, axis=1).max() <= ball.radius + 1e-4


@pytest.mark.parametrize(("centre", "radius", "message"), [
    ((0.0, float("nan"), 0.0), 1.0, r"workspace.centre: expected three finite numbers"),
    ((0.0, 0.0), 1.0, r"workspace.centre: expected three finite numbers"),
    ((0.0, 0.0, 0.0), 0.0, r"workspace.radius: must be a positive finite number, got 0.0"),
    ((0.0, 0.0, 0.0), "far", r"workspace: expected a centre of three numbers and a radius"),
])
def test_a_bad_workspace_is_refused_naming_the_field(centre: tuple, radius: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Workspace(centre, radius)


def test_a_robot_on_a_mobile_base_has_no_workspace_ball() -> None:
    with pytest.raises(ValueError, match="mobile base"):
        robot_workspace(load_robot("boxer-panda"), margin=0.1)
