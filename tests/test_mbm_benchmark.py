"""``dynfab benchmark mbm`` end to end on three cage problems (one invalid), resumed; and
the tables' reading of run records (with and without the metrics global guidance adds)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from dynfab.benchmarks.mbm.tables import case_outcome, type_rows
from dynfab.cli import main


def test_the_command_runs_reports_and_resumes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    arguments = ["benchmark", "mbm", "--types", "cage", "--problems", "3", "--jobs", "2", "--out", str(tmp_path)]
    assert main(arguments) == 0
    table = capsys.readouterr()
    assert "| cage | 3 | 1 |" in table.out and "mbm as-posed [" in table.err
    summary = json.loads((tmp_path / "summary.json").read_text())
    cage, total = summary["rows"]
    assert (cage["type"], cage["problems"], cage["invalid"], cage["valid"]) == ("cage", 3, 1, 2)
    assert cage["success"] + sum(cage["failures"].values()) == 2
    assert total["type"] == "all" and total["problems"] == 3
    assert list(summary["invalid"]) == ["cage/0011"]  # the open fingers 14 mm into the cube
    assert summary["invalid"]["cage/0011"].startswith("goal: panda_")
    assert sorted(p.name for p in (tmp_path / "scenarios").iterdir()) == ["cage_0009.yaml", "cage_0010.yaml"]
    log = (tmp_path / "runs.jsonl").read_text()
    assert len(log.splitlines()) == 3
    assert main(arguments) == 0  # resumed: nothing left to run
    assert (tmp_path / "runs.jsonl").read_text() == log
    assert main([*arguments[:-2], "--variant", "object-removed", "--out", str(tmp_path)]) == 2
    assert "holds runs of mbm as-posed, not mbm object-removed" in capsys.readouterr().err


def _record(problem: str, metrics: dict | None, check: dict | None, invalid: str | None = None) -> dict:
    return {"problem": problem, "type": problem.split("/")[0], "invalid": invalid, "refused": None,
            "metrics": metrics, "check": check, "wall_time_s": 1.0}


_CLEAN = {"ok": True, "collisions": [], "self_collisions": [], "joint_limit_violations": []}
_TOUCH = {**_CLEAN, "ok": False, "collisions": [{"link": "panda_leftfinger", "other": "obstacles[2]"}]}


def test_tables_flag_contradicted_successes_and_read_guidance_metrics_when_present() -> None:
    reached = {"success": True, "goal_reached": True, "time_to_goal": 3.0, "path_length": 1.0}
    records = [
        _record("box/0009", reached, _CLEAN),  # before guidance lands: no plans, no failure
        _record("box/0013", {**reached, "guided": True, "plans": 1, "plan_time_ms": 15.0, "goal_moved": True}, _CLEAN),
        _record("box/0010", {**reached, "guided": True, "plans": 2, "plan_time_ms": 12.0}, _TOUCH),
        _record("box/0011", {"success": False, "goal_reached": False, "guided": True, "plans": 4,
                             "plan_time_ms": 30.0, "failure": "no_path"}, _CLEAN),
        _record("box/0012", None, None, invalid="goal: panda_joint4 = -0.043 is outside [-3.0718, -0.0698]"),
    ]
    outcomes = [case_outcome(r) for r in records]
    assert [o.success for o in outcomes] == [True, True, False, False, False]
    assert [o.contradicted for o in outcomes] == [False, False, True, False, False]
    assert [o.failure for o in outcomes] == [None, None, "mesh_collision", "no_path", None]
    box, _ = type_rows(outcomes, ["box"])
    assert (box.problems, box.invalid, box.success, box.collisions, box.contradicted) == (5, 1, 2, 1, 1)
    assert box.failures == {"mesh_collision": 1, "no_path": 1}
    assert (box.median_plan_time_ms, box.mean_plans, box.guided, box.goal_moved) == (15.0, 7 / 3, 3, 1)
    assert box.median_time_to_goal_s == 3.0


def test_runs_recorded_by_other_code_are_not_resumed(monkeypatch: pytest.MonkeyPatch) -> None:
    """The digest covers dynfab's source: records of older code are refused, not mixed into
    a table (a rerun into an old output directory once reused them silently)."""
    import dynfab.benchmarks.mbm.benchmark as benchmark
    from dynfab.benchmarks.mbm.franka import franka
    from dynfab.benchmarks.mbm.problems import load_problems
    from dynfab.benchmarks.mbm.variants import prepare_case

    case = prepare_case(load_problems(["box"], per_type=1)[0], "as-posed", franka())
    record = {"digest": benchmark._digest(case.mapping)}
    assert benchmark._fresh(case, {case.problem.name: record}) is record   # the same code: resumed
    monkeypatch.setattr(benchmark, "package_digest", lambda: "other code")
    assert benchmark._digest(case.mapping) != record["digest"]
    with pytest.raises(benchmark.BenchmarkError, match="recorded from another scenario"):
        benchmark._fresh(case, {case.problem.name: record})


def test_tables_give_the_success_among_the_problems_the_reference_planner_solves(tmp_path: Path) -> None:
    from dynfab.benchmarks.mbm.tables import write_tables

    records = [
        {**_record("box/0001", {"goal_reached": True, "success": True}, _CLEAN), "reference": {"solved": True}},
        {**_record("box/0002", {"goal_reached": False, "success": False}, _CLEAN), "reference": {"solved": False}},
        {**_record("box/0003", {"goal_reached": False, "success": False}, _CLEAN), "reference": {"solved": True}},
        _record("box/0004", None, None, invalid="goal: outside"),
    ]
    outcomes = [case_outcome(r) for r in records]
    assert [o.reference_solved for o in outcomes] == [True, False, True, None]
    box, _ = type_rows(outcomes, ["box"])
    assert (box.referenced, box.reference_solved, box.reference_success) == (3, 2, 1)
    write_tables(tmp_path, "as-posed", ["box"], records)
    table = (tmp_path / "summary.md").read_text()
    assert "| box | 3 | 2 | 1/2 (50 %) |" in table
    without = [{k: v for k, v in r.items() if k != "reference"} for r in records]
    write_tables(tmp_path, "as-posed", ["box"], without)
    assert "solved by the reference" not in (tmp_path / "summary.md").read_text()


def test_the_reference_planner_solves_a_free_problem_and_not_one_whose_goal_touches(tmp_path: Path) -> None:
    """MotionBenchMaker's filter (dynfab.benchmarks.mbm.reference_plan) on archive box/0009
    object removed: solved, its path no shorter than the straight distance; with a block
    around the hand at the goal it is not (its end touches the scene on the meshes)."""
    import numpy as np

    from dynfab.benchmarks.mbm.franka import franka
    from dynfab.benchmarks.mbm.problems import load_problems
    from dynfab.benchmarks.mbm.reference_plan import reference_plan
    from dynfab.benchmarks.mbm.variants import prepare_case

    problem = load_problems(["box"], per_type=1)[0]
    case = prepare_case(problem, "object-removed", franka())
    solved = reference_plan(case.mapping, problem.goal, checks=20_000)
    straight = float(np.linalg.norm(np.subtract(problem.goal, problem.start)))
    assert solved["solved"] and solved["length"] >= straight - 1e-9 and solved["mesh_checks"] <= 20_000 + 2_000
    from dynfab.robots import load_robot
    hand = np.asarray(load_robot("panda").link_position(np.array(problem.goal), "panda_hand"), dtype=float).ravel()
    block = {"type": "box", "size": [0.1, 0.1, 0.1], "position": hand.tolist()}   # around the hand at the goal
    touching = reference_plan({**case.mapping, "obstacles": [*case.mapping["obstacles"], block]}, problem.goal,
                              checks=2_000)
    assert not touching["solved"] and touching["length"] is None
    with pytest.raises(ValueError, match="checks"):
        reference_plan(case.mapping, problem.goal, checks=0)


def test_the_command_runs_the_reference_filter_when_asked(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    arguments = ["benchmark", "mbm", "--types", "box", "--problems", "1", "--variant", "object-removed", "--jobs", "1",
                 "--reference-checks", "20000", "--out", str(tmp_path)]
    assert main(arguments) == 0
    assert "| box | 1 | 1 |" in capsys.readouterr().out
    record = json.loads((tmp_path / "runs.jsonl").read_text())
    assert record["reference"]["solved"] is True
    assert main([*arguments[:-4], "--out", str(tmp_path)]) == 2   # recorded with the filter: not resumed without
    assert "recorded from another scenario" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([*arguments[:-4], "--reference-checks", "-1", "--out", str(tmp_path)])
    assert "--reference-checks: expected a non-negative integer, got -1" in capsys.readouterr().err
