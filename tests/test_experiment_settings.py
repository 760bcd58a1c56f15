"""Experiments under another simulation: every scenario carries the keys; bad settings
are one-line errors."""

import pytest

from dynfab.cli import main
from dynfab.experiments.settings import setting_name, with_planners, with_setting
from dynfab.experiments.registry import EXPERIMENTS
from dynfab.scenario.simulation_schema import Simulation


def test_every_drawn_scenario_carries_the_simulation_keys() -> None:
    simulation = Simulation("mujoco", "velocity", 0.01, 0.002)
    experiment = with_setting(EXPERIMENTS["exp1"], simulation)
    for seed in range(3):
        for planner in experiment.planners:
            scenario = experiment.sampler(seed, planner)
            assert scenario == {**EXPERIMENTS["exp1"].sampler(seed, planner), "simulator": "mujoco",
                                "control": "velocity", "delay": 0.01, "noise": 0.002}
            assert scenario["recovery"] is False
    assert "mujoco-velocity-delay0.01-noise0.002" in experiment.description
    assert with_setting(EXPERIMENTS["exp1"], Simulation()) is EXPERIMENTS["exp1"]


def test_setting_names() -> None:
    assert setting_name(Simulation()) == "kinematic"
    assert setting_name(Simulation("mujoco")) == "mujoco-torque"
    assert setting_name(Simulation("mujoco", "position", 0.0, 0.001)) == "mujoco-position-noise0.001"
    assert setting_name(Simulation(), recovery=True) == "kinematic-recovery"


def test_the_paper_runs_have_no_recovery_and_the_setting_turns_it_on() -> None:
    assert EXPERIMENTS["exp4"].sampler(0, "static-fabric")["recovery"] is False
    assert with_setting(EXPERIMENTS["exp4"], Simulation(), recovery=True).sampler(0, "static-fabric")["recovery"]


def test_a_series_of_some_planners_keeps_the_experiments_order_and_scenarios() -> None:
    experiment = with_planners(EXPERIMENTS["exp2a"], ("dynamic-fabric", "static-fabric"))
    assert experiment.planners == EXPERIMENTS["exp2a"].planners
    fabric = with_planners(EXPERIMENTS["exp1"], ("static-fabric",))
    assert fabric.planners == ("static-fabric",)
    assert fabric.sampler(3, "static-fabric") == EXPERIMENTS["exp1"].sampler(3, "static-fabric")
    assert with_planners(EXPERIMENTS["exp1"], ()) is EXPERIMENTS["exp1"]


@pytest.mark.parametrize("arguments, message", [
    (["--simulator", "bullet"], "--simulator: expected one of kinematic, mujoco"),
    (["--simulator", "mujoco", "--control", "fast"], "--control: expected one of torque, velocity, position"),
    (["--simulator", "mujoco", "--delay", "-1"], "--delay: must be >= 0"),
    (["--noise", "0.1"], "need --simulator mujoco"),
    (["--planners", "static-fabric,rrt"], "--planners: rrt is not a planner of exp1 (expected some of static-fabric, mpc)"),
])
def test_bad_settings_are_one_line_errors(tmp_path, capsys, arguments, message) -> None:
    assert main(["experiment", "exp1", "--runs", "1", "--out", str(tmp_path / "out"), *arguments]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and message in error[0]


def test_a_series_runs_under_mujoco_and_its_scenarios_replay_there(tmp_path) -> None:
    import json
    out = tmp_path / "exp2a-mujoco"
    assert main(["experiment", "exp2a", "--runs", "1", "--jobs", "1", "--simulator", "mujoco", "--out", str(out)]) == 0
    for scenario in (out / "scenarios").glob("*.yaml"):
        assert "simulator: mujoco" in scenario.read_text(encoding="utf-8")
    runs = [json.loads(line) for line in (out / "runs.jsonl").read_text(encoding="utf-8").splitlines()]
    assert {run["planner"] for run in runs} == {"static-fabric", "dynamic-fabric"}
    assert all(run["metrics"]["contacts"] is not None for run in runs)   # physics ran: contacts are counted
