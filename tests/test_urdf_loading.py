"""Robot descriptions as they ship: every URDF of example-robot-data and pybullet_data that
pinocchio loads loads here too, and its forward kinematics matches pinocchio's."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest
from robot_files import arm_urdf, shipped_urdfs

from dynfab.robots import Kinematics, UrdfError, load_urdf, parse_urdf
from dynfab.robots.mesh_paths import PACKAGE_PATH_VARIABLE
from dynfab.robots.urdf import MeshFile


def _pinocchio_configuration(model: pin.Model, values: dict[str, float]) -> np.ndarray:
    """Pinocchio's q for joint values by name (continuous joints as cos, sin)."""
    q = pin.neutral(model)
    for joint_id in range(1, model.njoints):
        joint = model.joints[joint_id]
        value = values.get(model.names[joint_id], 0.0)
        if joint.nq == 1:
            q[joint.idx_q] = value
        else:
            assert joint.nq == 2, f"unexpected joint {model.names[joint_id]} with nq={joint.nq}"
            q[joint.idx_q:joint.idx_q + 2] = (np.cos(value), np.sin(value))
    return q


def _all_link_transforms(kin: Kinematics) -> ca.Function:
    q = ca.SX.sym("q", kin.dof)
    return ca.Function("links", [q], [ca.vertcat(*[ca.reshape(kin.transform(q, link).T, 16, 1)
                                                     for link in kin.link_names])])


def _fk_error(path: Path, rng: np.random.Generator) -> float:
    """Largest difference of any link pose entry between dynfab and pinocchio [m or -]."""
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    kin = Kinematics(load_urdf(path))
    transforms = _all_link_transforms(kin)
    worst = 0.0
    for _ in range(2):
        low = np.where(np.isfinite(kin.lower), kin.lower, -np.pi)
        high = np.where(np.isfinite(kin.upper), kin.upper, np.pi)
        q = rng.uniform(low, high)
        values = dict(zip(kin.joint_names, q))
        for joint in kin.model.joints:  # pinocchio moves mimic joints independently
            if joint.mimic is not None:
                values[joint.name] = joint.mimic.multiplier * values[joint.mimic.joint] + joint.mimic.offset
        pin.framesForwardKinematics(model, data, _pinocchio_configuration(model, values))
        ours = np.array(transforms(q)).reshape(-1, 4, 4)
        for k, link in enumerate(kin.link_names):
            frame = model.getFrameId(link, pin.BODY)
            assert frame < model.nframes, f"pinocchio has no frame for link {link}"
            worst = max(worst, float(np.abs(data.oMf[frame].homogeneous - ours[k]).max()))
    return worst


def test_every_shipped_urdf_that_pinocchio_loads_loads_with_exact_kinematics() -> None:
    rng = np.random.default_rng(0)
    checked, failures = 0, []
    for path in shipped_urdfs():
        try:
            pin.buildModelFromUrdf(str(path))
        except (RuntimeError, ValueError):
            continue  # files pinocchio itself refuses (spherical joints, broken XML)
        checked += 1
        try:
            error = _fk_error(path, rng)
        except (UrdfError, ValueError, AssertionError) as exc:
            failures.append(f"{path.name}: {exc}")
            continue
        if error > 1e-9:
            failures.append(f"{path.name}: link pose differs by {error:.2e}")
    assert checked > 1000, f"only {checked} shipped URDFs found"
    assert not failures, f"{len(failures)} of {checked} failed: " + "; ".join(failures[:10])


def test_joint_order_and_locked_joints_follow_the_request() -> None:
    path = arm_urdf("panda")
    full = Kinematics(load_urdf(path))
    assert full.joint_names[-1] == "panda_finger_joint1"  # a gripper joint is movable
    arm = [f"panda_joint{i}" for i in range(1, 8)]
    kin = Kinematics(load_urdf(path), joints=list(reversed(arm)), locked={"panda_finger_joint1": 0.03})
    assert kin.joint_names == tuple(reversed(arm)) and kin.dof == 7
    assert kin.locked == {"panda_finger_joint1": 0.03}
    q = np.random.default_rng(1).uniform(kin.lower, kin.upper)
    q_full = np.concatenate([q[::-1], [0.03]])
    for link in ("panda_hand_tcp", "panda_leftfinger", "panda_rightfinger"):
        np.testing.assert_allclose(np.array(kin.transform(q, link)), np.array(full.transform(q_full, link)),
                                   atol=1e-12)
    # the mimic finger follows the locked leader: fingers 2 x 0.03 m apart along the hand's y
    left = np.array(kin.position(q, "panda_leftfinger")).ravel()
    right = np.array(kin.position(q, "panda_rightfinger")).ravel()
    assert np.linalg.norm(left - right) == pytest.approx(0.06, abs=1e-12)
    # unlisted joints lock at 0 clipped into their limits
    default = Kinematics(load_urdf(path), joints=arm)
    assert default.locked == {"panda_finger_joint1": 0.0}


