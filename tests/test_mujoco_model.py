"""MuJoCo models built from robots: bodies, inertials, joints, collision geometry, errors."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from robot_files import arm_urdf

from dynfab.geometry.shapes import Box, Sphere
from dynfab.robots import load_robot, robot_from_urdf
from dynfab.robots.urdf import parse_urdf
from dynfab.robots.kinematics import Kinematics
from dynfab.robots.robot import Robot
from dynfab.sim.mujoco_model import ARMATURE, LIMIT_MARGIN, MujocoModelError, SceneObstacle, build_scene


def test_panda_bodies_carry_the_identified_inertials() -> None:
    robot = load_robot("panda")
    scene = build_scene(robot)
    model = scene.model
    links = {link.name: link for link in robot.kinematics.model.links}
    for i in range(1, 8):
        body = model.body(f"panda_link{i}")
        assert body.mass[0] == pytest.approx(links[f"panda_link{i}"].inertial.mass)
        principal = np.sort(body.inertia)
        assert principal[0] > 0.0 and principal[0] + principal[1] >= principal[2] - 1e-12  # physical inertia
    assert model.nq == model.nv == model.nu == 7
    assert list(scene.effort) == [87.0] * 4 + [12.0] * 3
    np.testing.assert_allclose(model.jnt_range[:7, 1], robot.kinematics.upper + LIMIT_MARGIN)
    np.testing.assert_allclose(scene.lower, robot.kinematics.lower)


def test_panda_mass_matrix_matches_pinocchio() -> None:
    """The MJCF's frames and inertias give the rigid-body dynamics of the URDF (+ armature)."""
    from importlib import resources

    text = resources.files("dynfab.robots").joinpath("data", "panda.urdf").read_text("utf-8")
    full = pin.buildModelFromXML(text)
    fingers = [full.getJointId(name) for name in full.names if "finger" in name]  # locked, massless
    reference = pin.buildReducedModel(full, fingers, pin.neutral(full))
    pin_data = reference.createData()
    scene = build_scene(load_robot("panda"))
    data = mujoco.MjData(scene.model)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rng.uniform(-1.5, 1.5, 7)
        data.qpos[:] = q
        mujoco.mj_forward(scene.model, data)
        mass = np.zeros((7, 7))
        mujoco.mj_fullM(scene.model, data, mass)
        expected = pin.crba(reference, pin_data, q)
        expected = np.triu(expected) + np.triu(expected, 1).T
        np.testing.assert_allclose(mass - ARMATURE * np.eye(7), expected, atol=1e-9)
        np.testing.assert_allclose(data.qfrc_bias, pin.rnea(reference, pin_data, q, np.zeros(7), np.zeros(7)),
                                   atol=1e-9)


def test_ur5_collides_by_its_meshes() -> None:
    robot = robot_from_urdf(arm_urdf("ur5"), "tool0", ())
    scene = build_scene(robot, (), (("base_link", "forearm_link"),))
    model = scene.model
    assert model.nq == 6 and model.nmesh >= 6
    meshes = [g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH]
    assert len(meshes) == model.nmesh
    assert model.npair == 1
    assert model.body("upper_arm_link").mass[0] > 1.0


def test_boxer_floats_on_wheels_and_casters() -> None:
    scene = build_scene(load_robot("boxer"), [SceneObstacle(Sphere(0.2), (1.0, 0.0, 0.0), (1, 0, 0, 0), True)])
    model = scene.model
    assert scene.base_qpos == 0 and model.nq == 7 + 2  # free joint + two wheels
    assert model.body_subtreemass[model.body("axle_link").id] == pytest.approx(100.0, abs=1e-2)
    assert model.nmocap == 1 and scene.mocap == (0,)
    cylinder = model.geom("obstacle0")
    assert cylinder.type[0] == mujoco.mjtGeom.mjGEOM_CYLINDER  # a disc for the planar robot
    assert {model.geom(g).name for g in range(model.ngeom) if model.geom_contype[g] == 2} == {
        "floor", "wheel_left", "wheel_right", "caster_left_link_wheel", "caster_right_link_wheel"}


def test_obstacles_become_static_geoms_or_mocap_bodies() -> None:
    obstacles = [SceneObstacle(Box((0.2, 0.4, 0.6)), (0.5, 0.0, 0.3), (1, 0, 0, 0), False),
                 SceneObstacle(Sphere(0.1), (0.0, 0.5, 0.3), (1, 0, 0, 0), True)]
    scene = build_scene(load_robot("panda"), obstacles)
    model = scene.model
    np.testing.assert_allclose(model.geom("obstacle0").size, (0.1, 0.2, 0.3))
    assert scene.mocap == (None, 0)
    assert scene.obstacle_of_geom == {model.geom("obstacle0").id: 0, model.geom("obstacle1").id: 1}


def test_link_without_inertial_is_refused_naming_it() -> None:
    text = """<robot name="r"><link name="base"/><link name="arm">
      <collision><geometry><sphere radius="0.1"/></geometry></collision></link>
      <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
      <limit lower="-1" upper="1" velocity="1" effort="1"/></joint></robot>"""
    robot = Robot(name="r", kinematics=Kinematics(parse_urdf(text)), goal_link="arm", collision_spheres=(),
                  self_collision_pairs=(), planar=False, default_q=np.zeros(1))
    with pytest.raises(MujocoModelError, match=r"link 'arm' moves but has no <inertial> mass"):
        build_scene(robot)


def test_mujoco_warnings_go_to_stderr_not_to_a_log_file_in_the_working_directory(tmp_path: Path) -> None:
    code = ("import mujoco, dynfab.sim.mujoco_model\n"
            "m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><body><freejoint/><geom size=\"0.1\"/>"
            "</body></worldbody></mujoco>')\n"
            "d = mujoco.MjData(m); d.qpos[:] = float('nan'); mujoco.mj_step(m, d)\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True)
    assert "mujoco: warning: Nan, Inf or huge value in QPOS" in done.stderr
    assert list(tmp_path.iterdir()) == []  # no MUJOCO_LOG.TXT
