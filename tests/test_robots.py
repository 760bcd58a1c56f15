"""Built-in robots, URDF errors, collision spheres and user robots."""

from __future__ import annotations

import dataclasses
from importlib import resources
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from dynfab.robots import (CollisionSphere, Robot, UnknownLinkError, UnknownRobotError,
                           UrdfError, load_robot, parse_urdf, robot_from_urdf)
from dynfab.robots.builtin import panda_robot

Q0 = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])
POINT_URDF = Path(str(resources.files("dynfab.robots").joinpath("data", "point.urdf")))


@pytest.fixture(scope="module")
def panda() -> Robot:
    return load_robot("panda")


def test_load_panda(panda: Robot) -> None:
    assert panda.name == "panda"
    assert panda.dof == 7 and panda.kinematics.dof == 7
    assert panda.goal_link == "panda_hand"
    assert not panda.planar
    np.testing.assert_array_equal(panda.default_q, Q0)
    assert len(panda.collision_spheres) == 75  # fitted to Franka's meshes: test_collision_model.py
    assert all(0.005 <= s.radius <= 0.11 for s in panda.collision_spheres)
    covered = {s.link for s in panda.collision_spheres}
    assert covered == {f"panda_link{i}" for i in range(8)} | {"panda_hand_body", "panda_leftfinger",
                                                              "panda_rightfinger"}
    assert panda.kinematics.locked == {"panda_finger_joint1": 0.04}  # open: no planner coordinate
    with pytest.raises(ValueError):
        panda.default_q[0] = 0.0  # read-only


def test_panda_plans_on_tighter_spheres_than_the_fabric_avoids_with(panda: Robot) -> None:
    """Guidance's spheres (links 5 and 6 at 1 cm: test_collision_model.py): the same links
    and kinematics, more spheres on links 5 and 6 only, and the planning robot has no
    planning spheres of its own."""
    planning = panda.planning_robot
    assert planning is panda.planning_robot and planning.kinematics is panda.kinematics
    assert len(planning.collision_spheres) == 101 and len(planning.self_collision_pairs) == 373
    assert planning.planning_spheres is None and planning.planning_robot is planning
    count = lambda robot, link: sum(s.link == link for s in robot.collision_spheres)  # noqa: E731
    for link in {s.link for s in panda.collision_spheres}:
        more = link in ("panda_link5", "panda_link6")
        assert (count(planning, link) > count(panda, link)) if more else count(planning, link) == count(panda, link)
    hand_written = panda_robot("hand-written")
    assert hand_written.planning_robot is hand_written


def test_bad_planning_spheres_are_refused(panda: Robot) -> None:
    spheres = panda.collision_spheres[:3]
    with pytest.raises(ValueError, match=r"planning pair \(0, 3\) must index two different spheres of 3"):
        dataclasses.replace(panda, planning_spheres=spheres, planning_pairs=((0, 3),))
    with pytest.raises(UnknownLinkError, match="unknown link 'elbow'"):
        dataclasses.replace(panda, planning_spheres=(CollisionSphere("elbow", (0.0, 0.0, 0.0), 0.1),))
    with pytest.raises(ValueError, match="planning_pairs need planning_spheres"):
        dataclasses.replace(panda, planning_spheres=None, planning_pairs=((0, 1),))


def test_load_point() -> None:
    point = load_robot("point")
    assert point.dof == 2 and point.planar and point.goal_link == "point"
    assert point.collision_spheres == (CollisionSphere("point", (0.0, 0.0, 0.0), 0.1),)
    np.testing.assert_array_equal(point.default_q, [0.0, 0.0])
    np.testing.assert_array_equal(point.kinematics.lower, [-5.0, -5.0])
    np.testing.assert_array_equal(point.kinematics.upper, [5.0, 5.0])
    np.testing.assert_allclose(point.sphere_centers([1.5, -2.0]), [[1.5, -2.0, 0.0]])


def test_unknown_robot_lists_valid_names() -> None:
    with pytest.raises(UnknownRobotError, match="'ur5'.*panda.*point"):
        load_robot("ur5")
    assert issubclass(UnknownRobotError, ValueError)
    assert issubclass(UnknownLinkError, ValueError)


def test_sphere_centers_types(panda: Robot) -> None:
    numeric = panda.sphere_centers(Q0)
    assert isinstance(numeric, np.ndarray) and numeric.shape == (len(panda.collision_spheres), 3)
    q = ca.SX.sym("q", 7)
    symbolic = panda.sphere_centers(q)
    assert isinstance(symbolic, ca.SX) and symbolic.shape == numeric.shape
    np.testing.assert_allclose(np.array(ca.Function("c", [q], [symbolic])(Q0)), numeric,
                               atol=1e-14)
    for center, sphere in zip(numeric, panda.collision_spheres):
        expected = panda.kinematics.position(Q0, sphere.link, offset=sphere.center)
        np.testing.assert_allclose(center, np.array(expected).ravel(), atol=1e-14)