@pytest.mark.parametrize(("joints", "locked", "pattern"), [
    (["panda_joint1", "wrist"], None, "joints: 'wrist' is not a movable joint.*panda_joint1"),
    (["panda_joint1", "panda_joint1"], None, "named twice"),
    (["panda_joint1", "panda_finger_joint2"], None, "'panda_finger_joint2' is not a movable"),
    (None, {"panda_joint1": 0.0}, "locked: 'panda_joint1' is active"),
    (["panda_joint1"], {"elbow": 0.0}, "locked: 'elbow' is not a movable joint.*panda_joint2"),
    (["panda_joint1"], {"panda_joint2": float("nan")}, "must be a finite number"),
])
def test_unknown_or_misused_joint_names_are_named(joints, locked, pattern) -> None:
    with pytest.raises(ValueError, match=pattern):
        Kinematics(load_urdf(arm_urdf("panda")), joints=joints, locked=locked)


def test_fixed_joint_axis_is_ignored_and_dangling_mimic_moves_on_its_own() -> None:
    text = ("<robot name='r'><link name='a'/><link name='b'/><link name='c'/>"
            "<joint name='f' type='fixed'><parent link='a'/><child link='b'/><axis xyz='0 0 0'/></joint>"
            "<joint name='j' type='continuous'><parent link='b'/><child link='c'/>"
            "<mimic joint='missing'/></joint></robot>")
    model = parse_urdf(text)
    kin = Kinematics(model)
    assert kin.joint_names == ("j",) and np.isinf(kin.lower[0]) and np.isinf(kin.upper[0])


def test_lower_above_upper_means_no_position_limit() -> None:
    text = ("<robot name='r'><link name='a'/><link name='b'/>"
            "<joint name='j' type='prismatic'><parent link='a'/><child link='b'/>"
            "<limit lower='1' upper='-1' velocity='1'/></joint></robot>")
    kin = Kinematics(parse_urdf(text))
    assert kin.lower[0] == -np.inf and kin.upper[0] == np.inf


def _robot_with_mesh(uri: str) -> str:
    return ("<robot name='r'><link name='a'><collision><origin xyz='0 0 0.1' rpy='0 0 1.5707963267948966'/>"
            f"<geometry><mesh filename='{uri}' scale='2 2 2'/></geometry></collision>"
            "<collision><geometry><box size='0.1 0.2 0.3'/></geometry></collision></link></robot>")


