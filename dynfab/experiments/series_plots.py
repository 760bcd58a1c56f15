"""Plots of a series: metric distributions and outcomes per planner, and one run replayed."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from dynfab.experiments.series_summary import METRICS, OUTCOMES, RunRecord, SeriesSummary
from dynfab.scenario.runner import RunResult, run_scenario
from dynfab.scenario.schema import load_scenario
from dynfab.viz.result_plot import plot_result


def write_plots(directory: Path, summary: SeriesSummary, records: Sequence[RunRecord], example: RunRecord,
                 example_file: Path) -> None:
    """Box plots of the metrics, outcome bars and the example run (matplotlib's Agg canvas)."""
    directory.mkdir(parents=True, exist_ok=True)
    _plot_metrics(directory / "metrics.png", summary, records)
    _plot_outcomes(directory / "outcomes.png", summary)
    result = run_scenario(load_scenario(example_file))
    _plot_example(directory / f"example_{example.seed}_{example.planner}.png", result,
                  f"{summary.experiment.name}, seed {example.seed}, {example.planner}")


def _plot_metrics(path: Path, summary: SeriesSummary, records: Sequence[RunRecord]) -> None:
    """One box plot per metric, one box per planner, over all runs where the metric has a
    value (failures included: a collision shows as clearance below zero)."""
    planners = [p.planner for p in summary.planners]
    values = {m: [[float(v) for r in records if r.planner == p and (v := r.metrics[m]) is not None] for p in planners]
              for m in METRICS}
    shown = [m for m in METRICS if any(values[m])]
    figure = Figure(figsize=(3.6 * len(shown), 4.2), layout="constrained")
    for k, metric in enumerate(shown):
        ax = figure.add_subplot(1, len(shown), k + 1)
        ax.boxplot(values[metric], tick_labels=planners)
        ax.set_title(METRICS[metric])
        ax.grid(True, axis="y", alpha=0.3)
        if metric == "clearance":
            ax.axhline(0.0, color="C3", linestyle="--", linewidth=1)
        if metric == "solver_time_ms":
            ax.set_yscale("log")
    figure.suptitle(f"{summary.experiment.name}: metrics over all {len(summary.seeds)} runs per planner "
                    "(where defined)")
    figure.savefig(path, dpi=100)


def _plot_outcomes(path: Path, summary: SeriesSummary) -> None:
    """Success, collision and deadlock counts per planner; the paper's as markers, scaled
    to our number of runs."""
    figure = Figure(figsize=(6.5, 4.2), layout="constrained")
    ax = figure.add_subplot()
    width = 0.8 / len(summary.planners)
    for k, planner in enumerate(summary.planners):
        x = np.arange(len(OUTCOMES)) + (k - (len(summary.planners) - 1) / 2) * width
        ax.bar(x, [planner.outcomes[o] for o in OUTCOMES], width, label=planner.planner)
        paper = [summary.experiment.figure(o, planner.planner) for o in OUTCOMES]
        known = [(xi, f.value * planner.runs) for xi, f in zip(x, paper) if f is not None and f.value is not None]
        if known:
            ax.plot(*zip(*known), "kD", markersize=6, label="paper (scaled)" if k == 0 else None)
    ax.set_xticks(np.arange(len(OUTCOMES)), OUTCOMES)
    ax.set_ylabel("runs")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_title(f"{summary.experiment.name}: outcomes of {len(summary.seeds)} runs per planner")
    ax.legend(loc="best", fontsize="small")
    ax.grid(True, axis="y", alpha=0.3)
    figure.savefig(path, dpi=100)


def _plot_example(path: Path, result: RunResult, title: str) -> None:
    """The replayed example run, drawn as ``dynfab run --plot`` draws a run."""
    plot_result(result, path, title)
