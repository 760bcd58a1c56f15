"""The ``dynfab run`` command: JSON on stdout, logs on stderr, one-line errors, exit codes."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from dynfab.cli import main

#: Keys of the ``--json`` object promised by docs/design.md section 5.5.
JSON_KEYS = {"success", "goal_reached", "collision", "time_to_goal", "clearance", "path_length",
             "summed_error", "solver_time_ms", "steps", "orientation_error", "max_velocity_ratio",
             "max_acceleration_ratio"}

VALID: dict[str, Any] = {
    "robot": "panda",
    "planner": "static-fabric",
    "dt": 0.01,
    "duration": 3.0,
    "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
    "goal": [{"type": "position", "link": "panda_hand", "position": [0.5, -0.3, 0.4], "tolerance": 0.05}],
    "obstacles": [{"type": "sphere", "position": [0.6, 0.3, 0.8], "radius": 0.1}],
}


def write_scenario(directory: Path, data: dict[str, Any], name: str = "scenario.yaml") -> Path:
    """Dump ``data`` as YAML into ``directory``; return the file."""
    path = directory / name
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def changed(path: tuple[str | int, ...], value: object) -> dict[str, Any]:
    """A deep copy of VALID with the entry at ``path`` set to ``value``."""
    data = copy.deepcopy(VALID)
    parent: Any = data
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = value
    return data


def test_run_json_prints_one_object_on_stdout_and_progress_on_stderr(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", str(write_scenario(tmp_path, VALID)), "--json"])
    out, err = capsys.readouterr()
    assert code == 0
    lines = out.splitlines()
    assert len(lines) == 1
    metrics = json.loads(lines[0])
    assert isinstance(metrics, dict)
    assert JSON_KEYS <= metrics.keys()
    assert metrics["success"] is True
    assert metrics["steps"] == 300
    assert metrics["clearance"] > 0.0
    assert "simulating" in err and "100%" in err
    assert "simulating" not in out


def test_run_without_json_prints_a_readable_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", str(write_scenario(tmp_path, VALID))])
    out, _ = capsys.readouterr()
    assert code == 0
    names = {line.split(":")[0].strip() for line in out.splitlines()}
    assert names == JSON_KEYS | {"sphere_clearance", "self_collision", "min_self_distance", "contacts", "link_contacts",
                                 "guided", "plans", "plan_time_ms", "recovered", "fallbacks", "goal_moved", "failure", "final_distance"}


def test_run_as_subprocess(tmp_path: Path) -> None:
    path = write_scenario(tmp_path, VALID)
    completed = subprocess.run([sys.executable, "-m", "dynfab.cli", "run", str(path), "--json"],
                               capture_output=True, text=True, timeout=120, check=False)
    assert completed.returncode == 0, completed.stderr
    lines = completed.stdout.splitlines()
    assert len(lines) == 1
    assert JSON_KEYS <= json.loads(lines[0]).keys()
    assert "100%" in completed.stderr
    assert "Traceback" not in completed.stderr


def test_plot_writes_a_png(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    plot = tmp_path / "run.png"
    code = main(["run", str(write_scenario(tmp_path, VALID)), "--json", "--plot", str(plot)])
    out, err = capsys.readouterr()
    assert code == 0
    assert plot.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    assert plot.stat().st_size > 1000
    assert JSON_KEYS <= json.loads(out).keys()
    assert str(plot) in err


BAD_SCENARIOS: dict[str, tuple[dict[str, Any], str]] = {
    "unknown top-level key": ({**VALID, "colour": "red"}, "colour"),
    "unknown nested key": (changed(("goal", 0, "colour"), "red"), "goal[0].colour"),
    "wrong q length": (changed(("initial_state", "q"), [0.0] * 6), "initial_state.q"),
    "goal position of 2 numbers": (changed(("goal", 0, "position"), [0.5, -0.3]), "goal[0].position"),
    "goal position of 4 numbers": (changed(("goal", 0, "position"), [0.5, -0.3, 0.4, 1.0]), "goal[0].position"),
    "unknown link": (changed(("goal", 0, "link"), "panda_link99"), "goal[0].link"),
    "unknown robot": (changed(("robot",), "ur5"), "robot"),
    "unknown backend": (changed(("backend",), "gpu"), "backend"),
    "negative radius": (changed(("obstacles", 0, "radius"), -0.1), "obstacles[0].radius"),
    "NaN": (changed(("dt",), float("nan")), "dt"),
    "infinity": (changed(("goal", 0, "position"), [0.5, float("inf"), 0.4]), "goal[0].position[1]"),
}


@pytest.mark.parametrize("case", BAD_SCENARIOS)
def test_bad_scenario_exits_2_with_one_line_naming_the_field(
        case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data, field = BAD_SCENARIOS[case]
    code = main(["run", str(write_scenario(tmp_path, data)), "--json"])
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, f"{case}: expected one line on stderr, got {lines}"
    assert lines[0].startswith(f"dynfab: error: {field}: "), lines[0]


def test_nan_and_infinity_spelled_in_yaml_are_rejected(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = yaml.safe_dump(VALID, sort_keys=False).replace("radius: 0.1", "radius: .inf")
    path = tmp_path / "inf.yaml"
    path.write_text(text, encoding="utf-8")
    assert ".inf" in text
    assert main(["run", str(path)]) == 2
    _, err = capsys.readouterr()
    assert len(err.splitlines()) == 1
    assert err.startswith("dynfab: error: obstacles[0].radius: expected a finite number")


def test_malformed_yaml_exits_2_naming_the_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "broken.yaml"
    path.write_text("robot: panda\ngoal: [{type: position\n", encoding="utf-8")
    assert main(["run", str(path), "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert len(err.splitlines()) == 1
    assert err.startswith(f"dynfab: error: {path}: invalid YAML")


def test_missing_file_exits_2_naming_the_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "absent.yaml"
    assert main(["run", str(path), "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert len(err.splitlines()) == 1
    assert err.startswith(f"dynfab: error: {path}: cannot read file")


def test_bad_file_as_subprocess_has_no_traceback(tmp_path: Path) -> None:
    path = write_scenario(tmp_path, changed(("obstacles", 0, "radius"), -0.1))
    completed = subprocess.run([sys.executable, "-m", "dynfab.cli", "run", str(path), "--json"],
                               capture_output=True, text=True, timeout=120, check=False)
    assert completed.returncode == 2
    assert completed.stdout == ""
    assert completed.stderr.splitlines() == ["dynfab: error: obstacles[0].radius: must be positive, got -0.1"]


@pytest.mark.parametrize("example", ["panda_joint_goal.yaml", "boxer_panda_base_goal.yaml"])
def test_plot_of_goals_not_in_workspace_coordinates(example: str, tmp_path: Path) -> None:
    """Joint goals and goals on a subset of axes plot the goal link's full path."""
    plot = tmp_path / "run.png"
    examples = Path(__file__).resolve().parents[1] / "examples"
    assert main(["run", str(examples / example), "--plot", str(plot)]) == 0
    assert plot.stat().st_size > 10_000
