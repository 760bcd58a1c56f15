"""References are checked for finite values over the whole run before it starts."""

import copy
from pathlib import Path

import pytest
import yaml

from dynfab.cli import main
from dynfab.motion.reference_checks import check_times, first_non_finite
from dynfab.motion.spline_trajectory import SplineTrajectory
from dynfab.motion.trajectory_mapping import trajectory_from_mapping

BASE = {
    "robot": "panda", "planner": "dynamic-fabric", "dt": 0.01, "duration": 3.0,
    "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
    "goal": [{"type": "path", "link": "panda_hand", "tolerance": 0.05,
              "trajectory": {"type": "expression", "x": ["0.5", "0.1*sin(t)", "0.5"]}}],
}


@pytest.mark.parametrize("expression, quantity, time", [
    ("1/(t-0.5)", "position", 0.5),
    ("log(1-t)", "position", 1.0),
    ("sqrt(0.5-t)", "velocity", 0.5),
    ("asin(t)", "velocity", 1.0),
    ("exp(1000*t)", "acceleration", None),
])
def test_an_expression_that_turns_non_finite_is_refused_naming_field_and_time(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], expression: str, quantity: str, time: float | None) -> None:
    data = copy.deepcopy(BASE)
    data["goal"][0]["trajectory"]["x"][1] = expression
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    assert main(["run", str(path)]) == 2
    captured = capsys.readouterr()
    error = captured.err.strip().splitlines()[-1]
    assert error.startswith("dynfab: error: goal[0].trajectory: the reference's " + quantity)
    if time is not None:
        assert f"at t = {time:g} s" in error
    assert captured.out == ""


@pytest.mark.parametrize("mapping, field", [
    ({"type": "linear", "start": [0.5, 0.0, 0.5], "velocity": [1e308, 0.0, 0.0]}, "obstacles[0].trajectory"),
    ({"type": "polynomial", "coefficients": [[0.5, 1e308, 1e308], [0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]},
     "obstacles[0].trajectory"),
])
def test_an_obstacle_motion_that_overflows_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                      mapping: dict, field: str) -> None:
    data = copy.deepcopy(BASE)
    data["obstacles"] = [{"type": "sphere", "radius": 0.05, "trajectory": mapping}]
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    assert main(["run", str(path)]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith(f"dynfab: error: {field}")


def test_spline_segment_ends_and_every_control_step_are_checked() -> None:
    spline = SplineTrajectory(((0.0, 0.0, 0.0), (0.1, 0.0, 0.0), (0.1, 0.2, 0.0)), 1.234567)
    times = check_times(spline, duration=2.0, dt=0.01)
    assert set(spline.knot_times) <= set(times)
    assert {round(k * 0.01, 12) for k in range(201)} <= {round(t, 12) for t in times}
    assert first_non_finite(spline, 2.0, 0.01) is None


def test_a_finite_reference_passes() -> None:
    trajectory = trajectory_from_mapping({"type": "expression", "x": ["0.5", "0.1*sin(t)", "0.5"]}, "x")
    assert first_non_finite(trajectory, 100.0, 0.01) is None


def test_a_reference_that_turns_non_finite_mid_run_ends_the_run_with_the_metrics_so_far(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The scenario check samples the run; a controller that still meets a non-finite
    reference (here: a trajectory made finite-looking for the check) stops the run."""
    import dataclasses
    import json

    import numpy as np

    from dynfab.motion.trajectories import LinearTrajectory
    from dynfab.scenario import controllers

    class Fails(LinearTrajectory):   # finite for the pre-run check, NaN for the controller after 1 s
        def evaluate(self, t: float):  # type: ignore[override]
            point = super().evaluate(t)
            return dataclasses.replace(point, position=point.position * np.nan) if t >= 1.0 else point

    original = controllers.FabricController.__init__

    def patched(self, planner, references, *args, **kwargs):  # noqa: ANN001
        goals = (Fails(start=tuple(references.goals[0].evaluate(0.0).position), velocity=(0.0, 0.0, 0.0)),)
        original(self, planner, dataclasses.replace(references, goals=goals + references.goals[1:]), *args, **kwargs)

    monkeypatch = pytest.MonkeyPatch()
    monkeypatch.setattr(controllers.FabricController, "__init__", patched)
    try:
        data = copy.deepcopy(BASE)
        path = tmp_path / "scenario.yaml"
        path.write_text(yaml.safe_dump(data), encoding="utf-8")
        code = main(["run", str(path), "--json"])
    finally:
        monkeypatch.undo()
    captured = capsys.readouterr()
    metrics = json.loads(captured.out)
    assert metrics["steps"] == 100   # 1 s at dt = 0.01
    assert "run stopped early: the reference of planner goal 0 turned non-finite at t = 1.000 s" in captured.err
    assert "Traceback" not in captured.err
    assert code == 1   # the metrics of the run so far are the output (no success); the reason is on stderr
