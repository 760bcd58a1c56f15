"""Runs measured on real collision meshes: metrics, start-state errors, ``--record`` and
``dynfab check`` (scenario/exact_metrics.py, start_state.py, recording.py, recording_check.py)."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from robot_files import arm_urdf, folded_configuration

from dynfab.cli import main
from dynfab.geometry.shapes import Box, Placement
from dynfab.robots import load_robot
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes
from dynfab.scenario.exact_metrics import mesh_model_for
from dynfab.scenario.recording import load_recording
from dynfab.scenario.runner import robot_for, run_scenario
from dynfab.scenario.schema import scenario_from_dict

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
UR5_START = [0.0, -1.57, 1.57, -1.57, -1.57, 0.0]
#: The tool swings a quarter turn about the base; the forearm sweeps through (0.165, 0.113, 0.514).
UR5: dict[str, Any] = {
    "robot": {"urdf": str(arm_urdf("ur5")), "goal_link": "tool0",
              "collision_spheres": [{"link": "tool0", "center": [0, 0, 0], "radius": 0.02}]},
    "planner": "static-fabric", "dt": 0.01, "duration": 3.0,
    "initial_state": {"q": UR5_START},
    "goal": [{"type": "position", "link": "tool0", "position": [0.075, 0.493, 0.432], "tolerance": 0.03}],
    "obstacles": [{"type": "sphere", "position": [-0.6, -0.6, 0.3], "radius": 0.1}],
}
PANDA: dict[str, Any] = {
    "robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 1.0,
    "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
    "goal": [{"type": "position", "link": "panda_hand", "position": [0.5, -0.3, 0.4]}],
    "obstacles": [{"type": "sphere", "position": [0.6, 0.3, 0.8], "radius": 0.1}],
}


def scenario_file(directory: Path, data: dict[str, Any], **changes: Any) -> Path:
    data = copy.deepcopy(data)
    for key, value in changes.items():
        data[key] = value
    path = directory / "scenario.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def with_q(data: dict[str, Any], q: list[float]) -> dict[str, Any]:
    return {**data, "initial_state": {"q": q}}


def error_of(path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    assert main(["run", str(path), "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    return err.strip()


@pytest.fixture(scope="module")
def hit(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The UR5 run whose forearm passes through a sphere its only (tool) sphere never nears."""
    directory = tmp_path_factory.mktemp("hit")
    path = scenario_file(directory, UR5, obstacles=[{"type": "sphere", "position": [0.165, 0.113, 0.514],
                                                     "radius": 0.05}])
    assert main(["run", str(path), "--json", "--record", str(directory / "run.npz")]) == 1   # it collides
    return path, directory / "run.npz"


