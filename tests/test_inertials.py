"""Link inertials read from URDF files: values as pinocchio reads them, and the built-in
robots' identified / published parameters."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robot_files import arm_urdf

from dynfab.robots import load_robot, load_urdf, parse_urdf
from dynfab.robots.urdf import UrdfError


def test_ur5_inertials_match_pinocchio() -> None:
    path = arm_urdf("ur5")
    model = load_urdf(path)
    reference = pin.buildModelFromUrdf(str(path))
    links = {link.name: link for link in model.links}
    checked = 0
    for frame in reference.frames:
        if frame.type != pin.FrameType.BODY or frame.name not in links or links[frame.name].inertial is None:
            continue
        joint_id = frame.parentJoint
        if reference.names[joint_id] == "universe" or model.parent_joint(frame.name).name != reference.names[joint_id]:
            continue  # bodies fixed to another link are merged by pinocchio
        inertial = links[frame.name].inertial
        body = reference.inertias[joint_id]
        assert inertial.mass == pytest.approx(body.mass, rel=1e-12)
        np.testing.assert_allclose(inertial.origin.xyz, body.lever, atol=1e-12)
        np.testing.assert_allclose(inertial.link_frame_inertia(), body.inertia, atol=1e-12)
        checked += 1
    assert checked == 6


def test_rotated_inertial_is_expressed_in_link_axes() -> None:
    text = """<robot name="r"><link name="a"><inertial><origin xyz="0.1 0 0" rpy="0 0 1.5707963267948966"/>
      <mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="2" iyz="0" izz="3"/></inertial></link></robot>"""
    inertial = parse_urdf(text).links[0].inertial
    assert inertial.mass == 2.0
    np.testing.assert_allclose(inertial.link_frame_inertia(), np.diag([2.0, 1.0, 3.0]), atol=1e-12)


@pytest.mark.parametrize("mass", ["-1", "nan"])
def test_invalid_mass_is_refused_naming_the_link(mass: str) -> None:
    text = f"""<robot name="r"><link name="arm"><inertial><mass value="{mass}"/>
      <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link></robot>"""
    with pytest.raises(UrdfError, match=r"<link name='arm'> <inertial>: mass"):
        parse_urdf(text)


def test_builtin_panda_carries_gaz_parameters() -> None:
    links = {link.name: link for link in load_robot("panda").kinematics.model.links}
    masses = [links[f"panda_link{i}"].inertial.mass for i in range(1, 8)]
    np.testing.assert_allclose(masses, [4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 0.735522])
    for link in links.values():
        if link.inertial is not None:
            assert np.all(np.linalg.eigvalsh(link.inertial.link_frame_inertia()) > 0.0), link.name


@pytest.mark.parametrize("name", ["boxer", "boxer-panda"])
def test_boxer_weighs_100_kg(name: str) -> None:
    model = load_robot(name).kinematics.model
    base = [link for link in model.links if not link.name.startswith("panda") and link.inertial is not None]
    assert sum(link.inertial.mass for link in base) == pytest.approx(100.0)
