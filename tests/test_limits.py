"""Motion limits of robots: where they come from and how they are checked."""

import math

import numpy as np
import pytest

from dynfab.robots import LimitsError, MotionLimits, load_robot, robot_from_urdf
from robot_files import arm_urdf

from dynfab.robots.limits import (BOXER_ACCELERATION, DEFAULT_ACCELERATION, DEFAULT_VELOCITY, FRANKA_ACCELERATION,
                                  limits_from_joints)


def test_builtin_panda_carries_frankas_published_limits():
    limits = load_robot("panda").limits
    assert limits.names == tuple(f"panda_joint{i}" for i in range(1, 8))
    np.testing.assert_allclose(limits.velocity, [2.175] * 4 + [2.61] * 3)
    np.testing.assert_allclose(limits.acceleration, FRANKA_ACCELERATION)
    np.testing.assert_allclose(limits.effort, [87] * 4 + [12] * 3)
    assert limits.jerk is None


def test_base_limits_are_on_forward_speed_and_yaw_rate():
    robot = load_robot("boxer-panda")
    assert robot.limits.names[:3] == ("v", "omega", "panda_joint1")
    assert robot.limits.velocity[0] == pytest.approx(1.9)
    assert robot.limits.velocity[1] == pytest.approx(2.0)
    np.testing.assert_allclose(robot.limits.acceleration[2:], FRANKA_ACCELERATION)
    assert robot.position_index == (None, None) + tuple(range(3, 10))


def test_boxer_bases_carry_traction_acceleration_limits():
    """Below what the drive wheels can push at friction 1 (about 6.3 m/s²)."""
    for name in ("boxer", "boxer-panda"):
        limits = load_robot(name).limits
        np.testing.assert_allclose(limits.acceleration[:2], BOXER_ACCELERATION)
    assert BOXER_ACCELERATION[0] < 6.3


def test_urdf_robot_reads_velocity_limits_and_defaults_acceleration():
    robot = robot_from_urdf(arm_urdf("ur5"), "tool0", ())
    assert robot.limits.names == robot.kinematics.joint_names
    np.testing.assert_allclose(robot.limits.velocity, robot.kinematics.velocity_limits)
    np.testing.assert_allclose(robot.limits.acceleration, DEFAULT_ACCELERATION)


def test_missing_or_zero_velocity_gets_the_default():
    limits = limits_from_joints(("a", "b", "c"), np.array([math.inf, 0.0, 1.5]))
    np.testing.assert_allclose(limits.velocity, [DEFAULT_VELOCITY, DEFAULT_VELOCITY, 1.5])
    assert limits.effort is None


@pytest.mark.parametrize("bad, message", [
    ([1.0, 0.0], r"limits.acceleration\[1\]: must be a positive finite number, got 0.0"),
    ([1.0, -2.0], r"limits.acceleration\[1\]"),
    ([math.nan, 1.0], r"limits.acceleration\[0\]"),
    ([1.0, math.inf], r"limits.acceleration\[1\]"),
    ([1.0], r"limits.acceleration: must have 2 values"),
    ("fast", r"limits.acceleration: must be a list of 2 numbers"),
])
def test_limits_that_are_not_positive_and_finite_are_refused(bad, message):
    with pytest.raises(LimitsError, match=message):
        MotionLimits(("a", "b"), np.ones(2), bad)


def test_ratios_are_the_largest_share_of_the_limit():
    limits = MotionLimits(("a", "b"), np.array([1.0, 2.0]), np.array([10.0, 5.0]))
    assert limits.velocity_ratio(np.array([[0.5, -3.0], [0.1, 0.1]])) == pytest.approx(1.5)
    assert limits.acceleration_ratio(np.array([[-10.0, 1.0]])) == pytest.approx(1.0)
    assert limits.acceleration_ratio(np.zeros((0, 2))) == 0.0


def test_limits_must_name_the_robots_velocity_coordinates():
    import dataclasses
    robot = load_robot("point")
    wrong = MotionLimits(("x",), np.ones(1), np.ones(1))
    with pytest.raises(ValueError, match="velocity coordinates joint_x, joint_y"):
        dataclasses.replace(robot, limits=wrong)


def _scenario_with_limits(tmp_path, limits) -> str:
    import yaml
    data = {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 1.0, "guidance": False,
            "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
            "goal": [{"type": "position", "link": "panda_hand", "position": [0.5, 0.3, 0.5], "tolerance": 0.02}],
            "limits": limits}
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return str(path)


@pytest.mark.parametrize("limits, message", [
    ({"acceleration": [1, 1, 1, 1, 1, 1, 0]}, "limits.acceleration[6]: must be positive, got 0"),
    ({"velocity": [1, 1, -1, 1, 1, 1, 1]}, "limits.velocity[2]: must be positive, got -1"),
    ({"jerk": [float("nan")] * 7}, "limits.jerk[0]: expected a finite number, got nan"),
    ({"acceleration": [1, 1, 1]}, "limits.acceleration: must have 7 values (one per velocity coordinate), got 3"),
    ({"torque": [1] * 7}, "limits"),
    ({"headroom": 0.6}, "limits.headroom: must be at most 0.5"),
    ({"headroom": -0.1}, "limits.headroom: must be >= 0, got -0.1"),
])
def test_bad_scenario_limits_are_one_line_errors_with_exit_2(tmp_path, capsys, limits, message) -> None:
    from dynfab.cli import main
    assert main(["run", _scenario_with_limits(tmp_path, limits)]) == 2
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert message in error and "Traceback" not in error


def test_scenario_limits_bound_the_run(tmp_path, capsys) -> None:
    import json
    from dynfab.cli import main
    assert main(["run", _scenario_with_limits(tmp_path, {"acceleration": [0.5] * 7, "velocity": [0.3] * 7}),
                 "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["max_acceleration_ratio"] <= 1.0 + 1e-9
    assert metrics["max_velocity_ratio"] <= 1.0 + 1e-9
    assert metrics["max_acceleration_ratio"] > 0.9   # the limit was binding


def test_headroom_keeps_the_planner_below_the_limits_by_that_fraction(tmp_path, capsys) -> None:
    import json
    from dynfab.cli import main
    assert main(["run", _scenario_with_limits(tmp_path, {"velocity": [0.3] * 7, "headroom": 0.2}), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert 0.75 < metrics["max_velocity_ratio"] <= 0.8 + 1e-9   # binding at (1 - 0.2) of the full limit


def test_headroom_defaults_to_zero_kinematic_and_to_the_physics_value_under_mujoco() -> None:
    from dynfab.scenario.limits_schema import PHYSICS_HEADROOM, LimitsSpec
    assert LimitsSpec().headroom_for("kinematic") == 0.0
    assert LimitsSpec().headroom_for("mujoco") == PHYSICS_HEADROOM > 0.0
    assert LimitsSpec(headroom=0.0).headroom_for("mujoco") == 0.0
    robot = load_robot("panda")
    np.testing.assert_allclose(robot.limits.with_headroom(0.1).velocity, 0.9 * robot.limits.velocity)
