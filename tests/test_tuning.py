"""``dynfab tune``: the objective's order and numbers, the search space's defaults, a tiny
study end to end (a loadable block), resuming, a killed trial run again, bad input."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import optuna
import pytest
import yaml

from dynfab.cli import main
from dynfab.experiments.registry import EXPERIMENTS
from dynfab.experiments.tuning_objective import Objective, evaluate
from dynfab.experiments.tuning_space import SEARCH_SPACE, block_of, default_values
from dynfab.scenario.schema import scenario_from_dict

TINY = ["--train", "2", "--held-out", "2", "--duration", "2.5", "--jobs", "1"]


def _run(reached: bool, time: float | None, clearance: float, collision: bool = False) -> dict[str, Any]:
    return {"success": reached and not collision, "goal_reached": reached, "collision": collision,
            "time_to_goal": time, "clearance": clearance}


def test_the_objective_is_success_first_then_time_and_clearance() -> None:
    durations = [20.0, 20.0]
    best_of_one = evaluate([_run(True, 0.0, 0.3), _run(False, None, 0.3)], durations)
    worst_of_two = evaluate([_run(True, 19.9, 0.0), _run(True, 19.9, 0.0)], durations)
    fast_clear = evaluate([_run(True, 0.1, 0.3), _run(True, 0.1, 0.3)], durations)
    assert fast_clear.score > worst_of_two.score > 1.0 > best_of_one.score  # one more success beats any tie-break
    # tie-break: (T - t + κ c) / ((N + 1) (T + κ c_cap)) with T = 20 s, κ = 10 s/m, c_cap = 0.3 m
    runs = [_run(True, 2.0, 0.1), _run(False, None, 0.5), _run(False, 3.0, -0.01, collision=True)]
    evaluation = evaluate(runs, [20.0] * 3)
    mean_time, mean_clearance = (2.0 + 20.0 + 20.0) / 3, (0.1 + 0.3 + 0.0) / 3
    assert evaluation.time_to_goal == pytest.approx(mean_time)
    assert evaluation.clearance == pytest.approx(mean_clearance)
    assert evaluation.score == pytest.approx(1 / 3 + (20 - mean_time + 10 * mean_clearance) / (4 * 23))
    assert (evaluation.successes, evaluation.collisions, evaluation.deadlocks) == (1, 1, 1)
    worth_nothing = evaluate(runs, [20.0] * 3, Objective(clearance_worth=0.0))
    assert worth_nothing.score == pytest.approx(1 / 3 + (20 - mean_time) / 80)
    with pytest.raises(ValueError, match="one duration per run"):
        evaluate(runs, [20.0])


def test_the_space_holds_every_default_and_blocks_are_rounded() -> None:
    panda = default_values(EXPERIMENTS["exp1"].sampler(0, "static-fabric"))
    assert panda == {"obstacle.gain": 5.0, "obstacle.energy_gain": 0.5, "obstacle.range": 0.2, "goal.gain": 5.0,
                     "speed_control.execution_energy": 0.5, "speed_control.damping": 0.5,
                     "speed_control.goal_damping": 6.0}
    assert default_values(EXPERIMENTS["exp4"].sampler(0, "static-fabric"))["obstacle.range"] == 0.5
    assert {d.key for d in SEARCH_SPACE} == set(panda)
    assert block_of({"obstacle.gain": 3.14159, "goal.gain": 12.3456}) == {"obstacle": {"gain": 3.14},
                                                                         "goal": {"gain": 12.3}}


def _tune(tmp_path: Path, trials: int, *extra: str) -> int:
    return main(["tune", "exp1", "--trials", str(trials), "--study", str(tmp_path / "study.db"),
                 "--out", str(tmp_path / "best.yaml"), *TINY, *extra])


def _trials(tmp_path: Path) -> list[optuna.trial.FrozenTrial]:
    study = optuna.load_study(study_name="dynfab-tune", storage=f"sqlite:///{tmp_path / 'study.db'}")
    return study.get_trials(states=(optuna.trial.TrialState.COMPLETE,))


def test_a_tiny_study_writes_a_loadable_block_and_resumes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _tune(tmp_path, 2) == 0
    out, err = capsys.readouterr()
    assert "| success | " in out and "held-out (2): defaults" in out
    assert "2 trials run" in err
    first = _trials(tmp_path)
    assert len(first) == 2 and first[0].user_attrs["default"] is True
    assert first[0].params == default_values(EXPERIMENTS["exp1"].sampler(0, "static-fabric"))
    written = yaml.safe_load((tmp_path / "best.yaml").read_text(encoding="utf-8"))
    assert set(written) == {"fabric"}
    best = max(first, key=lambda t: t.value)
    assert written["fabric"] == block_of(best.params)
    scenario = scenario_from_dict({**EXPERIMENTS["exp1"].sampler(7, "static-fabric"), **written})
    assert scenario.fabric.obstacle.range == written["fabric"]["obstacle"]["range"]

    assert _tune(tmp_path, 3) == 0  # the same study, one more trial
    assert "1 trials run" in capsys.readouterr().err
    resumed = _trials(tmp_path)
    assert len(resumed) == 3
    assert [(t.number, t.params, t.value) for t in resumed[:2]] == [(t.number, t.params, t.value) for t in first]
    assert resumed[2].params != resumed[1].params  # a resumed sampler draws new parameters

    assert _tune(tmp_path, 3) == 0  # finished: nothing runs, held-out results come from the study
    out, err = capsys.readouterr()
    assert "0 trials run" in err and "held-out" not in err.replace("then 2 held-out", "")


def test_a_killed_trial_runs_again(tmp_path: Path) -> None:
    assert _tune(tmp_path, 1) == 0
    study = optuna.load_study(study_name="dynfab-tune", storage=f"sqlite:///{tmp_path / 'study.db'}")
    distributions = {d.key: optuna.distributions.FloatDistribution(d.low, d.high, log=d.log) for d in SEARCH_SPACE}
    killed = study.ask(distributions)  # what a SIGKILL during a trial leaves: a RUNNING trial
    assert _tune(tmp_path, 2) == 0
    trials = optuna.load_study(study_name="dynfab-tune", storage=f"sqlite:///{tmp_path / 'study.db'}").trials
    assert trials[killed.number].state == optuna.trial.TrialState.FAIL
    completed = [t for t in trials if t.state == optuna.trial.TrialState.COMPLETE]
    assert len(completed) == 2 and completed[1].params == killed.params


@pytest.mark.parametrize(("arguments", "message"), [
    (["exp9"], "unknown experiment 'exp9'"),
    (["exp1", *TINY, "--planner", "mpc"], "--planner: expected static-fabric or dynamic-fabric"),
    (["exp1", *TINY, "--train-seed", "1"], "training seeds 1..2 overlap held-out seeds 0..1"),
    (["exp1", *TINY, "--duration", "-1"], "--duration: expected a number of seconds"),
    (["exp1", *TINY, "--out", "/no/such/folder/best.yaml"], "--out: folder /no/such/folder does not exist"),
])
def test_bad_input_exits_2(arguments: list[str], message: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                           capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["tune", *arguments]) == 2
    assert not (tmp_path / "dynfab-tuning" / "exp1.db").exists()
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and err.startswith(f"dynfab: error: {message}")


def test_a_study_of_another_setup_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _tune(tmp_path, 1) == 0
    capsys.readouterr()
    assert _tune(tmp_path, 1, "--seed", "5") == 2
    assert capsys.readouterr().err == (
        f"dynfab: error: --study: {tmp_path / 'study.db'} tunes another setup (differs in sampler_seed); "
        "use another --study file\n")


def test_without_optuna_the_command_says_what_to_install(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setitem(sys.modules, "optuna", None)
    assert _tune(tmp_path, 1) == 2
    assert capsys.readouterr().err == "dynfab: error: dynfab tune needs optuna: pip install 'dynfab[tune]'\n"


def test_trials_run_on_dask_with_the_same_results(tmp_path: Path) -> None:
    local, dask = tmp_path / "local", tmp_path / "dask"
    local.mkdir()
    dask.mkdir()
    assert _tune(local, 2) == 0
    assert _tune(dask, 2, "--workers", "1") == 0
    assert [(t.params, t.value) for t in _trials(dask)] == [(t.params, t.value) for t in _trials(local)]