def test_mesh_metrics_flag_what_the_spheres_miss(hit: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    path, _ = hit
    assert main(["run", str(path), "--json"]) == 1
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["goal_reached"] is True
    assert metrics["sphere_clearance"] > 0.1  # the tool sphere stays far away
    assert metrics["collision"] is True and metrics["clearance"] < -0.05  # the forearm goes through
    assert metrics["success"] is False
    assert metrics["self_collision"] is False and metrics["min_self_distance"] > 0.0


def test_check_reports_the_collision_of_a_recorded_run(hit: tuple[Path, Path],
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    path, recording = hit
    assert main(["check", str(recording), str(path), "--json"]) == 3
    report = json.loads(capsys.readouterr().out)
    assert report["ok"] is False and report["samples"] == 301
    assert {(c["link"], c["other"]) for c in report["collisions"]} == {("forearm_link", "obstacles[0]")}
    first = report["collisions"][0]
    assert 0.0 < first["first_time"] < 1.0 and first["samples"] > 10 and first["distance"] < -0.05
    assert report["self_collisions"] == [] and report["joint_limit_violations"] == []


def test_a_clean_run_checks_clean(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = scenario_file(tmp_path, UR5)
    recording = tmp_path / "run.npz"
    assert main(["run", str(path), "--json", "--record", str(recording)]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["success"] is True and metrics["collision"] is False and metrics["self_collision"] is False
    assert main(["check", str(recording), str(path)]) == 0
    out = capsys.readouterr().out
    assert "no collision, no self-collision, joints within limits" in out
    assert main(["check", str(recording), str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["ok"] is True and report["clearance"] == pytest.approx(metrics["clearance"])
    assert report["min_self_distance"] == pytest.approx(metrics["min_self_distance"])


def test_check_finds_a_joint_outside_its_limits(hit: tuple[Path, Path], tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    path, recording = hit
    with np.load(recording) as data:
        arrays = {key: data[key] for key in data.files}
    arrays["q"] = arrays["q"].copy()
    arrays["q"][100:120, 2] = 3.3  # elbow beyond pi
    edited = tmp_path / "edited.npz"
    np.savez(edited, **arrays)
    assert main(["check", str(edited), str(path), "--json"]) == 3
    (violation,) = json.loads(capsys.readouterr().out)["joint_limit_violations"]
    assert violation["joint"] == "elbow_joint" and violation["samples"] == 20
    assert violation["worst"] == 3.3 and violation["upper"] == pytest.approx(np.pi)
    assert violation["first_time"] == pytest.approx(1.0)


def test_a_link_through_a_box_is_flagged_though_no_sphere_nears_it(hit: tuple[Path, Path]) -> None:
    """The recorded clean-start run against a box across the forearm's sweep."""
    path, recording = hit
    scenario = scenario_from_dict(yaml.safe_load(path.read_text()))
    robot = robot_for(scenario)
    model = mesh_model_for(robot)
    q = load_recording(recording).q
    box = PlacedShape("box", Box((0.05, 0.05, 0.3)), (Placement((0.2, 0.2, 0.5)),))
    sweep = sweep_meshes(model, q, [box])
    assert {c.first for c in sweep.obstacle_contacts} >= {"forearm_link"}
    tool = np.array([robot.sphere_centers(row)[0] for row in q])  # the only sphere, radius 0.02
    outside = np.maximum(np.abs(tool - [0.2, 0.2, 0.5]) - [0.025, 0.025, 0.15], 0.0)
    assert np.min(np.linalg.norm(outside, axis=1)) - 0.02 > 0.05


def test_record_round_trip(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = scenario_file(tmp_path, PANDA)
    out = tmp_path / "panda.npz"
    assert main(["run", str(path), "--json", "--record", str(out)]) in (0, 1)   # recorded whether reached or not
    assert str(out) in capsys.readouterr().err
    result = run_scenario(scenario_from_dict(yaml.safe_load(path.read_text())))
    recording = load_recording(out)
    with np.load(out) as data:
        assert set(data.files) == {"t", "q", "qdot", "qddot", "joint_names", "velocity_names", "dt", "scenario"}
    assert recording.scenario == str(path.resolve())
    np.testing.assert_array_equal(recording.t, result.record.t)
    np.testing.assert_allclose(recording.q, result.record.q, atol=1e-12)
    np.testing.assert_allclose(recording.qdot, result.record.qdot, atol=1e-12)
    np.testing.assert_allclose(recording.qddot[:-1], result.record.qddot, atol=1e-12)
    np.testing.assert_array_equal(recording.qddot[-1], 0.0)
    assert recording.q.shape == (101, 7) and recording.dt == 0.01
    assert recording.joint_names == tuple(f"panda_joint{i}" for i in range(1, 8))
    # the recorded commands integrate to the recorded states (double integrator)
    predicted = recording.q[:-1] + recording.qdot[:-1] * 0.01 + 0.5 * recording.qddot[:-1] * 0.01 ** 2
    np.testing.assert_allclose(predicted, recording.q[1:], atol=1e-12)


def test_a_differential_drive_recording_holds_the_actuated_velocities(tmp_path: Path) -> None:
    boxer = {"robot": "boxer", "planner": "static-fabric", "dt": 0.01, "duration": 0.5,
             "initial_state": {"q": [0.0, 0.0, 0.0]}, "goal": [{"type": "position", "position": [1.0, 0.5]}]}
    out = tmp_path / "boxer.npz"
    assert main(["run", str(scenario_file(tmp_path, boxer)), "--json", "--record", str(out)]) == 1   # 0.5 s: not there
    recording = load_recording(out)
    assert recording.joint_names == ("base_x", "base_y", "base_yaw") and recording.velocity_names == ("v", "omega")
    assert recording.q.shape == (51, 3) and recording.qdot.shape == (51, 2) and recording.qddot.shape == (51, 2)


def test_builtin_panda_is_measured_on_frankas_meshes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Franka's meshes (example-robot-data, a test extra): the spheres reach out of them,
    so the mesh clearance is the larger; self-collision is measured too."""
    assert main(["run", str(scenario_file(tmp_path, PANDA)), "--json"]) in (0, 1)  # 1: goal not reached in 1 s
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["clearance"] > metrics["sphere_clearance"] > 0.0
    assert metrics["self_collision"] is False and metrics["min_self_distance"] > 0.0


def test_planar_builtin_robots_keep_the_sphere_figures(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    point = {"robot": "point", "planner": "static-fabric", "dt": 0.01, "duration": 0.5,
             "initial_state": {"q": [0.0, 0.0]}, "goal": [{"type": "position", "position": [1.0, 0.0]}],
             "obstacles": [{"type": "sphere", "position": [0.5, 0.8], "radius": 0.1}]}
    assert main(["run", str(scenario_file(tmp_path, point)), "--json"]) in (0, 1)
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["clearance"] == metrics["sphere_clearance"] > 0.0
    assert metrics["self_collision"] is None and metrics["min_self_distance"] is None


def test_start_outside_the_joint_limits(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ur5 = with_q(UR5, [0.0, -1.57, 3.5, -1.57, -1.57, 0.0])
    assert error_of(scenario_file(tmp_path, ur5), capsys) == (
        "dynfab: error: initial_state.q[2] (elbow_joint): 3.5 is outside [-3.14159, 3.14159]")
    panda = with_q(PANDA, [1.0, 0.0, 0.0, 0.5, 0.0, 1.8675, 0.0])
    assert error_of(scenario_file(tmp_path, panda), capsys) == (
        "dynfab: error: initial_state.q[3] (panda_joint4): 0.5 is outside [-3.0718, -0.0698]")


def test_start_in_collision_on_meshes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    obstacles = [{"type": "sphere", "position": [0.2, 0.016, 0.514], "radius": 0.03}]  # on the forearm
    message = error_of(scenario_file(tmp_path, UR5, obstacles=obstacles), capsys)
    assert message.startswith("dynfab: error: initial_state.q: the start state is in collision: "
                              "link 'forearm_link' touches obstacles[0]")


def test_start_in_self_collision_on_meshes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = mesh_model_for(robot_for(scenario_from_dict(UR5)))
    q, depths = folded_configuration(model, seed=11)
    touching = [(model.links[i], model.links[j]) for (i, j), depth in zip(model.pairs, depths) if depth <= 0.0]
    message = error_of(scenario_file(tmp_path, with_q(UR5, [float(x) for x in q])), capsys)
    assert message.startswith("dynfab: error: initial_state.q: the start state is in self-collision: links ")
    assert any(f"links '{a}' and '{b}' touch" in message for a, b in touching)


#: a robot measured by its spheres: the planar arm of examples/custom_urdf (no collision meshes)
ARM = {**yaml.safe_load((EXAMPLES / "custom_urdf" / "arm_spheres.yaml").read_text(encoding="utf-8")),
       "duration": 1.0}
ARM["robot"] = {**ARM["robot"], "urdf": str(EXAMPLES / "custom_urdf" / "arm.urdf")}


def test_start_in_collision_on_spheres(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    arm = robot_for(scenario_from_dict(ARM))
    tool = [float(x) for x in np.asarray(arm.kinematics.position(ARM["initial_state"]["q"], "tool")).ravel()[:2]]
    message = error_of(scenario_file(tmp_path, ARM, obstacles=[{"type": "sphere", "position": tool,
                                                               "radius": 0.05}]), capsys)
    assert "the start state is in collision: collision sphere" in message and "overlaps obstacles[0]" in message
    rng = np.random.default_rng(5)
    lower, upper = arm.kinematics.lower, arm.kinematics.upper
    for _ in range(2000):  # a configuration where two spheres of a self-collision pair overlap
        q = rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi))
        centers, radii = arm.sphere_centers(q), arm.sphere_radii
        if any(np.linalg.norm(centers[i] - centers[j]) < radii[i] + radii[j] for i, j in arm.self_collision_pairs):
            break
    else:
        pytest.fail("no self-colliding arm configuration found")
    message = error_of(scenario_file(tmp_path, with_q(ARM, [float(x) for x in q]), obstacles=[]), capsys)
    assert "the start state is in self-collision: collision spheres" in message and "overlap by" in message


def test_check_needs_meshes_and_the_robot_of_the_recording(hit: tuple[Path, Path], tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    _, recording = hit
    assert main(["check", str(recording), str(scenario_file(tmp_path, ARM))]) == 2
    assert "has no collision meshes" in capsys.readouterr().err
    np.savez(tmp_path / "other.npz", t=np.zeros(2), q=np.zeros((2, 6)), qdot=np.zeros((2, 6)),
             qddot=np.zeros((2, 6)), joint_names=np.array([f"j{i}" for i in range(6)]))
    assert main(["check", str(tmp_path / "other.npz"), str(scenario_file(tmp_path, UR5))]) == 2
    assert "joint_names: the recording has joints j0" in capsys.readouterr().err
    (tmp_path / "broken.npz").write_text("not a zip")
    assert main(["check", str(tmp_path / "broken.npz"), str(scenario_file(tmp_path, UR5))]) == 2
    assert "cannot read a numpy .npz file" in capsys.readouterr().err


def test_record_into_a_missing_folder_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "missing" / "run.npz"
    assert main(["run", str(scenario_file(tmp_path, PANDA)), "--json", "--record", str(out)]) == 2
    assert f"--record: cannot write {out}" in capsys.readouterr().err


def test_shape_obstacles_count_on_meshes_and_spheres(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # a turned box around the UR5's forearm at the start: an error naming the link and the box
    box = {"type": "box", "position": [0.2, 0.016, 0.514], "size": [0.05, 0.05, 0.05],
           "orientation": [0.92388, 0.0, 0.0, 0.38268]}
    message = error_of(scenario_file(tmp_path, UR5, obstacles=[box]), capsys)
    assert "link 'forearm_link' touches obstacles[0]" in message
    # a floor just under the Panda's hand: the mesh check (Franka's meshes) names a link and the plane
    panda = load_robot("panda")
    hand = np.asarray(panda.kinematics.position(PANDA["initial_state"]["q"], "panda_hand")).ravel()
    floor = {"type": "plane", "point": [0.0, 0.0, float(hand[2]) - 0.02], "normal": [0, 0, 1]}
    message = error_of(scenario_file(tmp_path, PANDA, obstacles=[floor]), capsys)
    assert "the start state is in collision: link '" in message and "touches obstacles[0]" in message
    # a box the forearm sweeps through: the mesh metrics see it
    box = {"type": "box", "position": [0.165, 0.113, 0.514], "size": [0.06, 0.06, 0.06]}
    result = run_scenario(scenario_from_dict({**UR5, "obstacles": [box]}))
    assert result.metrics.collision and result.metrics.clearance < 0.0
    assert result.mesh_sweep.obstacle_contacts[0].second == "obstacles[0]"
