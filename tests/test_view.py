"""The live view without a browser: goal and obstacle handles steer the planner, planners
switch, recordings replay, ports, and ``dynfab view`` as a process (issue 13 item 2)."""

from __future__ import annotations

import dataclasses
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from dynfab.cli import main
from dynfab.robots import load_robot
from dynfab.scenario.controllers import FabricController
from dynfab.scenario.recording import load_recording, run_recording, save_recording
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import ScenarioError, load_scenario, scenario_from_dict
from dynfab.viz.replay_session import ReplaySession
from dynfab.viz.robot_visuals import LinkPoses, robot_look
from dynfab.viz.view_server import LiveView, PortError, ReplayView, choose_port, port_is_free
from dynfab.viz.view_session import ViewSession

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PANDA_Q0 = [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def hand_position(session: ViewSession) -> np.ndarray:
    q = ca.SX.sym("q", session.robot.dof)
    return np.array(ca.Function("p", [q], [session.robot.kinematics.position(q, "panda_hand")])(session.q)).ravel()


def run_for(session: ViewSession, seconds: float) -> None:
    for _ in range(round(seconds / session.scenario.dt)):
        assert session.step(), session.message


@pytest.fixture
def live_view():
    """A LiveView of examples/panda_spheres.yaml on a free port; its loop is not started,
    so the test steps the session itself."""
    view = LiveView(ViewSession(load_scenario(EXAMPLES / "panda_spheres.yaml")),
                    robot_look(load_robot("panda")), free_port())
    yield view
    view.stop()


def test_dragging_the_goal_handle_moves_the_goal_and_the_hand_follows(live_view: LiveView) -> None:
    session = live_view.session
    run_for(session, 6.0)
    before = hand_position(session)
    assert np.linalg.norm(before - [0.55, -0.35, 0.25]) < 0.05  # reached the scenario's goal
    target = np.array([0.3, 0.45, 0.6])
    assert set(live_view.goal_handles) == {0}
    live_view.drag_goal(0, target)  # what the handle's on_update calls
    planner = session._controller(session.planner).planner
    start = np.array([0.55, -0.35, 0.25])
    run_for(session, 0.02)  # the goal glides there in MAX_GLIDE = 0.2 s: written at t0, then t0 + dt
    np.testing.assert_allclose(planner.parameters.goal_position[0], start + 0.05 * (target - start))
    run_for(session, 0.2)
    np.testing.assert_allclose(planner.parameters.goal_position[0], target)
    run_for(session, 8.0)
    assert np.linalg.norm(hand_position(session) - target) < 0.05
    status = session.status()
    assert status.goal_distance < 0.05 and status.clearance > 0.0 and status.step_time_ms > 0.0


def test_dragging_an_obstacle_writes_its_slot_and_the_dynamic_fabric_gives_way(live_view: LiveView) -> None:
    """An obstacle dragged down onto the resting hand at 0.1 m/s: the drag glides with that
    velocity, which the dynamic fabric sees (it keeps clear and moves the hand away); the
    static fabric sees positions only and, the arm at rest, does not react (paper sec. IV)."""
    outcomes = {}
    for planner in ("dynamic-fabric", "static-fabric"):
        session = ViewSession(load_scenario(EXAMPLES / "panda_spheres.yaml")) if outcomes else live_view.session
        session.switch_planner(planner)
        run_for(session, 6.0)
        hand = hand_position(session)
        clearance = []
        for height in np.arange(0.35, -0.05, -0.01):  # the handle, every 0.1 s of simulated time
            if outcomes:
                session.move_obstacle(1, hand + [0.0, 0.0, height])
            else:
                live_view.drag_obstacle(1, hand + [0.0, 0.0, height])  # what the handle's on_update calls
            run_for(session, 0.1)
            clearance.append(session.status().clearance)
        run_for(session, 0.1)  # the last glide has ended
        planner_slots = session._controller(planner).planner.parameters.obstacle_position
        np.testing.assert_allclose(planner_slots[1], hand + [0.0, 0.0, -0.04], atol=1e-9)
        outcomes[planner] = (min(clearance), np.linalg.norm(hand_position(session) - hand))
    assert outcomes["dynamic-fabric"][0] > 0.01 and outcomes["dynamic-fabric"][1] > 0.1   # 19 mm with open fingers
    assert outcomes["static-fabric"][0] < -0.05 and outcomes["static-fabric"][1] < 1e-3


def test_a_moving_goal_keeps_moving_after_a_drag() -> None:
    session = ViewSession(load_scenario(EXAMPLES / "panda_path_circle.yaml"))
    run_for(session, 1.0)
    circle_now = session.world.goal_point(0, session.t)
    session.move_goal(0, circle_now + [0.0, 0.1, -0.05])
    run_for(session, 2.0)
    controller = session._controller(session.planner)
    assert isinstance(controller, FabricController)
    last_call = session.t - session.scenario.dt  # when the controller last wrote the goal
    shifted = controller.references.goals[0].evaluate(last_call).position
    original = session.world._references.goals[0].evaluate(last_call).position
    np.testing.assert_allclose(shifted - original, [0.0, 0.1, -0.05], atol=1e-12)  # the glide (0.2 s) ended
    np.testing.assert_allclose(controller.planner.parameters.goal_position[0], shifted)
    session.restore_references()
    np.testing.assert_allclose(controller.references.goals[0].evaluate(session.t).position,
                               session.world._references.goals[0].evaluate(session.t).position)
    session.reset()
    assert session.t == 0.0 and np.allclose(session.q, PANDA_Q0)


def test_planners_switch_lazily_and_mpc_only_among_spheres() -> None:
    session = ViewSession(load_scenario(EXAMPLES / "panda_spheres.yaml"))
    assert session.planners == ("dynamic-fabric", "static-fabric", "mpc")
    assert set(session._controllers) == {"static-fabric"}
    run_for(session, 1.0)
    session.switch_planner("dynamic-fabric")
    run_for(session, 5.0)
    assert set(session._controllers) == {"static-fabric", "dynamic-fabric"}
    assert np.linalg.norm(hand_position(session) - [0.55, -0.35, 0.25]) < 0.05
    boxes = ViewSession(load_scenario(EXAMPLES / "panda_table_box.yaml"))
    assert "mpc" not in boxes.planners
    with pytest.raises(ScenarioError, match="planner"):
        boxes.switch_planner("mpc")


def test_mobile_base_pose_moves_the_whole_robot() -> None:
    robot = load_robot("boxer-panda")
    look = robot_look(robot)
    assert look.source == "built-in" and {"chassis_link", "panda_link3", "panda_hand"} <= {v.link for v in look.visuals}
    poses = LinkPoses(robot, ("chassis_link", "panda_hand"))
    q = np.array(robot.default_q)
    moved = q.copy()
    moved[:3] = [1.0, -2.0, np.pi / 2]
    a, b = poses(q), poses(moved)
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    for before, after in zip(a, b):
        np.testing.assert_allclose(after[:3, 3], turn @ before[:3, 3] + [1.0, -2.0, 0.0], atol=1e-12)
        np.testing.assert_allclose(after[:3, :3], turn @ before[:3, :3], atol=1e-12)
    hand = np.array(ca.Function("p", [s := ca.SX.sym("q", robot.dof)], [robot.kinematics.position(s, "panda_hand")])(
        moved)).ravel()
    np.testing.assert_allclose(b[1][:3, 3], hand, atol=1e-12)


def test_every_robot_has_a_look() -> None:
    for name, source in (("panda", "built-in"), ("boxer", "built-in"), ("point", "collision spheres")):
        look = robot_look(load_robot(name))
        assert look.source == source and look.visuals and not look.missing
    ur5 = ViewSession(load_scenario(EXAMPLES / "ur5_table_pose.yaml"))
    spec = ur5.scenario.robot
    look = robot_look(ur5.robot, spec.urdf, spec.package_dirs)
    assert look.source == "urdf" and not look.missing
    assert {"base_link", "forearm_link", "wrist_3_link"} <= {v.link for v in look.visuals}


def test_replay_shows_the_recorded_states(tmp_path: Path) -> None:
    scenario = dataclasses.replace(load_scenario(EXAMPLES / "panda_moving_obstacles.yaml"), duration=2.0)
    result = run_scenario(scenario)
    path = tmp_path / "run.npz"
    save_recording(path, run_recording(result.robot, result.record, scenario.dt, scenario.path))
    recording = load_recording(path)
    replay = ReplaySession(recording, load_scenario(recording.scenario))
    replay.seek(1.234)
    state = replay.scene()
    np.testing.assert_allclose(state.q, result.record.q[123])
    np.testing.assert_allclose(state.obstacle_centres, result.obstacle_centers[123])
    replay.playing = True
    replay.advance(5.0)
    assert replay.t == pytest.approx(2.0) and not replay.playing
    view = ReplayView(replay, robot_look(result.robot), free_port(), "run.npz")
    view.stop()
    point = scenario_from_dict({"robot": "point", "planner": "static-fabric", "dt": 0.01, "duration": 1.0,
                                "initial_state": {"q": [0.0, 0.0]}, "goal": [{"type": "position",
                                                                              "position": [1.0, 0.0]}]})
    with pytest.raises(ScenarioError, match="recording's joints"):
        ReplaySession(recording, point)


def test_replay_without_a_scenario_file_is_a_one_line_error(tmp_path: Path, capsys) -> None:
    scenario = dataclasses.replace(load_scenario(EXAMPLES / "panda_spheres.yaml"), duration=0.1, path=None)
    result = run_scenario(scenario)
    path = tmp_path / "run.npz"
    save_recording(path, run_recording(result.robot, result.record, scenario.dt))
    assert main(["view", str(path), "--port", str(free_port())]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "--scenario FILE" in error


def test_busy_ports() -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        assert not port_is_free(port)
        with pytest.raises(PortError, match=f"port {port} is taken"):
            choose_port(port)
        code = subprocess.run([sys.executable, "-m", "dynfab.cli", "view", str(EXAMPLES / "panda_spheres.yaml"),
                               "--port", str(port)], capture_output=True, text=True, timeout=120)
        assert code.returncode == 2
        assert code.stderr.strip() == (f"dynfab: error: --port: port {port} is taken (by another program); choose "
                                       "another or leave --port out to take the first free one from 8080")
    default_busy = None if not port_is_free(8080) else socket.socket()
    try:
        if default_busy is not None:
            default_busy.bind(("127.0.0.1", 8080))
        chosen, note = choose_port(None)
        assert chosen > 8080 and port_is_free(chosen) and note == f"port 8080 is taken; serving on {chosen}"
    finally:
        if default_busy is not None:
            default_busy.close()


def view_process(*args: str) -> tuple[subprocess.Popen, str]:
    """``dynfab view ARGS`` in a process; returns it and its URL once it serves."""
    process = subprocess.Popen([sys.executable, "-m", "dynfab.cli", "view", *args], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    line = process.stdout.readline()
    assert " at http://localhost:" in line, (line, process.stderr.read() if process.poll() is not None else "")
    return process, line.split(" at ")[1].split()[0]


def test_view_process_serves_the_page_and_stops_cleanly_on_ctrl_c() -> None:
    port = free_port()
    process, url = view_process(str(EXAMPLES / "boxer_panda_room.yaml"), "--port", str(port))
    try:
        assert url == f"http://localhost:{port}"
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=10) as page:
            assert page.status == 200 and b"<html" in page.read().lower()
        time.sleep(1.0)
        assert process.poll() is None
    finally:
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)
    assert process.returncode == 0
    assert "Traceback" not in err and "view stopped" in err


@pytest.mark.parametrize("example, source", [("boxer_path.yaml", "built-in"),
                                             ("point_moving_obstacle.yaml", "collision spheres"),
                                             ("custom_urdf/arm_spheres.yaml", "collision spheres"),
                                             ("panda_moving_box.yaml", "built-in")])
def test_every_robot_kind_runs_in_the_view(example: str, source: str) -> None:
    session = ViewSession(load_scenario(EXAMPLES / example))
    spec = session.scenario.robot
    look = robot_look(session.robot, *((spec.urdf, spec.package_dirs) if hasattr(spec, "urdf") else ()))
    assert look.source == source and look.visuals
    q0 = session.q.copy()
    run_for(session, 1.0)
    assert not np.allclose(session.q, q0)
    state = session.scene()
    assert state.obstacle_centres.shape == (len(session.scenario.obstacles), 3)
    moving = [k for k in range(len(session.scenario.obstacles)) if session.world.obstacle_moves(k)]
    for k in moving:  # drawn where the planner sees them
        np.testing.assert_allclose(state.obstacle_centres[k, :2],
                                   session.world._references.obstacles[k].evaluate(session.t).position[:2])


def test_shifted_trajectory_glides_with_consistent_derivatives() -> None:
    from dynfab.motion.shifted_trajectory import ShiftedTrajectory
    from dynfab.motion.trajectories import CircleTrajectory, StaticPoint

    circle = CircleTrajectory(center=(0.4, 0.0, 0.5), radius=0.2, angular_velocity=0.5, normal=(1.0, 0.0, 0.0))
    shifted = ShiftedTrajectory(circle, (0.1, -0.2, 0.3), (0.0, 0.1, 0.0), start=1.0, glide=0.5)
    times = np.array([0.5, 1.1, 1.3, 1.45, 2.0, 3.0])
    position, velocity, acceleration = shifted.sample(times)
    inner = circle.sample(times)
    progress = np.clip((times - 1.0) / 0.5, 0.0, 1.0)[:, None]
    np.testing.assert_allclose(position, inner[0] + [0.0, 0.1, 0.0] + progress * [0.1, -0.3, 0.3], atol=1e-12)
    h = 1e-6
    finite = (shifted.sample(times + h)[0] - shifted.sample(times - h)[0]) / (2 * h)
    np.testing.assert_allclose(velocity, finite, atol=1e-7)
    np.testing.assert_allclose(acceleration, inner[2])
    at_rest = ShiftedTrajectory(StaticPoint((1.0, 2.0)), (0.5, 0.5))
    np.testing.assert_allclose(at_rest.evaluate(7.0).position, [1.5, 2.5])
    with pytest.raises(ValueError, match="offset"):
        ShiftedTrajectory(circle, (0.1, 0.2))


def test_the_core_does_not_import_viser() -> None:
    check = "import sys, dynfab.cli, dynfab.viz.view_session; sys.exit('viser' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", check], timeout=120).returncode == 0
