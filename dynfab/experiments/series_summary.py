"""A series' runs summarized per planner beside the paper's figures: outcomes, mean ± std
of the metrics, ratios; as Markdown (``summary.md``) and JSON (``summary.json``).

The summary holds only what a seed determines, so that two executions of a series with the
same seeds write byte-identical summaries (also after a kill and a resume). Timings (solver
time per call, wall time per run) differ between any two executions, on any machine: they
go to ``timings.md`` and ``timings.json`` with the paper's timing figures and ratios."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from dynfab.experiments.registry import Experiment, PaperRatio, Quantity
from dynfab.scenario.metrics import Metrics


#: The run metrics summarized as mean ± std, with their labels.
METRICS: dict[Quantity, str] = {
    "clearance": "clearance [m]",
    "path_length": "path length [m]",
    "time_to_goal": "time to goal [s]",
    "summed_error": "summed error [m]",
    "solver_time_ms": "solver time [ms]",
}


#: The metrics of :data:`METRICS` that are measured times: in ``timings.md``, not the summary.
TIMINGS: tuple[Quantity, ...] = ("solver_time_ms",)


#: Limit ratios summarized as their worst (largest) value over all runs, with their labels.
LIMIT_RATIOS: dict[str, str] = {
    "max_velocity_ratio": "max velocity / limit (worst run)",
    "max_acceleration_ratio": "max acceleration / limit (worst run)",
}


#: The outcomes of a run; every run has exactly one.
OUTCOMES: tuple[Quantity, ...] = ("success", "collisions", "deadlocks")


METRIC_KEYS: tuple[str, ...] = tuple(field.name for field in dataclasses.fields(Metrics))


MetricValue = bool | int | float | None


@dataclass(frozen=True)
class RunRecord:
    """One finished run, as a line of ``runs.jsonl``.

    Attributes:
        seed: the scenario's seed.
        planner: the planner that ran it.
        metrics: ``Metrics.to_dict()`` of the run.
        wall_time_s: wall time of the whole run (build, simulation, metrics) [s].
    """

    seed: int
    planner: str
    metrics: dict[str, MetricValue]
    wall_time_s: float

    @property
    def outcome(self) -> Quantity:
        """``success``, ``collisions`` or ``deadlocks`` (goal not reached, no collision)."""
        if self.metrics["success"]:
            return "success"
        return "collisions" if self.metrics["collision"] else "deadlocks"


@dataclass(frozen=True)
class Statistic:
    """Mean and (population) standard deviation of ``n`` values."""

    mean: float
    std: float
    n: int


@dataclass(frozen=True)
class PlannerSummary:
    """One planner's results over the series.

    Attributes:
        planner: its name.
        runs: number of runs.
        outcomes: runs per outcome (``success``, ``collisions``, ``deadlocks``).
        metrics: per metric of :data:`METRICS`, over the runs where every planner
            succeeded; None where no such run has a value.
        own_metrics: the same over this planner's own successful runs.
        wall_time_s: mean wall time of one run over all its runs [s].
        worst_ratios: per ratio of :data:`LIMIT_RATIOS`, its largest value over all runs
            (None if no run reports it).
    """

    planner: str
    runs: int
    outcomes: dict[str, int]
    metrics: dict[str, Statistic | None]
    own_metrics: dict[str, Statistic | None]
    wall_time_s: float
    worst_ratios: dict[str, float | None] = dataclasses.field(default_factory=dict)


@dataclass(frozen=True)
class RatioSummary:
    """Our value of a paper's ratio: the ratio of the planners' means, or None."""

    paper: PaperRatio
    ours: float | None


@dataclass(frozen=True)
class SeriesSummary:
    """The series' results beside the paper's.

    Attributes:
        experiment: what ran.
        seeds: the seeds summarized.
        common_seeds: the seeds where every planner succeeded.
        planners: one summary per planner, in the experiment's order.
        ratios: the paper's ratios with ours.
    """

    experiment: Experiment
    seeds: tuple[int, ...]
    common_seeds: tuple[int, ...]
    planners: tuple[PlannerSummary, ...]
    ratios: tuple[RatioSummary, ...]


def summarize(experiment: Experiment, records: Sequence[RunRecord]) -> SeriesSummary:
    """Outcomes per planner, metrics over the seeds where every planner succeeded, and
    our values of the paper's ratios (ratios of those means)."""
    by_planner = {p: [r for r in records if r.planner == p] for p in experiment.planners}
    seeds = tuple(sorted({r.seed for r in records}))
    succeeded = {(r.seed, r.planner) for r in records if r.metrics["success"]}
    common = tuple(s for s in seeds if all((s, p) in succeeded for p in experiment.planners))
    planners = tuple(
        PlannerSummary(
            planner=planner,
            runs=len(own),
            outcomes={o: sum(r.outcome == o for r in own) for o in OUTCOMES},
            metrics={m: _statistic([r.metrics[m] for r in own if r.seed in common]) for m in METRICS},
            own_metrics={m: _statistic([r.metrics[m] for r in own if r.metrics["success"]]) for m in METRICS},
            wall_time_s=float(np.mean([r.wall_time_s for r in own])),
            worst_ratios={m: _worst([r.metrics.get(m) for r in own]) for m in LIMIT_RATIOS},
        )
        for planner, own in by_planner.items())
    means = {(s.planner, m): stat.mean for s in planners for m, stat in s.metrics.items() if stat is not None}
    ratios = []
    for ratio in experiment.ratios:
        top, bottom = means.get((ratio.numerator, ratio.quantity)), means.get((ratio.denominator, ratio.quantity))
        ours = top / bottom if top is not None and bottom else None
        ratios.append(RatioSummary(ratio, ours))
    return SeriesSummary(experiment, seeds, common, planners, tuple(ratios))