def test_mesh_uris_resolve_like_a_ros_workspace(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    package = tmp_path / "ws" / "my_arm"
    (package / "meshes").mkdir(parents=True)
    (package / "urdf").mkdir()
    (package / "meshes" / "base.stl").write_bytes(b"solid x\nendsolid x\n")
    # package:// found from the URDF's own folder upwards, relative to the URDF, file://
    for uri in ("package://my_arm/meshes/base.stl", "../meshes/base.stl",
                f"file://{package / 'meshes' / 'base.stl'}"):
        urdf = package / "urdf" / "arm.urdf"
        urdf.write_text(_robot_with_mesh(uri))
        link = load_urdf(urdf).links[0]
        mesh = link.collisions[0].shape
        assert isinstance(mesh, MeshFile) and mesh.uri == uri and mesh.scale == (2.0, 2.0, 2.0)
        assert Path(mesh.path) == (package / "meshes" / "base.stl").resolve()
        np.testing.assert_allclose(link.collisions[0].origin.xyz, (0, 0, 0.1))
        np.testing.assert_allclose(np.array(link.collisions[0].origin.rotation) @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    # a URDF copied elsewhere finds the package through package_dirs or DYNFAB_PACKAGE_PATH
    elsewhere = tmp_path / "elsewhere" / "arm.urdf"
    elsewhere.parent.mkdir()
    shutil.copy(package / "urdf" / "arm.urdf", elsewhere)
    elsewhere.write_text(_robot_with_mesh("package://my_arm/meshes/base.stl"))
    assert load_urdf(elsewhere).links[0].collisions[0].shape.path is None
    assert load_urdf(elsewhere, package_dirs=[tmp_path / "ws"]).links[0].collisions[0].shape.path is not None
    monkeypatch.setenv(PACKAGE_PATH_VARIABLE, os.pathsep.join(["/nonexistent", str(tmp_path / "ws")]))
    assert load_urdf(elsewhere).links[0].collisions[0].shape.path is not None


def test_shipped_arms_resolve_every_collision_mesh() -> None:
    for name in ("ur5", "kinova", "xarm7", "panda", "z1"):
        model = load_urdf(arm_urdf(name))
        meshes = [c.shape for link in model.links for c in link.collisions if isinstance(c.shape, MeshFile)]
        assert meshes, name
        assert all(mesh.path is not None and Path(mesh.path).is_file() for mesh in meshes), name


@pytest.mark.parametrize(("geometry", "pattern"), [
    ("<box size='0 1 1'/>", "link name='a'.*<collision>.*box size"),
    ("<sphere radius='-1'/>", "link name='a'.*<collision>.*sphere radius"),
    ("<cylinder radius='nan' length='1'/>", "link name='a'.*<collision>.*cylinder radius"),
])
def test_degenerate_collision_primitives_are_named(geometry: str, pattern: str) -> None:
    text = f"<robot name='r'><link name='a'><collision><geometry>{geometry}</geometry></collision></link></robot>"
    with pytest.raises(UrdfError, match=pattern) as info:
        parse_urdf(text)
    assert "\n" not in str(info.value)


def _panda_scenario(extra: dict) -> dict:
    robot = {"urdf": "package://example-robot-data/robots/panda_description/urdf/panda.urdf",
             "goal_link": "panda_hand_tcp",
             "collision_spheres": [{"link": "panda_hand", "center": [0, 0, 0.05], "radius": 0.08}]}
    return {"robot": {**robot, **extra}, "planner": "static-fabric", "dt": 0.01, "duration": 4.0,
            "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
            "goal": [{"type": "position", "position": [0.5, -0.3, 0.4], "tolerance": 0.05}]}


def test_a_shipped_urdf_runs_with_chosen_and_locked_joints() -> None:
    from dynfab.scenario.runner import run_scenario
    from dynfab.scenario.schema import ScenarioError, scenario_from_dict

    arm = [f"panda_joint{i}" for i in range(1, 8)]
    result = run_scenario(scenario_from_dict(_panda_scenario({"joints": arm, "locked": {"panda_finger_joint1": 0.02}})))
    assert result.metrics.goal_reached and result.robot.dof == 7
    with pytest.raises(ScenarioError, match=r"initial_state.q: expected 8 numbers \(one per joint: panda_joint1, "
                                            r".*panda_joint7, panda_finger_joint1\), got 7"):
        run_scenario(scenario_from_dict(_panda_scenario({})))
    with pytest.raises(ScenarioError, match="robot.locked: 'gripper' is not a movable joint"):
        run_scenario(scenario_from_dict(_panda_scenario({"joints": arm, "locked": {"gripper": 0.0}})))
    with pytest.raises(ScenarioError, match="robot.joints: 'shoulder' is not a movable joint"):
        run_scenario(scenario_from_dict(_panda_scenario({"joints": ["shoulder"]})))
    with pytest.raises(ScenarioError, match="robot.urdf: file not found: package://nowhere/arm.urdf"):
        scenario_from_dict(_panda_scenario({"urdf": "package://nowhere/arm.urdf"}))


def test_link_meshes_are_placed_in_the_link_frame_and_bad_files_are_named(tmp_path: Path) -> None:
    from dynfab.robots.link_meshes import LinkMeshError, link_collision_meshes

    meshes = link_collision_meshes(parse_urdf(_robot_with_mesh("x.stl").replace(
        "<mesh filename='x.stl' scale='2 2 2'/>", "<box size='0.1 0.2 0.4'/>")), "a")
    np.testing.assert_allclose(meshes[0].bounds, [[-0.1, -0.05, -0.1], [0.1, 0.05, 0.3]], atol=1e-12)
    np.testing.assert_allclose(meshes[1].bounds, [[-0.05, -0.1, -0.15], [0.05, 0.1, 0.15]], atol=1e-12)
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(_robot_with_mesh("missing.stl"))
    with pytest.raises(LinkMeshError, match="link 'a': collision mesh 'missing.stl' not found"):
        link_collision_meshes(load_urdf(urdf), "a")
    (tmp_path / "broken.stl").write_bytes(b"\x00\x01 not a mesh")
    urdf.write_text(_robot_with_mesh("broken.stl"))
    with pytest.raises(LinkMeshError, match="link 'a': collision mesh 'broken.stl' cannot be read"):
        link_collision_meshes(load_urdf(urdf), "a")
