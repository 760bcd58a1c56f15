"""The MuJoCo loop: tracking under each control mode, the differential-drive base,
contacts, observation delay and noise, and clean stops."""

from __future__ import annotations

import numpy as np
import pytest
from robot_files import arm_urdf

from dynfab.geometry.shapes import Box, Sphere
from dynfab.robots import load_robot, robot_from_urdf
from dynfab.robots.builtin import PANDA_DEFAULT_Q
from dynfab.sim import simulate
from dynfab.sim.mujoco_model import SceneObstacle, build_scene
from dynfab.sim.mujoco_sim import simulate_mujoco

Q0 = np.array(PANDA_DEFAULT_Q)
AMPLITUDE = np.array([0.3, 0.2, 0.3, 0.3, 0.4, 0.3, 0.5])
OMEGA = 2.0


def _sinusoid(t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """q̈ of q(t) = q0 + A sin(ω t) (open loop: ignores the state)."""
    return -AMPLITUDE * OMEGA**2 * np.sin(OMEGA * t)


def _joint_pd(goal: np.ndarray):
    def controller(t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        return 25.0 * (goal - q) - 10.0 * qdot
    return controller


@pytest.mark.parametrize(("control", "tolerance"), [("torque", 2e-3), ("velocity", 2e-2), ("position", 2e-2)])
def test_each_mode_tracks_a_known_acceleration_trajectory(control: str, tolerance: float) -> None:
    scene = build_scene(load_robot("panda"))
    qdot0 = AMPLITUDE * OMEGA
    run = simulate_mujoco(_sinusoid, scene, Q0, qdot0, 0.01, 2.0, control=control)
    ideal = simulate(_sinusoid, Q0, qdot0, 0.01, 2.0)
    assert run.stop_reason is None and run.record.steps == 200
    error = np.abs(run.record.q - ideal.q).max()
    assert error < tolerance, f"{control}: {error:.2e} rad"
    np.testing.assert_allclose(run.record.qddot, ideal.qddot)


def test_torque_control_without_command_holds_the_arm_against_gravity() -> None:
    robot = robot_from_urdf(arm_urdf("ur5"), "tool0", ())
    q0 = np.array([0.0, -1.2, 1.0, -0.5, 0.3, 0.0])
    run = simulate_mujoco(lambda t, q, u: np.zeros(6), build_scene(robot), q0, np.zeros(6), 0.01, 1.0)
    assert np.abs(run.record.q[-1] - q0).max() < 1e-4


def test_base_follows_forward_speed_and_yaw_rate_through_its_wheels() -> None:
    def ramp(t: float, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        return np.array([0.5 if t < 1.0 else 0.0, 0.5 if 2.0 <= t < 3.0 else 0.0])

    run = simulate_mujoco(ramp, build_scene(load_robot("boxer")), np.zeros(3), np.zeros(2), 0.01, 4.0)
    v, omega = run.record.qdot[-1]
    assert v == pytest.approx(0.5, abs=0.02) and omega == pytest.approx(0.5, abs=0.03)
    assert run.record.q[200, 0] == pytest.approx(0.75, abs=0.03)  # 0.25 m while speeding up, then 0.5 m/s
    assert abs(run.record.q[200, 1]) < 1e-3 and abs(run.record.q[200, 2]) < 1e-3
    assert run.record.q[-1, 2] == pytest.approx(0.25 + 0.5, abs=0.05)  # turning: 0.25 rad, then 0.5 rad/s


def test_base_set_point_stops_at_the_velocity_limits_while_the_wheels_lag() -> None:
    """Commanding past the limits (as no bounded planner does) must not wind the wheels'
    set-point up beyond them: the measured speed settles at the limit, not above (the
    transient overshoots by a few percent: the scenario's default headroom under MuJoCo)."""
    robot = load_robot("boxer")
    limit = robot.limits.velocity[:2]
    run = simulate_mujoco(lambda t, q, u: np.array([5.0, 5.0]), build_scene(robot), np.zeros(3), np.zeros(2),
                          0.01, 3.0)
    settled = np.abs(run.record.qdot[-100:]).max(axis=0)
    assert np.all(settled <= 1.01 * limit) and np.all(settled >= 0.95 * limit), settled
    assert np.all(np.abs(run.record.qdot).max(axis=0) <= 1.1 * limit)


def test_obstacle_in_the_way_is_reported_as_a_contact() -> None:
    goal = Q0.copy()
    goal[0] = -0.5  # swing the arm about its base, through the sphere
    obstacle = SceneObstacle(Sphere(0.1), (0.6, 0.15, 0.59), (1.0, 0.0, 0.0, 0.0), False)  # the hand at q1 = 0.25
    run = simulate_mujoco(_joint_pd(goal), build_scene(load_robot("panda"), [obstacle]), Q0, np.zeros(7), 0.01, 2.0)
    assert run.contacts, "the arm went through the sphere without a contact"
    first = run.contacts[0]
    assert first.other == "obstacles[0]" and first.body.startswith("panda_") and 0.0 < first.time < 2.0
    free = simulate_mujoco(_joint_pd(goal), build_scene(load_robot("panda")), Q0, np.zeros(7), 0.01, 2.0)
    assert free.contacts == ()


def test_moving_obstacle_follows_its_track() -> None:
    def centres(times: np.ndarray) -> np.ndarray:
        """A sphere moving at 0.3 m/s along -y from (0.33, 0.8, 0.59) into the resting hand."""
        return np.stack([np.stack([0.33 + 0.0 * times, 0.8 - 0.3 * times, 0.59 + 0.0 * times], axis=-1)], axis=1)

    obstacle = SceneObstacle(Sphere(0.1), (0.33, 0.8, 0.59), (1.0, 0.0, 0.0, 0.0), True)
    seen = []
    run = simulate_mujoco(lambda t, q, u: np.zeros(7), build_scene(load_robot("panda"), [obstacle]), Q0,
                          np.zeros(7), 0.01, 1.0, obstacle_centres=centres,
                          observer=lambda t, data: seen.append(data.mocap_pos[0].copy()))
    np.testing.assert_allclose(seen[-1], (0.33, 0.5, 0.59), atol=1e-9)
    assert any(contact.other == "obstacles[0]" for contact in run.contacts)


def test_delay_and_noise_change_the_run_and_are_seeded() -> None:
    scene = build_scene(load_robot("panda"))
    goal = Q0 + 0.3

    def run(**options: float) -> np.ndarray:
        return simulate_mujoco(_joint_pd(goal), scene, Q0, np.zeros(7), 0.01, 1.0, **options).record.q

    clean = run()
    noisy = run(noise=0.01)
    np.testing.assert_array_equal(noisy, run(noise=0.01))
    assert not np.array_equal(noisy, run(noise=0.01, seed=1))
    assert np.abs(noisy - clean).max() > 1e-3
    delayed = run(delay=0.05)
    assert np.abs(delayed - clean).max() > 1e-3
    overshoot = lambda qs: np.max(qs[:, 0] - goal[0])  # noqa: E731
    assert overshoot(delayed) > overshoot(clean)  # a late observation makes the PD loop overshoot


def test_non_finite_state_stops_the_run_cleanly() -> None:
    def poison(t: float, data: object) -> None:
        if t >= 0.5:
            data.qvel[0] = np.nan

    run = simulate_mujoco(lambda t, q, u: np.zeros(7), build_scene(load_robot("panda")), Q0, np.zeros(7), 0.01,
                          2.0, observer=poison)
    assert run.stop_reason is not None and "t = 0.5" in run.stop_reason
    assert run.record.steps == 50 and np.all(np.isfinite(run.record.q))


def test_non_finite_command_stops_the_run_cleanly() -> None:
    def controller(t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        return np.full(7, np.nan if t > 0.25 else 0.0)

    run = simulate_mujoco(controller, build_scene(load_robot("panda")), Q0, np.zeros(7), 0.01, 1.0)
    assert run.stop_reason == "the planner returned a non-finite acceleration at t = 0.260 s"
    assert run.record.steps == 26


@pytest.mark.parametrize(("option", "value"), [("delay", -0.1), ("noise", float("nan")), ("control", "current")])
def test_invalid_options_are_refused(option: str, value: object) -> None:
    with pytest.raises(ValueError, match=option):
        simulate_mujoco(_sinusoid, build_scene(load_robot("panda")), Q0, np.zeros(7), 0.01, 1.0, **{option: value})


def test_robot_held_by_an_obstacle_does_not_snap_back_when_released() -> None:
    """A wall holds the point robot for 1.5 s, then leaves: the set-points restarted from
    the held state, so the robot resumes at the planner's pace instead of jumping after the
    path it missed."""
    def centres(times: np.ndarray) -> np.ndarray:
        return np.where(times[:, None] < 1.5, [[0.5, 0.0, 0.0]], [[5.0, 5.0, 0.0]])[:, None, :]

    wall = SceneObstacle(Box((0.2, 2.0, 1.0)), (0.5, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0), True)

    def push_right(t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        return np.array([np.clip(1.0 - qdot[0], -1.0, 1.0), -qdot[1]])  # towards +x at 1 m/s

    run = simulate_mujoco(push_right, build_scene(load_robot("point"), [wall]), np.zeros(2), np.zeros(2), 0.01,
                          3.0, obstacle_centres=centres)
    assert run.contacts and run.contacts[0].other == "obstacles[0]"
    assert run.record.q[145, 0] == pytest.approx(0.3, abs=0.01)  # held against the wall (0.4 - r)
    assert np.abs(run.record.qdot[:, 0]).max() < 1.05  # released: no snap beyond the commanded speed
    assert run.record.q[-1, 0] > 1.0  # on its way again
