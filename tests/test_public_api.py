"""The public API: ``import dynfab`` is cheap and gives every documented name; parameters
are written one way; ``FabricPlanner.step`` advances the state within the limits; URDFs
load from ``package://`` URIs with fitted spheres."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dynfab
from dynfab.fabric.backends import BACKEND_VARIABLE, default_backend, series_backend
from dynfab.fabric.parameters import AbsentParameter, ParameterError, ParameterLayout
from dynfab.sim.models import DifferentialDrive

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
UR5 = "package://example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"


def test_import_loads_no_heavy_dependency() -> None:
    code = ("import sys, json, dynfab; "
            "print(json.dumps(sorted(m for m in ('casadi', 'ompl', 'mujoco', 'scipy', 'trimesh', 'numpy') "
            "if m in sys.modules)))")
    completed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(completed.stdout) == []


def test_every_public_name_resolves_and_is_documented() -> None:
    names = [name for name in dynfab.__all__ if name != "__version__"]
    assert sorted(names) == sorted(dynfab._EXPORTS), "__all__ and the lazy table must list the same names"
    for name in names:
        value = getattr(dynfab, name)
        assert value.__doc__, f"dynfab.{name} has no docstring"
    assert set(dir(dynfab)) >= set(names)
    with pytest.raises(AttributeError, match="no attribute 'FabricPlaner'"):
        dynfab.FabricPlaner  # noqa: B018 - the typo is the point


def test_backend_default_is_c_unless_the_environment_says_vm(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(BACKEND_VARIABLE, raising=False)
    assert default_backend() == "c"
    assert dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="x"),)).backend == "c"
    monkeypatch.setenv(BACKEND_VARIABLE, "vm")
    assert dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="x"),)).backend == "vm"
    assert series_backend() == "vm"
    monkeypatch.delenv(BACKEND_VARIABLE)
    assert series_backend() == "vm"  # series of short runs stay on the VM unless told
    monkeypatch.setenv(BACKEND_VARIABLE, "c")
    assert series_backend() == "c"
    monkeypatch.setenv(BACKEND_VARIABLE, "gpu")
    with pytest.raises(ValueError, match=r"\$DYNFAB_BACKEND must be one of vm, c, got 'gpu'"):
        default_backend()


def test_every_parameter_is_written_one_slot_at_a_time() -> None:
    layout = ParameterLayout((3, 2), obstacle_slots=2, dynamic=True)
    buffer = np.zeros(layout.size)
    p = layout.views(buffer)
    p.goal_position[0] = [1.0, 2.0, 3.0]
    p.goal_position[1] = [4.0, 5.0]
    p.goal_velocity[1] = [6.0, 7.0]
    p.obstacle_position[1] = [8.0, 9.0, 10.0]
    p.obstacle_velocity[0] = [11.0, 12.0, 13.0]
    p.obstacle_radius[1] = 14.0
    assert sorted(buffer[buffer != 0]) == list(np.arange(1.0, 15.0))
    with pytest.raises(ParameterError, match=r"goal_position\[1\] must have shape \(2,\).*got \(3,\)"):
        p.goal_position[1] = [1.0, 2.0, 3.0]


def test_a_static_planner_names_the_parameters_it_lacks() -> None:
    p = ParameterLayout((3,), obstacle_slots=1).views(np.zeros(ParameterLayout((3,), obstacle_slots=1).size))
    for name in ("goal_velocity", "goal_acceleration", "obstacle_velocity", "obstacle_acceleration"):
        absent = getattr(p, name)
        assert isinstance(absent, AbsentParameter) and not absent
        with pytest.raises(ParameterError, match=rf"{name}: this planner has no such parameter; "
                                                 r"build it with PlannerConfig\(\.\.\., dynamic=True\)"):
            absent[0] = [0.0, 0.0, 0.0]
        with pytest.raises(ParameterError, match=name):
            np.asarray(absent)


@pytest.fixture(scope="module")
def boxer_planner() -> dynfab.FabricPlanner:
    robot = dynfab.load_robot("boxer")
    return dynfab.FabricPlanner(robot, dynfab.PlannerConfig.for_robot(robot, (dynfab.GoalConfig(link="base_link"),)))


def test_step_integrates_the_command_over_one_control_period(boxer_planner: dynfab.FabricPlanner) -> None:
    planner = boxer_planner
    planner.parameters.goal_position[0] = [2.0, 1.0]
    q, u = np.array([0.0, 0.0, 0.3]), np.array([0.2, 0.1])
    expected = DifferentialDrive().step(q, u, planner.compute(q, u), planner.config.control_period)
    got = planner.step(q, u)
    np.testing.assert_array_equal(got[0], expected[0])
    np.testing.assert_array_equal(got[1], expected[1])
    assert got[0].shape == (3,) and got[1].shape == (2,)


def test_step_keeps_the_panda_within_its_limits_driving_into_them() -> None:
    robot = dynfab.load_robot("panda")
    planner = dynfab.FabricPlanner(robot, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(joints=(0, 3)),),
                                                               joint_limits=None, self_collision=None))
    kin, limits = robot.kinematics, planner.config.limits
    planner.parameters.goal_position[0] = [kin.upper[0] + 1.0, kin.lower[3] - 1.0]  # beyond both limits
    q, qdot = robot.default_q, np.zeros(robot.dof)
    for _ in range(400):
        q_next, qdot_next = planner.step(q, qdot)
        assert np.all(q_next >= kin.lower - 1e-9) and np.all(q_next <= kin.upper + 1e-9)
        assert np.all(np.abs(qdot_next) <= limits.velocity + 1e-9)
        assert np.all(np.abs(qdot_next - qdot) / planner.config.control_period <= limits.acceleration + 1e-6)
        q, qdot = q_next, qdot_next
    assert q[0] > kin.upper[0] - 0.05 and q[3] < kin.lower[3] + 0.05  # it got there


def test_robot_from_a_package_uri_fits_its_spheres_and_picks_the_tip() -> None:
    robot = dynfab.robot_from_urdf(UR5)
    assert robot.dof == 6 and robot.goal_link == "wrist_3_link"
    assert len(robot.collision_spheres) > 10 and robot.self_collision_pairs
    model = dynfab.auto_collision_model(UR5)
    assert model.spheres == robot.collision_spheres
    with pytest.raises(FileNotFoundError, match=r"package://no_such_robot/x.urdf: no such file"):
        dynfab.robot_from_urdf("package://no_such_robot/x.urdf")


def test_quickstart_dodges_the_sphere_and_reaches_the_goal() -> None:
    env = {**os.environ, BACKEND_VARIABLE: "vm"}
    completed = subprocess.run([sys.executable, str(EXAMPLES / "quickstart.py")], capture_output=True, text=True,
                               timeout=600, check=True, env=env)
    match = re.search(r"hand at \[\s*([-0-9.]+)\s+([-0-9.]+)\s+([-0-9.]+)\]", completed.stdout)
    assert match, completed.stdout + completed.stderr
    np.testing.assert_allclose([float(v) for v in match.groups()], [0.5, -0.3, 0.4], atol=1e-3)
