"""Control-loop adapters: set-points at the servo rate, and the commands of each interface,
including the examples that drive MuJoCo through them."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from dynfab.sim.control_interfaces import (PositionInterface, Setpoint, SetpointIntegrator, TorqueInterface,
                                           VelocityInterface, interface_for)

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_setpoints_integrate_a_held_acceleration_exactly() -> None:
    setpoints = SetpointIntegrator(servo_period=0.001)
    q0, v0, a = np.array([0.1, -0.2]), np.array([0.5, 0.0]), np.array([2.0, -1.0])
    setpoints.reset(q0, v0)
    setpoints.hold(a)
    for _ in range(10):
        last = setpoints.advance()
    t = 0.01
    np.testing.assert_allclose(last.position, q0 + v0 * t + 0.5 * a * t * t, atol=1e-15)
    np.testing.assert_allclose(last.velocity, v0 + a * t, atol=1e-15)
    setpoints.hold(np.zeros(2))  # continuous: a new command starts where the last one ended
    np.testing.assert_allclose(setpoints.advance().position, last.position + last.velocity * 0.001, atol=1e-15)


def test_setpoints_stop_at_the_position_limits() -> None:
    setpoints = SetpointIntegrator(servo_period=0.01, lower=[-1.0, -np.inf], upper=[0.1, np.inf])
    setpoints.reset([0.0, 0.0], [1.0, 1.0])
    setpoints.hold([0.0, 0.0])
    positions = [setpoints.advance() for _ in range(20)]
    assert positions[-1].position[0] == 0.1 and positions[-1].velocity[0] == 0.0  # held at the limit
    assert positions[-1].acceleration[0] == 0.0
    assert positions[-1].position[1] == pytest.approx(0.2) and positions[-1].velocity[1] == 1.0


def test_setpoints_refuse_misuse() -> None:
    setpoints = SetpointIntegrator(servo_period=0.001)
    with pytest.raises(RuntimeError, match="before reset"):
        setpoints.advance()
    with pytest.raises(ValueError, match="reset"):
        setpoints.hold([1.0])
    setpoints.reset([0.0, 0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="one acceleration per joint"):
        setpoints.hold([1.0])
    with pytest.raises(ValueError, match="servo_period"):
        SetpointIntegrator(servo_period=0.0)


def test_interfaces_command_what_their_controller_takes() -> None:
    setpoint = Setpoint(np.array([1.0, 2.0]), np.array([0.1, 0.2]), np.array([3.0, -4.0]))
    q, qdot = np.array([0.9, 2.0]), np.array([0.1, 0.0])
    assert PositionInterface().command(setpoint, q, qdot) is setpoint.position
    assert VelocityInterface().command(setpoint, q, qdot) is setpoint.velocity
    masses = np.array([2.0, 0.5])
    torque = TorqueInterface(lambda q, qd, qdd: masses * qdd + 1.0, stiffness=100.0, damping=20.0,
                             effort=np.array([100.0, 2.0]))
    # τ = m (q̈_d + K_p (q_d − q) + K_d (q̇_d − q̇)) + 1, clipped to ±effort
    expected = [2.0 * (3.0 + 100.0 * 0.1 + 0.0) + 1.0, np.clip(0.5 * (-4.0 + 0.0 + 20.0 * 0.2) + 1.0, -2, 2)]
    np.testing.assert_allclose(torque.command(setpoint, q, qdot), expected)
    clipped = TorqueInterface(lambda q, qd, qdd: 1e6 * qdd, 100.0, 20.0, np.array([87.0, 12.0]))
    still = Setpoint(setpoint.position, np.zeros(2), setpoint.acceleration)
    np.testing.assert_allclose(clipped.command(still, setpoint.position, np.zeros(2)), [87.0, -12.0])
    with pytest.raises(ValueError, match="current"):
        interface_for("current", lambda q, qd, qdd: qdd, np.ones(2))


@pytest.mark.parametrize("mode", ["position", "velocity", "torque"])
def test_example_reaches_its_goal_through_the_interface(mode: str) -> None:
    completed = subprocess.run([sys.executable, str(EXAMPLES / f"mujoco_{mode}_control.py")], capture_output=True,
                               text=True, timeout=600, check=True)
    match = re.search(rf"^{mode} control: .*, error ([0-9.]+) mm$", completed.stdout, re.MULTILINE)
    assert match is not None and float(match.group(1)) < 1.0, completed.stdout   # docs/guides/controllers.md: < 1 mm
