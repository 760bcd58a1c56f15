"""The experiment runner: small series of every experiment end to end (2 seeds, 2 jobs),
their outputs, replay of the scenario files, resuming an interrupted series, the
registry, Experiment 6's scenarios and ``dynfab experiment``."""

from __future__ import annotations

import csv
import fcntl
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from dynfab.cli import main
from dynfab.experiments import exp6
from dynfab.experiments.panda_sampling import PandaSampler
from dynfab.experiments.registry import EXPERIMENTS, MPC
from dynfab.experiments.series import SeriesError, SeriesResult, load_records, run_series, scenario_file
from dynfab.experiments.series_summary import METRIC_KEYS, METRICS, OUTCOMES
from dynfab.fabric.fingerprint import package_digest
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import load_scenario
from dynfab.motion.trajectory_mapping import trajectory_from_mapping

RUNS, JOBS = 2, 2
MPC_REPLAYED = {"exp4"}   # the experiments whose MPC runs are replayed (test_scenario_files_replay...)
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
TIMING_KEYS = {"solver_time_ms", "plan_time_ms"}  # wall-clock metrics, the only ones allowed to differ on replay


@pytest.fixture(scope="module", params=list(EXPERIMENTS))
def series(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> SeriesResult:
    """A series of RUNS seeds of each experiment, run once per module."""
    return run_series(EXPERIMENTS[request.param], RUNS, 0, tmp_path_factory.mktemp(request.param), jobs=JOBS)


def lines(path: Path) -> list[str]:
    """The lines of a text file."""
    return path.read_text(encoding="utf-8").splitlines()


def test_series_runs_every_pair_and_writes_its_outputs(series: SeriesResult) -> None:
    experiment = series.summary.experiment
    out = series.out_dir
    pairs = [(seed, planner) for seed in range(RUNS) for planner in experiment.planners]
    assert series.executed == len(pairs)
    assert [(r.seed, r.planner) for r in series.records] == pairs

    logged = [json.loads(line) for line in lines(out / "runs.jsonl")]
    assert sorted((d["seed"], d["planner"]) for d in logged) == sorted(pairs)
    assert all(d["experiment"] == experiment.name and set(d["metrics"]) == set(METRIC_KEYS) for d in logged)
    with (out / "runs.csv").open(encoding="utf-8") as file:
        rows = list(csv.DictReader(file))
    assert [(int(row["seed"]), row["planner"]) for row in rows] == pairs
    assert [row["success"] == "True" for row in rows] == [r.metrics["success"] for r in series.records]

    for seed, planner in pairs:
        scenario = yaml.safe_load(scenario_file(out, experiment.name, seed, planner).read_text(encoding="utf-8"))
        assert scenario == experiment.sampler(seed, planner), "the file holds the seed's scenario, as drawn"

    markdown = (out / "summary.md").read_text(encoding="utf-8")
    assert markdown.startswith(f"# {experiment.name}: ")
    for planner in experiment.planners:
        assert f"| {planner} | paper |" in markdown
    timings = (out / "timings.md").read_text(encoding="utf-8")
    for figure in experiment.figures:
        assert figure.text in (timings if figure.quantity == "solver_time_ms" else markdown)
    assert "solver time [ms]" not in markdown and "wall time per run" in timings
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["experiment"] == experiment.name and summary["seeds"] == list(range(RUNS))
    assert list(summary["planners"]) == list(experiment.planners)

    plots = out / "plots"
    example = series.example
    expected = {"metrics.png", "outcomes.png", f"example_{example.seed}_{example.planner}.png"}
    assert {p.name for p in plots.iterdir()} == expected
    for name in expected:
        assert (plots / name).read_bytes()[:8] == PNG_MAGIC


def test_summary_counts_outcomes_and_averages_over_common_successes(series: SeriesResult) -> None:
    summary = series.summary
    records = series.records
    common = [s for s in range(RUNS) if all(r.metrics["success"] for r in records if r.seed == s)]
    assert list(summary.common_seeds) == common
    for planner in summary.planners:
        own = [r for r in records if r.planner == planner.planner]
        assert planner.runs == RUNS == sum(planner.outcomes.values())
        assert planner.outcomes["success"] == sum(bool(r.metrics["success"]) for r in own)
        assert planner.outcomes["collisions"] == sum(bool(r.metrics["collision"]) for r in own)
        assert set(planner.outcomes) == set(OUTCOMES)
        for metric in METRICS:
            values = [r.metrics[metric] for r in own if r.seed in common and r.metrics[metric] is not None]
            statistic = planner.metrics[metric]
            if values:
                assert statistic is not None and statistic.n == len(values)
                assert statistic.mean == pytest.approx(np.mean(values))
                assert statistic.std == pytest.approx(np.std(values))
            else:
                assert statistic is None
    for ratio in summary.ratios:
        top = next(p for p in summary.planners if p.planner == ratio.paper.numerator).metrics[ratio.paper.quantity]
        bottom = next(p for p in summary.planners if p.planner == ratio.paper.denominator).metrics[ratio.paper.quantity]
        if top is not None and bottom is not None and bottom.mean:
            assert ratio.ours == pytest.approx(top.mean / bottom.mean)
        else:
            assert ratio.ours is None


def test_scenario_files_replay_to_the_same_metrics(series: SeriesResult) -> None:
    """The first seed's run of every planner replays from its file to identical metrics
    (apart from the solver time); MPC's on the Boxer (exp4, seconds) and not on the Panda
    (exp1, about 50 s of test time a run)."""
    name = series.summary.experiment.name
    replayed = [r for r in series.records if r.seed == 0 and (r.planner != MPC or name in MPC_REPLAYED)]
    for record in replayed:
        path = scenario_file(series.out_dir, name, record.seed, record.planner)
        metrics = run_scenario(load_scenario(path)).metrics.to_dict()
        for key in METRIC_KEYS:
            if key not in TIMING_KEYS:
                assert metrics[key] == record.metrics[key], (path.name, key)


def test_an_interrupted_series_resumes_with_the_missing_runs_only(tmp_path: Path) -> None:
    experiment = EXPERIMENTS["exp6"]
    log = tmp_path / "runs.jsonl"
    first = run_series(experiment, 1, 0, tmp_path, jobs=JOBS)
    assert first.executed == 2 and len(lines(log)) == 2
    first_line = lines(log)[0]

    second = run_series(experiment, 2, 0, tmp_path, jobs=JOBS)
    assert second.executed == 2, "only seed 1's two runs are new"
    assert len(lines(log)) == 4 and lines(log)[0] == first_line
    assert second.records[:2] == first.records, "seed 0's runs are read back, not run again"

    # Interrupt: the last run's line is lost and a write was cut short mid-line.
    kept = lines(log)[:3]
    log.write_text("\n".join(kept) + '\n{"experiment": "exp6", "seed": 1, "pla', encoding="utf-8")
    third = run_series(experiment, 2, 0, tmp_path, jobs=JOBS)
    assert third.executed == 1
    assert lines(log)[:3] == kept and len(lines(log)) == 4
    assert len(load_records(log, "exp6")) == 4


def test_an_output_directory_of_another_experiment_is_refused(tmp_path: Path) -> None:
    metrics = dict.fromkeys(METRIC_KEYS, 0)
    record = {"experiment": "exp2a", "seed": 0, "planner": "static-fabric", "metrics": metrics, "wall_time_s": 1.0}
    (tmp_path / "runs.jsonl").write_text(json.dumps(record) + "\n", encoding="utf-8")
    with pytest.raises(SeriesError, match="holds runs of exp2a, not exp6"):
        run_series(EXPERIMENTS["exp6"], 1, 0, tmp_path, jobs=1)
    assert not (tmp_path / "summary.md").exists()


def test_an_output_directory_of_another_dynfab_version_is_refused(tmp_path: Path) -> None:
    """Runs recorded by other code (another ``code`` digest, or none: before the digest was
    recorded) are not resumed as if this code had made them."""
    metrics = dict.fromkeys(METRIC_KEYS, 0)
    record = {"experiment": "exp6", "seed": 0, "planner": "static-fabric", "metrics": metrics, "wall_time_s": 1.0}
    for code in ("0" * 64, None):
        (tmp_path / "runs.jsonl").write_text(json.dumps({**record, "code": code}) + "\n", encoding="utf-8")
        with pytest.raises(SeriesError, match="runs.jsonl:1: recorded by another dynfab version"):
            run_series(EXPERIMENTS["exp6"], 1, 0, tmp_path, jobs=1)
    assert not (tmp_path / "summary.md").exists()
    (tmp_path / "runs.jsonl").write_text(json.dumps({**record, "code": package_digest()}) + "\n", encoding="utf-8")
    assert load_records(tmp_path / "runs.jsonl", "exp6")[(0, "static-fabric")].metrics == metrics


def test_a_directory_another_series_is_running_in_is_refused(tmp_path: Path) -> None:
    with (tmp_path / ".lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(SeriesError, match="another series is running"):
            run_series(EXPERIMENTS["exp6"], 1, 0, tmp_path, jobs=1)
    assert not (tmp_path / "runs.jsonl").exists()


def test_registry_figures_belong_to_the_planners_compared() -> None:
    assert list(EXPERIMENTS) == ["exp1", "exp2a", "exp2b", "exp3", "exp4", "exp5", "exp6", "arms", "arms-pose"]
    for name, experiment in EXPERIMENTS.items():
        assert experiment.name == name and experiment.planners
        for figure in experiment.figures:
            assert figure.planner in experiment.planners
        for ratio in experiment.ratios:
            assert {ratio.numerator, ratio.denominator} <= set(experiment.planners)
    assert EXPERIMENTS["exp1"].planners == ("static-fabric", "mpc")
    assert EXPERIMENTS["exp2a"].figure("summed_error", "dynamic-fabric").value == 0.0792
    assert EXPERIMENTS["exp4"].planners == ("static-fabric", "mpc")


@pytest.mark.parametrize("seed", range(5))
def test_exp6_hand_passes_close_to_the_robots_hand_and_forearm(seed: int) -> None:
    data = exp6.scenario(seed, "dynamic-fabric")
    assert data == exp6.scenario(seed, "dynamic-fabric")
    assert data["goal"][0]["position"] == [0.5, 0.0, 0.5] and data["duration"] == 20.0
    (hand,) = data["obstacles"]
    assert hand["radius"] == exp6.HAND_RADIUS and hand["trajectory"]["type"] == "spline"
    waypoints = np.array(hand["trajectory"]["waypoints"])
    assert len(waypoints) == 4 + 3 * exp6.WIGGLE_POINTS
    path = trajectory_from_mapping(hand["trajectory"], "hand").sample(np.arange(0.0, 20.0, 0.01))[0]
    sampler = PandaSampler.create("hand-written")   # the sphere indices exp6 names
    assert np.linalg.norm(sampler.hand_position(exp6.goal_pose()) - exp6.GOAL) < 1e-3

    def gaps(points: np.ndarray, q: tuple[float, ...]) -> np.ndarray:
        """Surface gaps (points, robot spheres) between the hand and the robot at ``q``."""
        centres = np.array(sampler.spheres(q)).T
        return np.linalg.norm(points[:, None] - centres[None], axis=2) - sampler.sphere_radii - exp6.HAND_RADIUS

    step = exp6.WIGGLE_POINTS + 1
    passes = gaps(waypoints[[step, 2 * step]], exp6.goal_pose())
    rounding = 1e-3  # waypoints are written with 4 decimals
    assert exp6.GAP[0] - rounding < passes[0, exp6.FINGERTIPS] < exp6.GAP[1] + rounding
    assert exp6.GAP[0] - rounding < passes[1, list(exp6.FOREARM)].min() < exp6.GAP[1] + rounding
    along = gaps(path, exp6.goal_pose())
    assert along.min() > exp6.GAP[0] - exp6.WIGGLE_INTRUSION - rounding
    assert along[:, list(exp6.FIXED_SPHERES)].min() > exp6.FIXED_CLEARANCE
    assert gaps(path[:1], tuple(data["initial_state"]["q"])).min() > exp6.START_CLEARANCE, "the hand starts away"


def test_cli_runs_a_series_and_prints_its_summary(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["experiment", "exp6", "--runs", "1", "--seed", "3", "--out", str(tmp_path), "--jobs", "1"])
    out, err = capsys.readouterr()
    assert code == 0
    assert out == ((tmp_path / "summary.md").read_text(encoding="utf-8") + "\n"
                   + (tmp_path / "timings.md").read_text(encoding="utf-8"))
    assert "| static-fabric | paper | dynamic-fabric | paper |" in out
    assert "2 runs executed" in err
    assert sorted(p.name for p in (tmp_path / "scenarios").iterdir()) == [
        "exp6_3_dynamic-fabric.yaml", "exp6_3_static-fabric.yaml"]


def test_cli_unknown_experiment_exits_2_with_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["experiment", "exp9", "--runs", "1"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.splitlines() == [f"dynfab: error: unknown experiment 'exp9' (expected one of {', '.join(EXPERIMENTS)})"]
