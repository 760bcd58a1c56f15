"""Forward kinematics against pinocchio, derivatives against finite differences."""

from __future__ import annotations

from importlib import resources

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from dynfab.robots import Kinematics, UnknownLinkError, parse_urdf
from dynfab.robots.franka import PANDA_JOINTS

PANDA_TEXT = resources.files("dynfab.robots").joinpath("data", "panda.urdf").read_text()

# Prismatic joint on an oblique axis, a continuous joint on an oblique axis, origins
# with general rpy, and a fixed tool: exercises the non-specialised code paths.
SMALL_TEXT = """<?xml version="1.0"?>
<robot name="small">
  <link name="base"/><link name="slider"/><link name="wheel"/><link name="tool"/>
  <link name="side"/>
  <joint name="slide" type="prismatic">
    <parent link="base"/><child link="slider"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.3 -0.7 1.1"/>
    <axis xyz="1 1 0"/>
    <limit lower="-1" upper="2" velocity="0.5" effort="10"/>
  </joint>
  <joint name="spin" type="continuous">
    <parent link="slider"/><child link="wheel"/>
    <origin xyz="0.05 0.4 -0.1" rpy="-1.2 0.4 0.25"/>
    <axis xyz="0.3 -0.5 0.8"/>
  </joint>
  <joint name="mount" type="fixed">
    <parent link="wheel"/><child link="tool"/>
    <origin xyz="0.2 0 0.05" rpy="0 1.5707963267948966 0"/>
  </joint>
  <joint name="side_joint" type="revolute">
    <parent link="slider"/><child link="side"/>
    <origin xyz="0 0 0.2" rpy="0 0 0"/>
    <axis xyz="0 -1 0"/>
    <limit lower="-1" upper="1" velocity="1" effort="10"/>
  </joint>
</robot>
"""


@pytest.fixture(scope="module")
def panda() -> Kinematics:
    """The built-in Panda's arm joints; the fingers locked closed (0, as pinocchio's q)."""
    return Kinematics(parse_urdf(PANDA_TEXT), joints=PANDA_JOINTS)


def _pin_placements(text: str, q_pin: np.ndarray) -> tuple[pin.Model, pin.Data]:
    model = pin.buildModelFromXML(text)
    data = model.createData()
    pin.forwardKinematics(model, data, q_pin)
    pin.updateFramePlacements(model, data)
    return model, data


def to_pinocchio_q(model: pin.Model, kin: Kinematics, q: np.ndarray) -> np.ndarray:
    """Our q (one angle per joint) as pinocchio's q (cos, sin for continuous joints)."""
    q_pin = np.zeros(model.nq)
    for name, value in zip(kin.joint_names, q):
        joint = model.joints[model.getJointId(name)]
        if joint.nq == 2:
            q_pin[joint.idx_q:joint.idx_q + 2] = (np.cos(value), np.sin(value))
        else:
            q_pin[joint.idx_q] = value
    return q_pin


def _random_q(kin: Kinematics, rng: np.random.Generator) -> np.ndarray:
    lower = np.where(np.isfinite(kin.lower), kin.lower, -np.pi)
    upper = np.where(np.isfinite(kin.upper), kin.upper, np.pi)
    return rng.uniform(lower, upper)


def test_panda_structure(panda: Kinematics) -> None:
    assert panda.dof == 7
    assert panda.joint_names == tuple(f"panda_joint{i}" for i in range(1, 8))
    assert panda.link_names == tuple(f"panda_link{i}" for i in range(9)) + (
        "panda_hand_body", "panda_hand", "panda_leftfinger", "panda_rightfinger")
    assert panda.locked == {"panda_finger_joint1": 0.0}
    np.testing.assert_allclose(panda.lower, [-2.8973, -1.7628, -2.8973, -3.0718,
                                             -2.8973, -0.0175, -2.8973])
    np.testing.assert_allclose(panda.upper, [2.8973, 1.7628, 2.8973, -0.0698,
                                             2.8973, 3.7525, 2.8973])
    np.testing.assert_allclose(panda.velocity_limits, [2.175] * 4 + [2.61] * 3)


def test_panda_every_link_matches_pinocchio(panda: Kinematics) -> None:
    rng = np.random.default_rng(0)
    for _ in range(25):
        q = _random_q(panda, rng)
        model, data = _pin_placements(PANDA_TEXT, to_pinocchio_q(pin.buildModelFromXML(PANDA_TEXT), panda, q))
        for link in panda.link_names:
            expected = data.oMf[model.getFrameId(link)]
            transform = np.array(panda.transform(q, link))
            np.testing.assert_allclose(transform[:3, :3], expected.rotation, atol=1e-10)
            np.testing.assert_allclose(transform[:3, 3], expected.translation, atol=1e-10)
            np.testing.assert_allclose(transform[3], [0, 0, 0, 1], atol=0)
            np.testing.assert_allclose(np.array(panda.position(q, link)).ravel(),
                                       expected.translation, atol=1e-10)
            np.testing.assert_allclose(np.array(panda.rotation(q, link)),
                                       expected.rotation, atol=1e-10)