def _configurations(robot: Robot, count: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    kin = robot.kinematics
    return [Q0, np.zeros(7)] + [rng.uniform(kin.lower, kin.upper) for _ in range(count)]


def test_panda_spheres_cover_every_joint_origin(panda: Robot) -> None:
    kin = panda.kinematics
    # every joint origin of the arm, the hand body and the fingers; not panda_hand, the
    # point between the open fingertips, where nothing is
    chain = [link for link in kin.link_names[kin.link_names.index("panda_link1"):] if link != "panda_hand"]
    radii = panda.sphere_radii
    for q in _configurations(panda, 30, seed=5):
        centers = panda.sphere_centers(q)
        for link in chain:
            origin = np.array(kin.position(q, link)).ravel()
            gap = np.min(np.linalg.norm(centers - origin, axis=1) - radii)
            assert gap <= 0.02, f"{link} origin is {gap:.3f} m outside the spheres"


def test_panda_spheres_cover_segments_between_joints(panda: Robot) -> None:
    """Points along the straight segments between consecutive joint origins, from the base
    to the hand body."""
    kin = panda.kinematics
    radii = panda.sphere_radii
    chain = [f"panda_link{i}" for i in range(9)] + ["panda_hand_body"]
    for q in _configurations(panda, 10, seed=6):
        centers = panda.sphere_centers(q)
        origins = [np.array(kin.position(q, link)).ravel() for link in chain]
        for start, end in zip(origins[1:-1], origins[2:]):
            for t in np.linspace(0.0, 1.0, 11):
                point = start + t * (end - start)
                assert np.min(np.linalg.norm(centers - point, axis=1) - radii) <= 0.02


def _joint_depth(link: str) -> int:
    """Number of actuated joints between the base and ``link``."""
    return int(link[-1]) if link[-1].isdigit() and link != "panda_link8" else 7


def test_panda_self_collision_pairs(panda: Robot) -> None:
    spheres = panda.collision_spheres
    pairs = panda.self_collision_pairs
    assert 240 <= len(pairs) <= 300   # 268: pairs also chosen around each body pair's close samples
    assert len(set(pairs)) == len(pairs)
    for a, b in pairs:
        assert abs(_joint_depth(spheres[a].link) - _joint_depth(spheres[b].link)) >= 2
    links = {(spheres[a].link, spheres[b].link) for a, b in pairs}
    assert {("panda_link0", "panda_link7"), ("panda_link2", "panda_link7"), ("panda_link5", "panda_link7")} <= links
    centers = panda.sphere_centers(Q0)
    for a, b in pairs:
        clearance = (np.linalg.norm(centers[a] - centers[b])
                     - spheres[a].radius - spheres[b].radius)
        assert clearance > 0.04, f"pair ({a}, {b}) in contact at the default configuration"
    # at q = 0 (joint 4 just beyond its limit) Franka's meshes of the forearm and the hand
    # overlap by 4.1 cm (tests/test_collision_model.py measures the meshes); a pair sees it
    centers = panda.sphere_centers(np.zeros(7))
    assert min(np.linalg.norm(centers[a] - centers[b]) - spheres[a].radius - spheres[b].radius
               for a, b in pairs if spheres[a].link == "panda_link5") < -0.04


def test_panda_self_collision_pairs_can_meet(panda: Robot) -> None:
    """Each pair comes into contact somewhere within the joint limits (folded arm)."""
    kin = panda.kinematics
    rng = np.random.default_rng(7)
    q = ca.SX.sym("q", 7)
    centers = ca.Function("c", [q], [panda.sphere_centers(q)]).map(20000)
    samples = rng.uniform(kin.lower, kin.upper, size=(20000, 7))
    all_centers = np.array(centers(samples.T)).reshape(len(panda.collision_spheres), -1, 3)
    radii = panda.sphere_radii
    for a, b in panda.self_collision_pairs:
        clearance = (np.linalg.norm(all_centers[a] - all_centers[b], axis=1)
                     - radii[a] - radii[b])
        assert clearance.min() < 0.03, f"pair ({a}, {b}) never comes close"


BAD_URDFS = [
    ("<robot name='r'><link name='a'>", "not well-formed"),
    ("<model name='r'/>", "<robot>"),
    ("<robot name='r'/>", "no <link>"),
    ("<robot name='r'><link/></robot>", "<link>.*'name'"),
    ("<robot name='r'><link name='a'/><link name='a'/></robot>", "duplicate link"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint type='fixed'><parent link='a'/><child link='b'/></joint></robot>",
     "<joint>.*'name'"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='floating'><parent link='a'/><child link='b'/></joint></robot>",
     "joint name='j'.*'floating' is not supported"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='planar'><parent link='a'/><child link='b'/></joint></robot>",
     "joint name='j'.*'planar' is not supported"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='hinge'><parent link='a'/><child link='b'/></joint></robot>",
     "joint name='j'.*unknown joint type 'hinge'"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='fixed'><child link='b'/></joint></robot>",
     "joint name='j'.*missing <parent>"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='fixed'><parent/><child link='b'/></joint></robot>",
     "joint name='j'.*<parent>.*'link'"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='revolute'><parent link='a'/><child link='b'/></joint></robot>",
     "joint name='j'.*needs a <limit>"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
     "<limit lower='-1' upper='1'/></joint></robot>",
     "joint name='j'.*<limit>.*'velocity'"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
     "<limit lower='x' upper='1' velocity='1'/></joint></robot>",
     "joint name='j'.*'lower' is not a number"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='fixed'><parent link='a'/><child link='b'/>"
     "<origin xyz='1 2'/></joint></robot>",
     "joint name='j'.*<origin>.*'xyz' must be three"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='continuous'><parent link='a'/><child link='b'/>"
     "<axis xyz='0 0 0'/></joint></robot>",
     "joint name='j'.*<axis>.*zero"),
    ("<robot name='r'><link name='a'/><link name='b'/>"
     "<joint name='j' type='fixed'><parent link='a'/><child link='c'/></joint></robot>",
     "joint name='j'.*child link 'c'"),
    ("<robot name='r'><link name='a'/><link name='b'/></robot>", "single root"),
    ("<robot name='r'><link name='a'/><link name='b'/><link name='c'/>"
     "<joint name='j1' type='fixed'><parent link='b'/><child link='c'/></joint>"
     "<joint name='j2' type='fixed'><parent link='c'/><child link='b'/></joint></robot>",
     "cycle"),
]


@pytest.mark.parametrize(("text", "pattern"), BAD_URDFS)
def test_malformed_urdf_raises_one_line_urdf_error(text: str, pattern: str) -> None:
    with pytest.raises(UrdfError, match=pattern) as info:
        parse_urdf(text)
    assert "\n" not in str(info.value)
    assert isinstance(info.value, ValueError)


def test_parse_urdf_reads_limits_and_defaults() -> None:
    model = parse_urdf(POINT_URDF.read_text())
    assert model.name == "point" and model.root_link == "world"
    joint = model.joints[1]
    assert (joint.type, joint.parent, joint.child) == ("prismatic", "point_x", "point")
    assert joint.axis == (0.0, 1.0, 0.0)
    assert joint.origin.xyz == (0.0, 0.0, 0.0) and joint.origin.is_identity_rotation
    assert (joint.limit.lower, joint.limit.upper, joint.limit.velocity) == (-5.0, 5.0, 2.0)


def test_robot_from_urdf(tmp_path: Path) -> None:
    spheres = [CollisionSphere("point", (0.0, 0.0, 0.0), 0.2),
               CollisionSphere("point_x", (0.0, 0.0, 0.0), 0.1)]
    robot = robot_from_urdf(POINT_URDF, "point", spheres, self_collision_pairs=[(0, 1)],
                            planar=True)
    assert robot.name == "point" and robot.planar and robot.dof == 2
    assert robot.self_collision_pairs == ((0, 1),)
    np.testing.assert_array_equal(robot.default_q, [0.0, 0.0])
    np.testing.assert_allclose(robot.sphere_centers([1.0, 2.0]), [[1, 2, 0], [1, 0, 0]])

    with pytest.raises(UnknownLinkError, match="'gripper'.*world"):
        robot_from_urdf(POINT_URDF, "point", [CollisionSphere("gripper", (0, 0, 0), 0.1)])
    with pytest.raises(UnknownLinkError, match="'tool'"):
        robot_from_urdf(POINT_URDF, "tool", spheres)
    with pytest.raises(ValueError, match=r"pair \(0, 2\)"):
        robot_from_urdf(POINT_URDF, "point", spheres, self_collision_pairs=[(0, 2)])
    with pytest.raises(ValueError, match="default_q must have 2"):
        robot_from_urdf(POINT_URDF, "point", spheres, default_q=[0.0])
    with pytest.raises(ValueError, match="radius"):
        CollisionSphere("point", (0, 0, 0), -0.1)

    # default_q: zeros clipped into the joint limits
    shifted = tmp_path / "shifted.urdf"
    shifted.write_text(POINT_URDF.read_text().replace('lower="-5.0"', 'lower="1.0"', 1))
    robot = robot_from_urdf(shifted, "point", spheres[:1])
    np.testing.assert_array_equal(robot.default_q, [1.0, 0.0])

    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='x'><link name='a'>")
    with pytest.raises(UrdfError, match="broken.urdf"):
        robot_from_urdf(broken, "a", [])
