"""The compiled dynamic planner is exactly dynamically unbiased: started on a moving
reference, with no obstacle, the goal link stays on it (the base energy is pulled
dynamically with the joint-space reference of dynfab/fabric/joint_reference.py)."""

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.joint_reference import joint_reference, reference_damping
from dynfab.fabric.maps import DifferentialMap, Reference
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots import load_robot

RADIUS, RATE = 0.1, 1.0   # circle [m], angular rate [rad/s]


def _circle(centre: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    c, s = np.cos(RATE * t), np.sin(RATE * t)
    return (centre + RADIUS * np.array([c, s, 0.0]), RADIUS * RATE * np.array([-s, c, 0.0]),
            -RADIUS * RATE**2 * np.array([c, s, 0.0]))


def test_a_panda_started_on_a_moving_reference_stays_on_it() -> None:
    robot = load_robot("panda")
    planner = FabricPlanner(robot, PlannerConfig(goals=(GoalConfig(link="panda_hand"),), dynamic=True,
                                                 self_collision=None, bound_command=False))
    q = np.array(robot.default_q)
    hand = lambda q: np.array(robot.kinematics.position(q, "panda_hand"), dtype=float).ravel()  # noqa: E731
    centre = hand(q) - [RADIUS, 0.0, 0.0]

    def acceleration(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        position, velocity, accel = _circle(centre, t)
        planner.parameters.goal_position[0][:] = position
        planner.parameters.goal_velocity[0][:] = velocity
        planner.parameters.goal_acceleration[0][:] = accel
        return planner.compute(q, v)

    symbols = ca.SX.sym("q", 7)
    jacobian = ca.Function("J", [symbols], [ca.jacobian(robot.kinematics.position(symbols, "panda_hand"), symbols)])
    v = np.linalg.pinv(np.array(jacobian(q))) @ _circle(centre, 0.0)[1]
    h, t, worst = 2e-3, 0.0, 0.0
    for _ in range(1000):   # 2 s of RK4, a third of a turn
        k1q, k1v = v, acceleration(t, q, v)
        k2q, k2v = v + h / 2 * k1v, acceleration(t + h / 2, q + h / 2 * k1q, v + h / 2 * k1v)
        k3q, k3v = v + h / 2 * k2v, acceleration(t + h / 2, q + h / 2 * k2q, v + h / 2 * k2v)
        k4q, k4v = v + h * k3v, acceleration(t + h, q + h * k3q, v + h * k3v)
        q, v, t = q + h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q), v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v), t + h
        worst = max(worst, float(np.linalg.norm(hand(q) - _circle(centre, t)[0])))
    assert worst < 1e-6   # was 2.6 mm with a static base energy and a constant damping


def test_the_pseudo_inverse_is_exact_away_from_singularities_and_damped_at_them() -> None:
    regular = ca.DM([[1.0, 0.0, 0.2], [0.0, 0.8, 0.1]])
    singular = ca.DM([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    assert float(ca.evalf(reference_damping(ca.SX(regular), 0.05))) == 0.0
    assert float(ca.evalf(reference_damping(ca.SX(singular), 0.05))) == pytest.approx(0.05**2)


def test_the_joint_reference_moves_the_task_with_the_reference() -> None:
    """``J q̇̃ = ẋ̃`` and ``J q̈̃ + J̇ q̇ = ẍ̃`` at a regular configuration."""
    q, qdot = ca.SX.sym("q", 3), ca.SX.sym("qdot", 3)
    task = DifferentialMap.from_expression(ca.vertcat(ca.cos(q[0]) + q[1] * q[2], ca.sin(q[1]) * q[0]), q, qdot)
    reference = Reference(ca.DM.zeros(2), ca.DM([0.3, -0.2]), ca.DM([1.0, 0.5]))
    velocity, acceleration = joint_reference(task, reference, 0.05)
    check = ca.Function("check", [q, qdot], [ca.mtimes(task.jacobian, velocity),
                                             ca.mtimes(task.jacobian, acceleration) + task.jdot_qdot])
    rng = np.random.default_rng(3)
    for _ in range(5):
        task_velocity, task_acceleration = check(rng.uniform(0.3, 1.0, 3), rng.normal(size=3))
        np.testing.assert_allclose(np.array(task_velocity).ravel(), [0.3, -0.2], atol=1e-12)
        np.testing.assert_allclose(np.array(task_acceleration).ravel(), [1.0, 0.5], atol=1e-12)