def _worst(values: Iterable[MetricValue]) -> float | None:
    kept = [float(v) for v in values if v is not None]
    return max(kept) if kept else None


def _statistic(values: Iterable[MetricValue]) -> Statistic | None:
    kept = [float(v) for v in values if v is not None]
    return Statistic(float(np.mean(kept)), float(np.std(kept)), len(kept)) if kept else None


def render_summary(summary: SeriesSummary) -> str:
    """The summary as Markdown: a table with the paper's figures beside ours, the same
    metrics over each planner's own successes (where those differ from the common
    ones), the ratio lines and the notes."""
    experiment, planners = summary.experiment, summary.planners
    rows = [["", *(cell for p in planners for cell in (p.planner, "paper"))]]
    for outcome in OUTCOMES:
        rows.append([outcome, *(cell for p in planners
                                for cell in (_count(p.outcomes[outcome], p.runs), _paper(experiment, outcome, p.planner)))])
    rows += _metric_rows(summary, _results())
    for ratio, label in LIMIT_RATIOS.items():
        worst = [p.worst_ratios.get(ratio) for p in planners]
        if any(value is not None for value in worst):
            rows.append([label, *(cell for value in worst for cell in ("–" if value is None else f"{value:.3g}", ""))])
    lines = [f"# {experiment.name}: {experiment.description}", "",
             f"Seeds {summary.seeds[0]}..{summary.seeds[-1]} ({len(summary.seeds)} runs per planner). Outcomes "
             f"over all runs; metrics (mean ± std) over the {len(summary.common_seeds)} runs where every planner "
             "succeeded, as the paper compares them. Timings are in timings.md.", "", *_table(rows)]
    lines += _own_and_ratio_lines(summary, _results())
    if experiment.notes:
        lines += ["", experiment.notes]
    return "\n".join(lines) + "\n"


def render_timings(summary: SeriesSummary) -> str:
    """The timings as Markdown: solver time per call beside the paper's, wall time per
    run, and the paper's timing ratios; measured on the machine that ran the series."""
    experiment, planners = summary.experiment, summary.planners
    rows = [["", *(cell for p in planners for cell in (p.planner, "paper"))], *_metric_rows(summary, TIMINGS)]
    rows.append(["wall time per run [s]", *(cell for p in planners for cell in (f"{p.wall_time_s:.3g}", ""))])
    lines = [f"# {experiment.name}: timings", "",
             f"Measured on the machine that ran the series; solver time (mean ± std of each run's mean time per "
             f"controller call) over the {len(summary.common_seeds)} runs where every planner succeeded, wall time "
             "(build, simulation, metrics) over all runs. These differ between executions; the results are in "
             "summary.md.", "", *_table(rows)]
    return "\n".join(lines + _own_and_ratio_lines(summary, TIMINGS)) + "\n"


def _results() -> tuple[Quantity, ...]:
    """The metrics of :data:`METRICS` that a seed determines (all but the timings)."""
    return tuple(m for m in METRICS if m not in TIMINGS)