def test_panda_known_pose_at_zero(panda: Kinematics) -> None:
    # At q = 0 the flange is at x = a7 = 0.088, z = d1 + d3 + d5 - d_flange - tcp.
    hand = np.array(panda.position(np.zeros(7), "panda_hand")).ravel()
    np.testing.assert_allclose(hand, [0.088, 0.0, 0.333 + 0.316 + 0.384 - 0.107 - 0.1034],
                               atol=1e-12)


def test_relative_to_parent_and_offset_match_pinocchio(panda: Kinematics) -> None:
    rng = np.random.default_rng(1)
    links = panda.link_names
    for _ in range(20):
        q = _random_q(panda, rng)
        model, data = _pin_placements(PANDA_TEXT, to_pinocchio_q(pin.buildModelFromXML(PANDA_TEXT), panda, q))
        link, parent = rng.choice(links, size=2, replace=False)
        offset = rng.normal(size=3) * 0.1
        relative = data.oMf[model.getFrameId(parent)].actInv(
            data.oMf[model.getFrameId(link)])
        transform = np.array(panda.transform(q, link, parent))
        np.testing.assert_allclose(transform[:3, :3], relative.rotation, atol=1e-10)
        np.testing.assert_allclose(transform[:3, 3], relative.translation, atol=1e-10)
        np.testing.assert_allclose(np.array(panda.rotation(q, link, parent)),
                                   relative.rotation, atol=1e-10)
        point = np.array(panda.position(q, link, parent, offset=offset)).ravel()
        np.testing.assert_allclose(point, relative.act(offset), atol=1e-10)


def test_small_urdf_prismatic_continuous_matches_pinocchio() -> None:
    kin = Kinematics(parse_urdf(SMALL_TEXT))
    assert kin.joint_names == ("slide", "spin", "side_joint")
    assert kin.lower[1] == -np.inf and kin.upper[1] == np.inf
    rng = np.random.default_rng(2)
    for _ in range(20):
        q = _random_q(kin, rng) * 2.0  # continuous joint beyond +-pi too
        model, data = _pin_placements(SMALL_TEXT, to_pinocchio_q(pin.buildModelFromXML(SMALL_TEXT), kin, q))
        for link in kin.link_names:
            expected = data.oMf[model.getFrameId(link)]
            transform = np.array(kin.transform(q, link))
            np.testing.assert_allclose(transform[:3, :3], expected.rotation, atol=1e-10)
            np.testing.assert_allclose(transform[:3, 3], expected.translation, atol=1e-10)
        # tool relative to a sibling branch (common ancestor is "slider")
        relative = data.oMf[model.getFrameId("side")].actInv(
            data.oMf[model.getFrameId("tool")])
        np.testing.assert_allclose(np.array(kin.transform(q, "tool", "side")),
                                   relative.homogeneous, atol=1e-10)
        np.testing.assert_allclose(
            np.array(kin.position(q, "tool", "side", offset=(0.1, 0.2, 0.3))).ravel(),
            relative.act(np.array([0.1, 0.2, 0.3])), atol=1e-10)


def test_mimic_joint_follows_its_leader() -> None:
    text = SMALL_TEXT.replace(
        '<axis xyz="0 -1 0"/>',
        '<axis xyz="0 -1 0"/><mimic joint="slide" multiplier="2" offset="0.1"/>')
    kin = Kinematics(parse_urdf(text))
    assert kin.joint_names == ("slide", "spin")
    plain = Kinematics(parse_urdf(SMALL_TEXT))
    q = np.array([0.3, -0.8])
    np.testing.assert_allclose(np.array(kin.transform(q, "side")),
                               np.array(plain.transform([0.3, -0.8, 0.7], "side")),
                               atol=1e-14)


def _fd_jacobian(f, q: np.ndarray, eps: float = 1e-6) -> np.ndarray:
    columns = []
    for i in range(q.size):
        step = np.zeros_like(q)
        step[i] = eps
        columns.append((f(q + step) - f(q - step)) / (2 * eps))
    return np.stack(columns, axis=-1)


@pytest.mark.parametrize("link", ["panda_link3", "panda_link6", "panda_hand"])
def test_position_jacobian_and_jdot_qdot_match_finite_differences(
        panda: Kinematics, link: str) -> None:
    q_sym, qdot_sym = ca.SX.sym("q", 7), ca.SX.sym("qdot", 7)
    offset = (0.03, -0.02, 0.05)
    x = panda.position(q_sym, link, offset=offset)
    jac = ca.jacobian(x, q_sym)
    jdot_qdot = ca.jtimes(jac @ qdot_sym, q_sym, qdot_sym)
    f_x = ca.Function("x", [q_sym], [x])
    f_jac = ca.Function("J", [q_sym], [jac])
    f_jdot = ca.Function("Jdq", [q_sym, qdot_sym], [jdot_qdot])
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = _random_q(panda, rng)
        qdot = rng.normal(size=7)
        fd_jac = _fd_jacobian(lambda v: np.array(f_x(v)).ravel(), q)
        np.testing.assert_allclose(np.array(f_jac(q)), fd_jac, atol=1e-8)
        # d/dt (J(q) qdot) along q(t) = q + t qdot, by central differences in t
        eps = 1e-6
        fd_jdot = (np.array(f_jac(q + eps * qdot)) - np.array(f_jac(q - eps * qdot))) \
            @ qdot / (2 * eps)
        np.testing.assert_allclose(np.array(f_jdot(q, qdot)).ravel(), fd_jdot, atol=1e-7)


