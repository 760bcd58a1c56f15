"""Scenarios under MuJoCo: the scenario keys and ``dynfab run --simulator mujoco``
(metrics, contacts as collisions, one-line errors with exit 2, videos)."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import imageio_ffmpeg
import numpy as np
import pytest
import yaml

from dynfab.cli import main
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import ScenarioError, scenario_from_dict

#: examples/panda_spheres.yaml, shortened.
SPHERES: dict[str, Any] = {
    "robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 4.0,
    "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
    "goal": [{"type": "position", "link": "panda_hand", "position": [0.55, -0.35, 0.25], "tolerance": 0.05}],
    "obstacles": [{"type": "sphere", "position": [0.5, 0.15, 0.35], "radius": 0.15},
                  {"type": "sphere", "position": [0.2, -0.5, 0.6], "radius": 0.1},
                  {"type": "sphere", "position": [0.8, -0.2, 0.6], "radius": 0.15},
                  {"type": "sphere", "position": [0.0, -0.55, 0.25], "radius": 0.15}],
    "simulator": "mujoco",
}


def _scenario(**changes: Any) -> Any:
    data = copy.deepcopy(SPHERES)
    data.update(changes)
    return scenario_from_dict(data)


@pytest.mark.parametrize("control", ["torque", "velocity", "position"])
def test_each_control_mode_reaches_the_goal_without_contact(control: str) -> None:
    result = run_scenario(_scenario(control=control))
    metrics = result.metrics
    assert metrics.success and metrics.goal_reached and not metrics.collision, metrics
    assert metrics.contacts == 0 and result.contacts == () and result.stop_reason is None
    assert metrics.time_to_goal < 4.0   # guided: the reference moves at half the limits (3.33 s measured)


def test_boxer_reaches_its_goal_on_its_wheels() -> None:
    data = yaml.safe_load(Path("examples/boxer_spheres.yaml").read_text())
    data["simulator"] = "mujoco"
    metrics = run_scenario(scenario_from_dict(data)).metrics
    assert metrics.success and metrics.contacts == 0


def test_contact_with_an_obstacle_the_fabric_cannot_avoid_is_a_collision() -> None:
    """A sphere sweeps at 2 m/s through the Panda's base, which cannot move away."""
    sweeping = {"type": "sphere", "radius": 0.15,
                "trajectory": {"type": "linear", "start": [0.0, 1.2, 0.1], "velocity": [0.0, -2.0, 0.0]}}
    result = run_scenario(_scenario(obstacles=[sweeping], duration=1.5))
    assert result.metrics.collision and not result.metrics.success
    assert result.metrics.contacts >= 1
    assert {contact.other for contact in result.contacts} == {"obstacles[0]"}
    assert any(contact.body in ("panda_link0", "panda_link1") for contact in result.contacts)
    kinematic = run_scenario(_scenario(obstacles=[sweeping], duration=1.5, simulator="kinematic"))
    assert kinematic.metrics.contacts is None  # the kinematic simulator has no contacts


def test_delay_and_noise_reach_the_simulation() -> None:
    clean = run_scenario(_scenario(duration=1.0)).record.q
    noisy = run_scenario(_scenario(duration=1.0, noise=0.005)).record.q
    delayed = run_scenario(_scenario(duration=1.0, delay=0.02)).record.q
    assert np.abs(noisy - clean).max() > 1e-4 and np.abs(delayed - clean).max() > 1e-4
    np.testing.assert_array_equal(noisy, run_scenario(_scenario(duration=1.0, noise=0.005)).record.q)


def test_unstable_state_ends_the_run_with_the_metrics_so_far() -> None:
    def poison(t: float, data: Any) -> None:
        if t >= 0.3:
            data.qpos[1] = np.inf

    result = run_scenario(_scenario(duration=2.0), observer=poison)
    assert result.stop_reason is not None and "unstable" in result.stop_reason
    assert result.metrics.steps == 30 and result.record.q.shape[0] == 31


