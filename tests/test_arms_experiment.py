"""Arms as they ship reach goals past spheres and boxes: one seeded run per arm of the
``arms`` series, checked again from its recording on the real meshes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from dynfab.cli import main
from dynfab.experiments.arms import ARM_NAMES, scenario
from dynfab.experiments.registry import EXPERIMENTS
from dynfab.scenario.recording import load_recording


def test_the_series_is_registered_and_draws_each_arm_in_turn() -> None:
    assert EXPERIMENTS["arms"].sampler.args[0] is scenario   # wrapped with the paper setting (no recovery)
    drawn = [scenario(seed)["robot"]["urdf"] for seed in range(4)]
    assert [name in urdf for name, urdf in zip(("ur_description", "kinova", "xarm", "panda"), drawn)] == [True] * 4
    assert scenario(7) == scenario(7)  # reproducible from the seed
    kinds = [obstacle["type"] for obstacle in scenario(5)["obstacles"]]
    assert kinds == ["sphere", "box", "sphere"]


@pytest.mark.parametrize("seed", [4, 5, 6, 7], ids=list(ARM_NAMES))
def test_an_arm_reaches_its_goal_and_the_recording_checks_clean(seed: int, tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario(seed)), encoding="utf-8")
    record = tmp_path / "run.npz"
    assert main(["run", str(path), "--json", "--record", str(record)]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["success"] and not metrics["collision"] and not metrics["self_collision"]
    assert metrics["clearance"] > 0.0 and metrics["min_self_distance"] > 0.0
    assert main(["check", str(record), str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["ok"] and not report["collisions"] and not report["self_collisions"]
    assert not report["joint_limit_violations"]


def test_a_recorded_series_writes_one_recording_per_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from dynfab.experiments.series import run_series

    result = run_series(EXPERIMENTS["arms"], 1, 6, tmp_path, jobs=1, record=True)
    recording = tmp_path / "recordings" / "arms_6_static-fabric.npz"
    assert result.records[0].metrics["success"] and recording.is_file()
    assert load_recording(recording).scenario == str((tmp_path / "scenarios" / "arms_6_static-fabric.yaml").resolve())
    assert main(["check", str(recording), str(tmp_path / "scenarios" / "arms_6_static-fabric.yaml")]) == 0