def test_numeric_sx_and_mx_evaluations_agree(panda: Kinematics) -> None:
    q_sx, q_mx = ca.SX.sym("q", 7), ca.MX.sym("q", 7)
    points = [("panda_link4", (0.0, 0.1, 0.0)), ("panda_hand", (0.0, 0.0, -0.05))]
    f_sx = ca.Function("f", [q_sx], [panda.transform(q_sx, "panda_hand", "panda_link2"),
                                     panda.positions(q_sx, points)])
    f_mx = ca.Function("f", [q_mx], [panda.transform(q_mx, "panda_hand", "panda_link2"),
                                     panda.positions(q_mx, points)])
    assert isinstance(panda.transform(q_sx, "panda_hand"), ca.SX)
    assert isinstance(panda.transform(q_mx, "panda_hand"), ca.MX)
    rng = np.random.default_rng(4)
    for _ in range(5):
        q = _random_q(panda, rng)
        numeric = [panda.transform(q, "panda_hand", "panda_link2"),
                   panda.positions(q, points)]
        assert all(isinstance(value, ca.DM) for value in numeric)
        for evaluated in (f_sx(q), f_mx(q)):
            for got, want in zip(evaluated, numeric):
                np.testing.assert_allclose(np.array(got), np.array(want), atol=1e-14)
        rows = np.array(numeric[1])
        for row, (link, offset) in zip(rows, points):
            np.testing.assert_allclose(
                row, np.array(panda.position(q, link, offset=offset)).ravel(), atol=1e-14)


def test_q_as_list_row_and_wrong_size(panda: Kinematics) -> None:
    q = [0.1, 0.2, 0.3, -1.0, 0.5, 1.0, 0.2]
    column = np.array(panda.position(q, "panda_hand"))
    np.testing.assert_allclose(np.array(panda.position(np.array([q]), "panda_hand")), column)
    np.testing.assert_allclose(np.array(panda.position(ca.DM(q).T, "panda_hand")), column)
    with pytest.raises(ValueError, match="7 elements"):
        panda.position(np.zeros(6), "panda_hand")
    with pytest.raises(ValueError, match="7 elements"):
        panda.position(ca.SX.sym("q", 8), "panda_hand")


def test_unknown_link_names_link_and_valid_ones(panda: Kinematics) -> None:
    with pytest.raises(UnknownLinkError, match="'panda_link9'.*panda_link0.*panda_hand"):
        panda.position(np.zeros(7), "panda_link9")
    with pytest.raises(ValueError, match="'nowhere'"):
        panda.transform(np.zeros(7), "panda_hand", parent="nowhere")
    with pytest.raises(UnknownLinkError, match="'gripper'"):
        panda.positions(np.zeros(7), [("gripper", (0, 0, 0))])
    with pytest.raises(UnknownLinkError, match="'base'"):
        Kinematics(parse_urdf(PANDA_TEXT), root_link="base")


def test_subtree_root(panda: Kinematics) -> None:
    sub = Kinematics(parse_urdf(PANDA_TEXT), root_link="panda_link4", joints=PANDA_JOINTS[4:])
    assert sub.joint_names == ("panda_joint5", "panda_joint6", "panda_joint7")
    q = np.array([0.3, 1.2, -0.4])
    full_q = np.concatenate([[0.5, 0.2, -0.1, -1.7], q])
    np.testing.assert_allclose(np.array(sub.transform(q, "panda_hand")),
                               np.array(panda.transform(full_q, "panda_hand", "panda_link4")),
                               atol=1e-14)
    with pytest.raises(UnknownLinkError, match="panda_link2"):
        sub.position(q, "panda_link2")


def test_expressions_stay_small(panda: Kinematics) -> None:
    """Constant folding keeps the hand position to sines, cosines and few products."""
    q = ca.SX.sym("q", 7)
    hand = ca.Function("hand", [q], [panda.position(q, "panda_hand")])
    assert hand.n_instructions() <= 80
    # q7 rotates about the hand's own axis: the hand position must not depend on it
    assert not ca.depends_on(panda.position(q, "panda_hand"), q[6])
    centres = ca.Function("c", [q], [panda.positions(
        q, [(link, (0.0, 0.0, 0.05)) for link in panda.link_names])])
    assert centres.n_instructions() <= 320
