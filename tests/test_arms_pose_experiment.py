"""Arms as they ship reach reachable poses among boxes, guided (experiment ``arms-pose``):
the series draws six arms in turn, its goals are poses of configurations free on the
meshes, its boxes keep clear of the arm at the start and at the goal, and seeded runs
reach their pose with no contact on the meshes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from dynfab.cli import main
from dynfab.experiments.arms_pose import (ANGLE_TOLERANCE, BOX_MARGIN, POSE_ARM_NAMES, TOLERANCE, _PoseGeometry,
                                          scenario)
from dynfab.experiments.registry import EXPERIMENTS
from dynfab.geometry.shapes import Box, Placement


def test_the_series_is_registered_guided_and_draws_six_arms_in_turn() -> None:
    assert EXPERIMENTS["arms-pose"].sampler is scenario   # not the paper setting: guidance is the default
    assert POSE_ARM_NAMES == ("ur5", "kinova", "xarm7", "panda", "z1", "so100")
    drawn = [scenario(seed)["robot"]["urdf"] for seed in range(6)]
    assert [name in urdf for name, urdf in zip(("ur5", "kinova", "xarm7", "panda", "z1", "so100"), drawn)] == [True] * 6
    assert scenario(7) == scenario(7)  # reproducible from the seed
    drawn_scenario = scenario(11)
    assert "guidance" not in drawn_scenario and "recovery" not in drawn_scenario
    assert [obstacle["type"] for obstacle in drawn_scenario["obstacles"]] == ["box"] * 3
    (goal,) = drawn_scenario["goal"]
    assert goal["type"] == "pose" and goal["tolerance"] == TOLERANCE and goal["angle_tolerance"] == ANGLE_TOLERANCE


@pytest.mark.parametrize("seed", [4, 5])
def test_boxes_keep_clear_of_the_arm_meshes_at_the_start(seed: int) -> None:
    drawn = scenario(seed)
    geometry = _PoseGeometry.of(POSE_ARM_NAMES[seed % 6])
    home = np.array(drawn["initial_state"]["q"])
    for obstacle in drawn["obstacles"]:
        box = Box(tuple(obstacle["size"]))
        placement = Placement(tuple(obstacle["position"]), tuple(obstacle["orientation"]))
        assert geometry.clearance(home, box, placement) > BOX_MARGIN - 1e-3   # rounded to 0.1 mm


@pytest.mark.parametrize("seed", [16, 17], ids=["z1", "so100"])
def test_an_arm_reaches_its_pose_guided_without_touching_on_the_meshes(seed: int, tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario(seed)), encoding="utf-8")
    assert main(["run", str(path), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["guided"] and metrics["failure"] is None
    assert metrics["goal_reached"] and metrics["success"]
    assert metrics["orientation_error"] < ANGLE_TOLERANCE
    assert not metrics["collision"] and not metrics["self_collision"]
    assert metrics["clearance"] > 0.0 and metrics["min_self_distance"] > 0.0