@pytest.mark.parametrize(("changes", "message"), [
    ({"simulator": "bullet"}, "simulator: expected one of kinematic, mujoco; got str 'bullet'"),
    ({"control": "current"}, "control: expected one of torque, velocity, position; got str 'current'"),
    ({"delay": -0.01}, "delay: must be >= 0, got -0.01"),
    ({"noise": ".nan"}, "noise: expected a number"),
    ({"simulator": "kinematic", "control": "torque"}, "control: applies to simulator: mujoco only"),
    ({"simulator": "kinematic", "delay": 0.1}, "delay: applies to simulator: mujoco only"),
])
def test_bad_simulation_keys_are_refused(changes: dict[str, Any], message: str) -> None:
    with pytest.raises(ScenarioError, match=message.replace("(", r"\(").replace(")", r"\)")):
        _scenario(**changes)


def _write(tmp_path: Path, data: dict[str, Any]) -> Path:
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _exit_and_stderr(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, list[str]]:
    code = main(argv)
    return code, [line for line in capsys.readouterr().err.splitlines() if line.startswith("dynfab: error")]


@pytest.mark.parametrize(("options", "message"), [
    (["--simulator", "bullet"], "dynfab: error: simulator: expected one of kinematic, mujoco; got str 'bullet'"),
    (["--simulator", "mujoco", "--control", "current"],
     "dynfab: error: control: expected one of torque, velocity, position; got str 'current'"),
    (["--control", "velocity"], "dynfab: error: --control: applies to --simulator mujoco only"),
    (["--video", "run.mp4"], "dynfab: error: --video: renders MuJoCo runs: add --simulator mujoco"),
])
def test_cli_refuses_bad_options_with_one_line_and_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                           options: list[str], message: str) -> None:
    data = {key: value for key, value in SPHERES.items() if key != "simulator"}
    code, errors = _exit_and_stderr(["run", str(_write(tmp_path, data)), *options], capsys)
    assert code == 2 and errors == [message]


def test_cli_refuses_a_period_that_is_not_whole_physics_steps(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    code, errors = _exit_and_stderr(["run", str(_write(tmp_path, dict(SPHERES, dt=0.0025)))], capsys)
    assert code == 2 and errors == ["dynfab: error: dt: under MuJoCo must be a whole number of 1 ms physics steps, "
                                    "got 0.0025"]


def test_cli_refuses_a_urdf_link_without_inertial(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "arm.urdf").write_text("""<robot name="arm"><link name="base"/>
      <link name="arm"><collision><geometry><box size="0.1 0.1 0.4"/></geometry></collision></link>
      <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.3"/>
      <axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="1" effort="10"/></joint></robot>""")
    data = dict(SPHERES, robot={"urdf": "arm.urdf", "goal_link": "arm",
                                "collision_spheres": [{"link": "arm", "center": [0, 0, 0], "radius": 0.1}]},
                initial_state={"q": [0.0]}, obstacles=[],
                goal=[{"type": "joint", "position": [0.5], "tolerance": 0.05}])
    code, errors = _exit_and_stderr(["run", str(_write(tmp_path, data))], capsys)
    assert code == 2 and len(errors) == 1
    assert errors[0].startswith("dynfab: error: robot: link 'arm' moves but has no <inertial> mass")


def test_video_shows_the_robot_moving(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = {key: value for key, value in SPHERES.items() if key != "simulator"}
    video = tmp_path / "run.mp4"
    code = main(["run", str(_write(tmp_path, dict(data, duration=1.0))), "--simulator", "mujoco",
                 "--video", str(video), "--json"])
    assert code in (0, 1) and json.loads(capsys.readouterr().out)["contacts"] == 0   # 1 s: maybe not there yet
    reader = imageio_ffmpeg.read_frames(str(video))
    width, height = next(reader)["size"]
    frames = np.array([np.frombuffer(frame, np.uint8).reshape(height, width, 3) for frame in reader])
    assert len(frames) == 31  # 30 frames per second of simulated time, and t = 0
    red, green, blue = (frames[..., i].astype(int) for i in range(3))
    orange = (red > 170) & (green > 70) & (green < 170) & (blue < 80)  # the robot's colour
    assert np.all(orange.sum(axis=(1, 2)) > 500), "a frame without the robot"
    assert np.abs(frames[-1].astype(int) - frames[0]).mean() > 1.0, "the robot did not move in the video"