def _metric_rows(summary: SeriesSummary, metrics: Sequence[Quantity]) -> list[list[str]]:
    """One table row per metric: each planner's mean ± std over the common successes and the paper's figure."""
    return [[METRICS[m], *(cell for p in summary.planners
                           for cell in (_shown(p.metrics[m]), _paper(summary.experiment, m, p.planner)))]
            for m in metrics]


def _own_and_ratio_lines(summary: SeriesSummary, metrics: Sequence[Quantity]) -> list[str]:
    """The ``metrics`` over each planner's own successes (when those differ from the
    common ones), and the paper's ratios of those metrics with ours."""
    planners, lines = summary.planners, []
    if any(p.outcomes["success"] != len(summary.common_seeds) for p in planners):
        own = [["", *(f"{p.planner} ({p.outcomes['success']} runs)" for p in planners)]]
        own += [[METRICS[m], *(_shown(p.own_metrics[m]) for p in planners)] for m in metrics]
        lines += ["", "The same metrics over each planner's own successful runs:", "", *_table(own)]
    ratios = [r for r in summary.ratios if r.paper.quantity in metrics]
    if ratios:
        lines += ["", "Ratios of the means (runs where every planner succeeded):", ""]
        lines += [f"- {METRICS[r.paper.quantity]} {r.paper.numerator} / {r.paper.denominator}: ours "
                  f"{'–' if r.ours is None else f'{r.ours:.3g}'}, paper {r.paper.text}" for r in ratios]
    return lines


def _table(rows: list[list[str]]) -> list[str]:
    """Markdown table lines; the first row is the header."""
    return ["| " + " | ".join(rows[0]) + " |", "|" + "---|" * len(rows[0]),
            *("| " + " | ".join(row) + " |" for row in rows[1:])]


def _count(count: int, runs: int) -> str:
    return f"{count}/{runs} ({100 * count / runs:.0f} %)"


def _paper(experiment: Experiment, quantity: Quantity, planner: str) -> str:
    figure = experiment.figure(quantity, planner)
    return "" if figure is None else figure.text


def _shown(statistic: Statistic | None) -> str:
    return "–" if statistic is None else f"{statistic.mean:.3g} ± {statistic.std:.2g}"


def _statistics_dict(statistics: dict[str, Statistic | None],
                     metrics: Sequence[Quantity]) -> dict[str, dict[str, float] | None]:
    return {m: None if statistics[m] is None else dataclasses.asdict(statistics[m]) for m in metrics}


def summary_dict(summary: SeriesSummary) -> dict[str, Any]:
    """The summary as a JSON-ready mapping (no timings: see :func:`timings_dict`)."""
    experiment, results = summary.experiment, _results()
    return {
        "experiment": experiment.name,
        "description": experiment.description,
        "seeds": list(summary.seeds),
        "common_success_seeds": list(summary.common_seeds),
        "planners": {p.planner: {"runs": p.runs, **p.outcomes, "success_rate": p.outcomes["success"] / p.runs,
                                 "metrics": _statistics_dict(p.metrics, results),
                                 "own_success_metrics": _statistics_dict(p.own_metrics, results), **p.worst_ratios}
                     for p in summary.planners},
        "paper": [dataclasses.asdict(f) for f in experiment.figures if f.quantity not in TIMINGS],
        "ratios": [{**dataclasses.asdict(r.paper), "ours": r.ours} for r in summary.ratios
                   if r.paper.quantity not in TIMINGS],
        "notes": experiment.notes,
    }


def timings_dict(summary: SeriesSummary) -> dict[str, Any]:
    """The timings as a JSON-ready mapping: per planner the solver time statistics and
    the mean wall time per run [s], with the paper's timing figures and ratios."""
    experiment = summary.experiment
    return {
        "experiment": experiment.name,
        "planners": {p.planner: {"metrics": _statistics_dict(p.metrics, TIMINGS),
                                 "own_success_metrics": _statistics_dict(p.own_metrics, TIMINGS),
                                 "wall_time_s": p.wall_time_s}
                     for p in summary.planners},
        "paper": [dataclasses.asdict(f) for f in experiment.figures if f.quantity in TIMINGS],
        "ratios": [{**dataclasses.asdict(r.paper), "ours": r.ours} for r in summary.ratios
                   if r.paper.quantity in TIMINGS],
    }
