"""Mobile robots: the Boxer base and the Panda on a Boxer (``boxer``, ``boxer-panda``)."""

from __future__ import annotations

import dataclasses
from importlib import resources

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from dynfab.robots import Kinematics, Robot, UnknownRobotError, load_robot, parse_urdf
from dynfab.robots.builtin import (BOXER_BASE, BOXER_DISC_RADIUS, BOXER_SPHERE_RADIUS,
                                   PANDA_DEFAULT_Q)
from dynfab.robots.robot import BASE_JOINTS, DifferentialDriveBase
from test_kinematics import to_pinocchio_q

DATA = resources.files("dynfab.robots").joinpath("data")
TEXTS = {"boxer": DATA.joinpath("boxer.urdf").read_text(),
         "boxer-panda": DATA.joinpath("boxer_panda.urdf").read_text()}
PANDA_TEXT = DATA.joinpath("panda.urdf").read_text()

# Chassis box in chassis_link coordinates (Clearpath's collision box) [m].
HALF_LENGTH, HALF_WIDTH, HEIGHT = 0.74143 / 2, 0.55093 / 2, 0.2884
# base_link (body centre on the floor), chassis_link and the Panda's mount (panda_link0)
# in axle_link coordinates; axle_link's planar pose is q[:3] [m].
BASE_IN_AXLE = np.array([0.1503, 0.0, 0.0])
CHASSIS_IN_AXLE = BASE_IN_AXLE + [0.0, 0.0, 0.0275]
MOUNT_IN_AXLE = CHASSIS_IN_AXLE + [0.2, 0.0, HEIGHT]


@pytest.fixture(scope="module", params=["boxer", "boxer-panda"])
def mobile(request: pytest.FixtureRequest) -> Robot:
    return load_robot(request.param)


@pytest.fixture(scope="module")
def boxer_panda() -> Robot:
    return load_robot("boxer-panda")


def _random_q(robot: Robot, rng: np.random.Generator) -> np.ndarray:
    """Joints within their limits; base yaw (continuous) within +-2 pi."""
    kin = robot.kinematics
    lower = np.where(np.isfinite(kin.lower), kin.lower, -2.0 * np.pi)
    upper = np.where(np.isfinite(kin.upper), kin.upper, 2.0 * np.pi)
    return rng.uniform(lower, upper)


