"""The benchmark's tables: per problem type (and over all) from the run records of
:mod:`dynfab.benchmarks.mbm.benchmark`.

A valid case succeeds when the goal was reached (dynfab's metrics) and Franka's meshes
(the UR5's for ``ur5-*`` variants) find no collision, no self-collision and no joint beyond its limits over the whole run.
A run whose metrics claim success while the meshes find one of those is *contradicted*:
counted and listed. Invalid cases count neither as success nor as failure.

Run metrics that global guidance adds (``guided``, ``plans``, ``plan_time_ms``,
``goal_moved``, ``failure``) are read where present: the tables work with and without them.
Where the records hold MotionBenchMaker's filter (``reference``:
:mod:`dynfab.benchmarks.mbm.reference_plan`), a second table gives per type the valid
problems the reference planner solves and the successes among them: the success rate on the
problems MotionBenchMaker would have kept.

Writes ``summary.md``, ``summary.json`` (the rows and the flagged cases) and ``runs.csv``
(one row per case).
"""

from __future__ import annotations

import csv
import json
import statistics
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

__all__ = ["CaseOutcome", "TypeRow", "case_outcome", "type_rows", "write_tables"]


@dataclass(frozen=True)
class CaseOutcome:
    """What one case's record says.

    Attributes:
        problem: ``<type>/<NNNN>``.
        type: Its type.
        invalid: Why it is invalid; None if valid.
        refused: Why dynfab refused to run it; None if it ran (or is invalid).
        success: Reached and clean on the meshes.
        claimed: dynfab's metrics say success.
        collision, self_collision, limit_violation: What the meshes found.
        failure: Why a valid case failed (``refused``, the run's ``failure``,
            ``mesh_collision``, ``self_collision``, ``joint_limits``, ``not_reached``); None
            for successes and invalid cases.
        time_to_goal, path_length, plan_time_ms, plans, guided, goal_moved: From the metrics
            (None where absent).
        wall_time_s: Wall time of the run [s]; None if it did not run.
        reference_solved: Whether MotionBenchMaker's filter solved the problem; None if
            it was not run.
    """

    problem: str
    type: str
    invalid: str | None
    refused: str | None
    success: bool
    claimed: bool
    collision: bool
    self_collision: bool
    limit_violation: bool
    failure: str | None
    time_to_goal: float | None
    path_length: float | None
    plan_time_ms: float | None
    plans: int | None
    guided: bool | None
    goal_moved: bool | None
    wall_time_s: float | None
    reference_solved: bool | None = None

    @property
    def contradicted(self) -> bool:
        """The metrics claim success; the meshes disagree."""
        return self.claimed and not self.success


def case_outcome(record: dict[str, Any]) -> CaseOutcome:
    """The outcome of one run record."""
    metrics: dict[str, Any] = record.get("metrics") or {}
    check: dict[str, Any] = record.get("check") or {}
    collision, self_collision = bool(check.get("collisions")), bool(check.get("self_collisions"))
    limits = bool(check.get("joint_limit_violations"))
    success = bool(metrics.get("goal_reached")) and bool(check.get("ok"))
    failure = None
    if record["invalid"] is None and not success:
        failure = ("refused" if record["refused"] is not None else metrics.get("failure")
                   or ("mesh_collision" if collision else "self_collision" if self_collision
                       else "joint_limits" if limits else "not_reached"))
    return CaseOutcome(record["problem"], record["type"], record["invalid"], record["refused"], success,
                       bool(metrics.get("success")), collision, self_collision, limits, failure,
                       metrics.get("time_to_goal") if success else None,
                       metrics.get("path_length") if success else None,
                       metrics.get("plan_time_ms"), metrics.get("plans"), metrics.get("guided"),
                       metrics.get("goal_moved"), record.get("wall_time_s"),
                       None if record.get("reference") is None else bool(record["reference"]["solved"]))


@dataclass(frozen=True)
class TypeRow:
    """One row of the table: the cases of one type (or ``all``).

    Attributes:
        type: The problem type, or ``all``.
        problems, invalid, success: Counts (``success`` among the valid ones).
        collisions, self_collisions, limit_violations: Runs with a mesh collision, a mesh
            self-collision, a joint beyond its limits.
        contradicted: Runs whose metrics claim a success the meshes contradict.
        refused: Valid cases dynfab refused to run.
        median_time_to_goal_s, median_path_length_m: Over the successes.
        median_plan_time_ms, mean_plans: Over the runs that report them.
        guided: Runs that report guidance used.
        goal_moved: Successes whose goal guidance moved inside its tolerance (reached
            within the tolerance, not exactly).
        failures: Failure reasons and their counts.
        referenced: Valid cases MotionBenchMaker's filter was run on.
        reference_solved: Of those, the ones it solved.
        reference_success: Successes among ``reference_solved``.
    """

    type: str
    problems: int
    invalid: int
    success: int
    collisions: int
    self_collisions: int
    limit_violations: int
    contradicted: int
    refused: int
    median_time_to_goal_s: float | None
    median_path_length_m: float | None
    median_plan_time_ms: float | None
    mean_plans: float | None
    guided: int
    goal_moved: int
    failures: dict[str, int]
    referenced: int = 0
    reference_solved: int = 0
    reference_success: int = 0

    @property
    def valid(self) -> int:
        return self.problems - self.invalid


def type_rows(outcomes: Sequence[CaseOutcome], types: Sequence[str]) -> list[TypeRow]:
    """A row per type in ``types`` that has cases, then ``all``."""
    groups = [(t, [o for o in outcomes if o.type == t]) for t in types]
    return [_row(t, group) for t, group in groups if group] + [_row("all", list(outcomes))]