def _planar_pose(x: float, y: float, yaw: float) -> np.ndarray:
    """4x4 transform of a planar pose."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0, x], [s, c, 0, y], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float)


def _translation(p: np.ndarray) -> np.ndarray:
    t = np.eye(4)
    t[:3, 3] = p
    return t


def test_load_boxer() -> None:
    boxer = load_robot("boxer")
    assert boxer.name == "boxer" and boxer.dof == 3
    assert boxer.kinematics.joint_names == BASE_JOINTS
    assert boxer.goal_link == "base_link" and boxer.planar
    assert boxer.base == BOXER_BASE
    assert boxer.self_collision_pairs == ()
    assert 4 <= len(boxer.collision_spheres) <= 6
    np.testing.assert_array_equal(boxer.default_q, [0.0, 0.0, 0.0])
    kin = boxer.kinematics
    np.testing.assert_array_equal(kin.lower, [-10.0, -10.0, -np.inf])
    np.testing.assert_array_equal(kin.upper, [10.0, 10.0, np.inf])
    np.testing.assert_allclose(kin.velocity_limits, [1.9, 1.9, 2.0])


def test_load_boxer_panda(boxer_panda: Robot) -> None:
    robot = boxer_panda
    assert robot.name == "boxer-panda" and robot.dof == 10
    assert robot.kinematics.joint_names == BASE_JOINTS + tuple(
        f"panda_joint{i}" for i in range(1, 8))
    assert robot.goal_link == "panda_hand" and not robot.planar
    assert robot.base == BOXER_BASE
    np.testing.assert_array_equal(robot.default_q, (0.0, 0.0, 0.0) + PANDA_DEFAULT_Q)
    panda = load_robot("panda")
    np.testing.assert_array_equal(robot.kinematics.lower[3:], panda.kinematics.lower)
    np.testing.assert_array_equal(robot.kinematics.upper[3:], panda.kinematics.upper)
    np.testing.assert_array_equal(robot.kinematics.velocity_limits[3:],
                                  panda.kinematics.velocity_limits)
    # the Panda's spheres, unchanged, after the base's
    assert robot.collision_spheres[-len(panda.collision_spheres):] == panda.collision_spheres


def test_arm_joints_are_those_of_panda_urdf() -> None:
    arm = {j.name: j for j in parse_urdf(TEXTS["boxer-panda"]).joints}
    for joint in parse_urdf(PANDA_TEXT).joints:
        assert arm[joint.name] == joint


def test_base_matches_urdf_and_is_consistent() -> None:
    """Wheel links of the URDF agree with the DifferentialDriveBase figures."""
    kin = load_robot("boxer").kinematics
    left = np.array(kin.position(np.zeros(3), "wheel_left_link")).ravel()
    right = np.array(kin.position(np.zeros(3), "wheel_right_link")).ravel()
    assert np.linalg.norm(left - right) == pytest.approx(BOXER_BASE.wheel_separation)
    assert left[2] == pytest.approx(BOXER_BASE.wheel_radius)
    assert right[2] == pytest.approx(BOXER_BASE.wheel_radius)
    # axle_link is the axle midpoint, on the floor
    np.testing.assert_allclose((left + right) / 2, [0.0, 0.0, BOXER_BASE.wheel_radius])
    np.testing.assert_allclose(np.array(kin.position(np.zeros(3), "axle_link")).ravel(),
                               [0.0, 0.0, 0.0])
    assert left[1] > 0.0 > right[1]  # left is +y
    assert BOXER_BASE.max_forward_speed == kin.velocity_limits[0] == kin.velocity_limits[1]
    assert BOXER_BASE.max_yaw_rate == kin.velocity_limits[2]


def test_unknown_robot_lists_mobile_robots() -> None:
    with pytest.raises(UnknownRobotError, match="'albert'.*boxer.*boxer-panda"):
        load_robot("albert")


def test_fixed_robots_have_no_base() -> None:
    assert load_robot("panda").base is None
    assert load_robot("point").base is None


@pytest.mark.parametrize("name", ["boxer", "boxer-panda"])
def test_every_link_matches_pinocchio(name: str) -> None:
    robot = load_robot(name) if name == "boxer" else load_robot(name, fingers=0.0)  # pinocchio's fingers: 0
    kin = robot.kinematics
    model = pin.buildModelFromXML(TEXTS[name])
    data = model.createData()
    fingers = sum("finger" in joint for joint in model.names)
    assert model.nq == kin.dof + 1 + fingers  # base_yaw is continuous: (cos, sin) in pinocchio
    rng = np.random.default_rng(11)
    for q in [robot.default_q, np.zeros(kin.dof)] + [_random_q(robot, rng)
                                                      for _ in range(25)]:
        pin.forwardKinematics(model, data, to_pinocchio_q(model, kin, q))
        pin.updateFramePlacements(model, data)
        for link in kin.link_names:
            expected = data.oMf[model.getFrameId(link)]
            transform = np.array(kin.transform(q, link))
            np.testing.assert_allclose(transform[:3, :3], expected.rotation, atol=1e-10)
            np.testing.assert_allclose(transform[:3, 3], expected.translation, atol=1e-10)


def test_base_frames_follow_the_planar_pose(mobile: Robot) -> None:
    """axle_link at (x, y, 0) with heading yaw; base_link (body centre) and the body
    move rigidly with it."""
    kin = mobile.kinematics
    rng = np.random.default_rng(12)
    for _ in range(20):
        q = _random_q(mobile, rng)
        x, y, yaw = q[:3]
        pose = _planar_pose(x, y, yaw)
        np.testing.assert_allclose(np.array(kin.transform(q, "axle_link")), pose,
                                   atol=1e-12)
        np.testing.assert_allclose(np.array(kin.transform(q, "base_link")),
                                   pose @ _translation(BASE_IN_AXLE), atol=1e-12)
        np.testing.assert_allclose(
            np.array(kin.position(q, "base_link")).ravel(),
            [x + 0.1503 * np.cos(yaw), y + 0.1503 * np.sin(yaw), 0.0], atol=1e-12)
        np.testing.assert_allclose(np.array(kin.transform(q, "chassis_link")),
                                   pose @ _translation(CHASSIS_IN_AXLE), atol=1e-12)
        top = pose @ _translation(CHASSIS_IN_AXLE + [0.0, 0.0, HEIGHT])
        np.testing.assert_allclose(np.array(kin.transform(q, "top_plate_link")), top,
                                   atol=1e-12)
        # the arm (if any) does not move the base
        moved = q.copy()
        moved[3:] = _random_q(mobile, rng)[3:]
        np.testing.assert_allclose(np.array(kin.transform(moved, "top_plate_link")), top,
                                   atol=1e-12)


def test_base_velocities_under_the_differential_drive_constraint(mobile: Robot) -> None:
    """For q_dot = J_nh (v, omega): the axle point moves at v along the heading, the body
    centre (base_link) additionally at 0.1503 omega sideways (so a goal on it turns the
    base)."""
    kin = mobile.kinematics
    q = ca.SX.sym("q", kin.dof)
    jacobians = {link: ca.Function("J", [q], [ca.jacobian(kin.position(q, link), q)])
                 for link in ("axle_link", "base_link")}
    rng = np.random.default_rng(13)
    for _ in range(10):
        value = _random_q(mobile, rng)
        v, omega = rng.normal(size=2)
        c, s = np.cos(value[2]), np.sin(value[2])
        qdot = np.zeros(kin.dof)
        qdot[:3] = v * c, v * s, omega
        axle = np.array(jacobians["axle_link"](value)) @ qdot
        np.testing.assert_allclose(axle, [v * c, v * s, 0.0], atol=1e-12)
        centre = np.array(jacobians["base_link"](value)) @ qdot
        np.testing.assert_allclose(centre, [v * c - 0.1503 * omega * s,
                                            v * s + 0.1503 * omega * c, 0.0], atol=1e-12)


def test_hand_is_the_panda_hand_behind_the_mount(boxer_panda: Robot) -> None:
    """panda_hand = base pose * mount * (the Panda's own hand pose)."""
    panda = load_robot("panda").kinematics
    kin = boxer_panda.kinematics
    mount = _translation(MOUNT_IN_AXLE)
    q0 = boxer_panda.default_q
    np.testing.assert_allclose(np.array(kin.transform(q0, "panda_link0")), mount, atol=1e-12)
    own = np.array(panda.transform(q0[3:], "panda_hand"))
    np.testing.assert_allclose(np.array(kin.transform(q0, "panda_hand")), mount @ own,
                               atol=1e-12)
    np.testing.assert_allclose(np.array(kin.position(q0, "panda_hand")).ravel(),
                               MOUNT_IN_AXLE + own[:3, 3], atol=1e-12)
    rng = np.random.default_rng(14)
    for _ in range(10):
        q = _random_q(boxer_panda, rng)
        expected = _planar_pose(*q[:3]) @ mount @ np.array(panda.transform(q[3:], "panda_hand"))
        np.testing.assert_allclose(np.array(kin.transform(q, "panda_hand")), expected,
                                   atol=1e-12)


def _body_points(planar: bool) -> np.ndarray:
    """A grid over the footprint (planar) or the whole chassis box, chassis_link coords."""
    xs = np.linspace(-HALF_LENGTH, HALF_LENGTH, 31)
    ys = np.linspace(-HALF_WIDTH, HALF_WIDTH, 23)
    zs = [0.1442] if planar else np.linspace(0.0, HEIGHT, 13)
    return np.array([[x, y, z] for x in xs for y in ys for z in zs])


@pytest.mark.parametrize(("name", "radius"), [("boxer", BOXER_DISC_RADIUS),
                                              ("boxer-panda", BOXER_SPHERE_RADIUS)])
def test_spheres_cover_the_body(name: str, radius: float) -> None:
    """Footprint (boxer: discs, x-y only) or body box (boxer-panda: 3-D) is covered,
    without the spheres reaching much beyond it."""
    robot = load_robot(name)
    planar = robot.planar
    body = [s for s in robot.collision_spheres if s.link == "chassis_link"]
    assert len(body) == 6 and all(s.radius == radius for s in body)
    centers = np.array([s.center for s in body])
    axes = slice(0, 2) if planar else slice(0, 3)
    points = _body_points(planar)
    distance = np.linalg.norm(points[:, None, axes] - centers[None, :, axes], axis=2)
    assert np.all(np.min(distance - radius, axis=1) <= 0.0)
    # overhang beyond the body: at most 8 cm (discs) / 12 cm (spheres)
    reach = np.abs(centers[:, :2]).max(axis=0) + radius
    assert reach[0] - HALF_LENGTH <= (0.08 if planar else 0.12)
    assert reach[1] - HALF_WIDTH <= (0.08 if planar else 0.12)
    # and the footprint covers the floor area under the body in the world frame
    q = np.array([1.0, -2.0, 0.7] + [0.0] * (robot.dof - 3))
    world = np.array(robot.sphere_centers(q))[:len(body)]
    pose = _planar_pose(*q[:3]) @ _translation(CHASSIS_IN_AXLE)
    floor = (pose[:3, :3] @ points.T).T + pose[:3, 3]
    distance = np.linalg.norm(floor[:, None, :2] - world[None, :, :2], axis=2)
    assert np.all(np.min(distance - radius, axis=1) <= 1e-12)


def test_self_collision_pairs_apart_at_default(boxer_panda: Robot) -> None:
    spheres = boxer_panda.collision_spheres
    pairs = boxer_panda.self_collision_pairs
    assert len(set(pairs)) == len(pairs)
    centers = boxer_panda.sphere_centers(boxer_panda.default_q)
    for a, b in pairs:
        clearance = (np.linalg.norm(centers[a] - centers[b])
                     - spheres[a].radius - spheres[b].radius)
        assert clearance > 0.04, f"pair ({a}, {b}) in contact at default_q"
    # the Panda's own pairs are all there
    panda = load_robot("panda")
    offset = len(spheres) - len(panda.collision_spheres)
    assert {(a + offset, b + offset) for a, b in panda.self_collision_pairs} <= set(pairs)
    # the rest are arm spheres from the elbow on against the base body
    for a, b in set(pairs) - {(a + offset, b + offset) for a, b in panda.self_collision_pairs}:
        assert spheres[a].link == "chassis_link"
        assert spheres[b].link in ("panda_link4", "panda_link5", "panda_link6", "panda_link7", "panda_hand_body",
                                   "panda_leftfinger", "panda_rightfinger")


def test_arm_body_pairs_are_those_that_can_come_close(boxer_panda: Robot) -> None:
    """An arm sphere and a body sphere are a pair exactly when they come within 2 cm of
    each other somewhere within the arm's limits (on these samples: within 3 cm for
    pairs, at least 2 cm apart for the rest; the selection used 100,000 samples, the hand
    open and closed)."""
    kin = boxer_panda.kinematics
    spheres = boxer_panda.collision_spheres
    count = 20000
    rng = np.random.default_rng(15)
    samples = np.zeros((count, kin.dof))
    samples[:, 3:] = rng.uniform(kin.lower[3:], kin.upper[3:], size=(count, 7))
    q = ca.SX.sym("q", kin.dof)
    centers = ca.Function("c", [q], [boxer_panda.sphere_centers(q)]).map(count)
    all_centers = np.array(centers(samples.T)).reshape(len(spheres), count, 3)
    radii = boxer_panda.sphere_radii
    body = [i for i, s in enumerate(spheres) if s.link == "chassis_link"]
    arm = [i for i, s in enumerate(spheres) if s.link not in ("chassis_link", "panda_link0")]
    pairs = set(boxer_panda.self_collision_pairs)
    assert sum(a in body for a, _ in pairs) == 6 * 38 + 2
    for a in body:
        for b in arm:
            closest = (np.linalg.norm(all_centers[a] - all_centers[b], axis=1) - radii[a] - radii[b]).min()
            if (a, b) in pairs:
                assert closest < 0.03, f"pair ({a}, {b}) never comes close: {closest:.3f} m"
            else:
                assert closest > 0.02, f"({a}, {b}) comes within {closest:.3f} m but is not a pair"


def test_default_q_is_collision_free(boxer_panda: Robot) -> None:
    """At default_q no arm sphere beyond the shoulder touches the base body."""
    spheres = boxer_panda.collision_spheres
    centers = boxer_panda.sphere_centers(boxer_panda.default_q)
    body = [i for i, s in enumerate(spheres) if s.link == "chassis_link"]
    arm = [i for i, s in enumerate(spheres)
           if s.link not in ("chassis_link", "panda_link0", "panda_link1", "panda_link2")]
    for a in body:
        for b in arm:
            gap = np.linalg.norm(centers[a] - centers[b]) - spheres[a].radius - spheres[b].radius
            assert gap > 0.1


# ---------------------------------------------------------------- validation


def test_differential_drive_base_validation_and_wheel_speeds() -> None:
    for field in ("wheel_radius", "wheel_separation", "max_forward_speed", "max_yaw_rate"):
        for bad in (0.0, -1.0, float("nan"), float("inf")):
            values = dict(wheel_radius=0.08, wheel_separation=0.5, max_forward_speed=1.0,
                          max_yaw_rate=1.0)
            values[field] = bad
            with pytest.raises(ValueError, match=field):
                DifferentialDriveBase(**values)
    with pytest.raises(dataclasses.FrozenInstanceError):
        BOXER_BASE.wheel_radius = 0.1  # type: ignore[misc]
    base = DifferentialDriveBase(0.1, 0.5, 1.0, 2.0)
    assert base.wheel_speeds(1.0, 0.0) == pytest.approx((10.0, 10.0))
    # turning on the spot counter-clockwise: left wheel backwards, right forwards
    assert base.wheel_speeds(0.0, 2.0) == pytest.approx((-5.0, 5.0))
    for v, omega in [(0.3, -0.7), (-1.2, 0.4)]:
        assert base.body_velocity(*base.wheel_speeds(v, omega)) == pytest.approx((v, omega))


def _robot_with_urdf(text: str, base: DifferentialDriveBase | None) -> Robot:
    kin = Kinematics(parse_urdf(text))
    return Robot(name="test", kinematics=kin, goal_link=kin.link_names[-1],
                 collision_spheres=(), self_collision_pairs=(), planar=True,
                 default_q=np.zeros(kin.dof), base=base)


def test_robot_with_base_needs_the_base_joints() -> None:
    boxer = TEXTS["boxer"]
    assert _robot_with_urdf(boxer, BOXER_BASE).base == BOXER_BASE
    assert _robot_with_urdf(PANDA_TEXT, None).base is None
    with pytest.raises(ValueError, match="'test'.*base_x, base_y, base_yaw first"):
        _robot_with_urdf(PANDA_TEXT, BOXER_BASE)
    point = DATA.joinpath("point.urdf").read_text()
    with pytest.raises(ValueError, match="first joints are joint_x, joint_y"):
        _robot_with_urdf(point, BOXER_BASE)
    # wrong order: y before x
    swapped = (boxer.replace('name="base_x"', 'name="tmp"')
               .replace('name="base_y"', 'name="base_x"').replace('name="tmp"', 'name="base_y"'))
    with pytest.raises(ValueError, match="base_x, base_y, base_yaw first"):
        _robot_with_urdf(swapped, BOXER_BASE)
    # wrong axis, type, origin
    tilted = boxer.replace('<axis xyz="0 1 0"/>', '<axis xyz="1 1 0"/>')
    with pytest.raises(ValueError, match="base joint 'base_y': axis"):
        _robot_with_urdf(tilted, BOXER_BASE)
    sliding = boxer.replace('name="base_yaw" type="continuous"', 'name="base_yaw" type="prismatic"'
                            ).replace('<limit velocity="2.0" effort="1000"/>',
                                      '<limit lower="-1" upper="1" velocity="2.0" effort="1000"/>')
    with pytest.raises(ValueError, match="base joint 'base_yaw': type"):
        _robot_with_urdf(sliding, BOXER_BASE)
    offset = boxer.replace('<child link="base_y_link"/>\n    <origin xyz="0 0 0"',
                           '<child link="base_y_link"/>\n    <origin xyz="0.1 0 0"')
    assert offset != boxer
    with pytest.raises(ValueError, match="base joint 'base_y': origin"):
        _robot_with_urdf(offset, BOXER_BASE)
    with pytest.raises(TypeError, match="DifferentialDriveBase"):
        _robot_with_urdf(boxer, (0.08, 0.5, 1.0, 1.0))  # type: ignore[arg-type]