def _row(name: str, cases: Sequence[CaseOutcome]) -> TypeRow:
    ran = [c for c in cases if c.invalid is None and c.refused is None]
    successes = [c for c in ran if c.success]
    return TypeRow(
        name, len(cases), sum(c.invalid is not None for c in cases), len(successes),
        sum(c.collision for c in ran), sum(c.self_collision for c in ran), sum(c.limit_violation for c in ran),
        sum(c.contradicted for c in ran), sum(c.refused is not None for c in cases),
        _median([c.time_to_goal for c in successes]), _median([c.path_length for c in successes]),
        _median([c.plan_time_ms for c in ran]), _mean([c.plans for c in ran]),
        sum(bool(c.guided) for c in ran), sum(bool(c.goal_moved) for c in successes),
        dict(sorted(Counter(c.failure for c in cases if c.failure).items())),
        sum(c.invalid is None and c.reference_solved is not None for c in cases),
        sum(c.invalid is None and bool(c.reference_solved) for c in cases),
        sum(c.success and bool(c.reference_solved) for c in cases))


def _median(values: Sequence[float | None]) -> float | None:
    present = [v for v in values if v is not None]
    return statistics.median(present) if present else None


def _mean(values: Sequence[float | None]) -> float | None:
    present = [v for v in values if v is not None]
    return statistics.fmean(present) if present else None


def write_tables(out: Path, variant: str, types: Sequence[str], records: Sequence[dict[str, Any]]) -> None:
    """Write ``summary.md``, ``summary.json`` and ``runs.csv`` into ``out`` (module doc)."""
    outcomes = [case_outcome(r) for r in records]
    rows = type_rows(outcomes, types)
    flagged = [o for o in outcomes if o.contradicted]
    (out / "summary.md").write_text(_markdown(variant, rows, outcomes), encoding="utf-8")
    summary = {"variant": variant, "rows": [{**asdict(r), "valid": r.valid} for r in rows],
               "contradicted": [o.problem for o in flagged],
               "invalid": {o.problem: o.invalid for o in outcomes if o.invalid is not None}}
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    with (out / "runs.csv").open("w", encoding="utf-8", newline="") as file:
        writer = csv.writer(file)
        keys = [name for name in CaseOutcome.__dataclass_fields__]
        writer.writerow([*keys, "contradicted"])
        for o in outcomes:
            writer.writerow(["" if getattr(o, k) is None else getattr(o, k) for k in keys] + [o.contradicted])


def _markdown(variant: str, rows: Sequence[TypeRow], outcomes: Sequence[CaseOutcome]) -> str:
    ur5 = variant.startswith("ur5-")
    robot, meshes = (("UR5 with gripper", "the UR5's meshes (ur5_gripper.urdf)") if ur5
                     else ("Panda", "Franka's meshes (fingers open 0.04 m)"))
    lines = [f"# MotionBenchMaker ({robot}), {variant}", "",
             f"Success: goal reached with no collision, self-collision or joint-limit violation on {meshes}, in % "
             f"of the valid problems.", "",
             "| type | problems | invalid | success | mesh collisions | self-collisions | joint limits "
             "| contradicted | refused | time to goal [s] | plan time [ms] | path length [m] | plans | guided "
             "| goal moved | failures |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        rate = f"{r.success}/{r.valid} ({100 * r.success / r.valid:.0f} %)" if r.valid else "-"
        failures = ", ".join(f"{k} {v}" for k, v in r.failures.items()) or "-"
        lines.append(f"| {r.type} | {r.problems} | {r.invalid} | {rate} | {r.collisions} | {r.self_collisions} "
                     f"| {r.limit_violations} | {r.contradicted} | {r.refused} | {_shown(r.median_time_to_goal_s)} "
                     f"| {_shown(r.median_plan_time_ms)} | {_shown(r.median_path_length_m)} | {_shown(r.mean_plans)} "
                     f"| {r.guided} | {r.goal_moved} | {failures} |")
    lines += ["", "Times, plan times and path lengths are medians (time to goal and path length over the "
              "successes), plans a mean; contradicted: dynfab's metrics claim a success the meshes contradict; goal "
              "moved: successes reached within the goal's tolerance at a target guidance moved there."]
    if any(r.referenced for r in rows):
        lines += ["", "MotionBenchMaker keeps a generated problem only if its planner solves it; here RRT-Connect on "
                  "the meshes (reference_plan) on the valid problems:", "",
                  "| type | filtered | solved by the reference | success among them |", "|---|---|---|---|"]
        for r in rows:
            rate = (f"{r.reference_success}/{r.reference_solved} ({100 * r.reference_success / r.reference_solved:.0f} %)"
                    if r.reference_solved else "-")
            lines.append(f"| {r.type} | {r.referenced} | {r.reference_solved} | {rate} |")
    flagged = [o for o in outcomes if o.contradicted]
    if flagged:
        lines += ["", "Contradicted by the meshes: " + ", ".join(o.problem for o in flagged) + "."]
    invalid = [o for o in outcomes if o.invalid is not None]
    if invalid:
        lines += ["", "Invalid problems (not run):", ""] + [f"- {o.problem}: {o.invalid}" for o in invalid]
    refused = [o for o in outcomes if o.refused is not None]
    if refused:
        lines += ["", "Refused by dynfab (counted as failures):", ""] + [f"- {o.problem}: {o.refused}" for o in refused]
    return "\n".join(lines) + "\n"


def _shown(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"
