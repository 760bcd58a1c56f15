"""Run one of the paper's experiments as a series of seeded runs: in parallel, resumable,
with a summary beside the paper's figures and plots.

``run_series(experiment, runs, seed, out_dir)`` writes into ``out_dir``:

- ``scenarios/<exp>_<seed>_<planner>.yaml``: every run's scenario file; ``dynfab run
  FILE`` replays it (the same metrics apart from the solver time);
- ``runs.jsonl``: one JSON line per finished run, appended the moment it finishes:
  ``{"experiment", "seed", "planner", "metrics", "wall_time_s"}``. On start, the
  (seed, planner) pairs already in it are skipped, so an interrupted series resumes;
- ``runs.csv``: the same, one row per run of the requested seeds;
- ``summary.md``, ``summary.json``: per planner the success rate, collisions and
  deadlocks (goal not reached, no collision), and mean ± std of the metrics over the runs
  where every planner succeeded (as the paper compares them), beside the paper's figures
  and ratios; the same metrics over each planner's own successful runs;
- ``plots/metrics.png`` (box plots per planner over all runs), ``plots/outcomes.png`` (success,
  collision and deadlock counts) and ``plots/example_<seed>_<planner>.png``: one run of
  the experiment's first planner (its baseline, static fabrics in every experiment, and
  cheap to replay), replayed and plotted: its first failure, else its first run;
- ``.lock``: held while a series runs, so that two never append to one ``runs.jsonl``.
"""

from __future__ import annotations

import csv
import dataclasses
import fcntl
import json
import multiprocessing
import os
import time
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np
import yaml
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from dynfab.experiments.registry import Experiment, PaperRatio, Quantity
from dynfab.scenario.metrics import Metrics
from dynfab.viz.plots import plot_run
from dynfab.scenario.recording import run_recording, save_recording
from dynfab.scenario.runner import RunResult, run_scenario
from dynfab.scenario.schema import load_scenario

#: The run metrics summarized as mean ± std, with their labels.
METRICS: dict[Quantity, str] = {
    "clearance": "clearance [m]",
    "path_length": "path length [m]",
    "time_to_goal": "time to goal [s]",
    "summed_error": "summed error [m]",
    "solver_time_ms": "solver time [ms]",
}
#: The outcomes of a run; every run has exactly one.
OUTCOMES: tuple[Quantity, ...] = ("success", "collisions", "deadlocks")
METRIC_KEYS: tuple[str, ...] = tuple(field.name for field in dataclasses.fields(Metrics))

MetricValue = bool | int | float | None
Pair = tuple[int, str]


class SeriesError(ValueError):
    """``out_dir`` holds results that do not belong to this series."""


class RunError(RuntimeError):
    """A run of the series raised; the message names its scenario file."""


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
    """

    planner: str
    runs: int
    outcomes: dict[str, int]
    metrics: dict[str, Statistic | None]
    own_metrics: dict[str, Statistic | None]
    wall_time_s: float


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


@dataclass(frozen=True)
class SeriesResult:
    """What :func:`run_series` did and wrote.

    Attributes:
        out_dir: the output directory.
        records: the runs of the requested seeds, by seed, then in the experiment's
            planner order.
        executed: the runs this call ran (the others were already in ``runs.jsonl``).
        summary: the summary written to ``summary.md`` and ``summary.json``.
        example: the run replayed and plotted in ``plots/``.
    """

    out_dir: Path
    records: tuple[RunRecord, ...]
    executed: int
    summary: SeriesSummary
    example: RunRecord


def scenario_file(out_dir: Path, experiment: str, seed: int, planner: str) -> Path:
    """The scenario file of one run: ``out_dir/scenarios/<exp>_<seed>_<planner>.yaml``."""
    return out_dir / "scenarios" / f"{experiment}_{seed}_{planner}.yaml"


def run_series(experiment: Experiment, runs: int, seed: int, out_dir: str | Path, jobs: int | None = None,
               progress: IO[str] | None = None, record: bool = False) -> SeriesResult:
    """Run ``experiment`` on seeds ``seed .. seed + runs - 1`` with each of its planners.

    Writes the scenario files, runs the missing (seed, planner) pairs over ``jobs``
    processes (appending each to ``runs.jsonl`` as it finishes), then the CSV, the
    summary and the plots (see the module docstring).

    Args:
        experiment: the experiment (:data:`dynfab.experiments.registry.EXPERIMENTS`).
        runs: number of seeds, >= 1.
        seed: the first seed.
        out_dir: output directory, created if needed.
        jobs: worker processes, >= 1; default ``os.cpu_count()``.
        progress: stream for a progress bar (done/total, rate, ETA); None is silent.
        record: also write each run's recording to
            ``out_dir/recordings/<exp>_<seed>_<planner>.npz`` (``dynfab check`` reads them).

    Raises:
        ValueError: ``runs`` or ``jobs`` < 1.
        SeriesError: ``out_dir`` holds runs of another experiment, a recorded run's
            scenario file no longer matches what its seed draws, or another series is
            running in it.
        RunError: a run raised (the finished ones stay recorded).
    """
    jobs = (os.cpu_count() or 1) if jobs is None else jobs
    if runs < 1 or jobs < 1:
        raise ValueError(f"runs and jobs must be >= 1, got {runs} and {jobs}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with _exclusive(out):
        seeds = tuple(range(seed, seed + runs))
        log = out / "runs.jsonl"
        done = load_records(log, experiment.name)
        files = _write_scenarios(experiment, seeds, out, done)
        pending = [pair for pair in files if pair not in done]
        bar = None if progress is None else _Progress(progress, experiment.name, len(files), len(files) - len(pending))
        recordings = out / "recordings" if record else None
        if recordings is not None:
            recordings.mkdir(exist_ok=True)
        for entry in _execute(experiment.name, pending, files, jobs, log, bar, recordings):
            done[(entry.seed, entry.planner)] = entry
        records = tuple(done[pair] for pair in files)
        summary = summarize(experiment, records)
        _write_csv(out / "runs.csv", records, experiment.name)
        (out / "summary.md").write_text(render_summary(summary), encoding="utf-8")
        (out / "summary.json").write_text(json.dumps(summary_dict(summary), indent=2) + "\n", encoding="utf-8")
        baseline = [r for r in records if r.planner == experiment.planners[0]]
        example = next((r for r in baseline if not r.metrics["success"]), baseline[0])
        _write_plots(out / "plots", summary, records, example, files[(example.seed, example.planner)])
    return SeriesResult(out, records, len(pending), summary, example)


@contextmanager
def _exclusive(out: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``out/.lock`` (two series must not append to one log).

    Raises:
        SeriesError: another process holds it.
    """
    with (out / ".lock").open("w") as file:
        try:
            fcntl.flock(file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise SeriesError(f"another series is running in {out}") from None
        yield


def load_records(log: Path, experiment: str) -> dict[Pair, RunRecord]:
    """The runs recorded in ``log`` (none if it does not exist).

    A last line without its newline (a write cut short) is removed from the file.

    Raises:
        SeriesError: a line is not a run record, or belongs to another experiment.
    """
    if not log.exists():
        return {}
    text = log.read_text(encoding="utf-8")
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
        with log.open("r+", encoding="utf-8") as file:
            file.truncate(len(text.encode("utf-8")))
    records: dict[Pair, RunRecord] = {}
    for number, line in enumerate(text.splitlines(), 1):
        try:
            data = json.loads(line)
            record = RunRecord(int(data["seed"]), str(data["planner"]), dict(data["metrics"]),
                               float(data["wall_time_s"]))
            name = data["experiment"]
            missing = [key for key in METRIC_KEYS if key not in record.metrics]
            if missing:
                raise KeyError(f"metrics lack {', '.join(missing)}")
        except (ValueError, KeyError, TypeError) as error:
            raise SeriesError(f"{log}:{number}: not a run record ({error})") from None
        if name != experiment:
            raise SeriesError(f"{log} holds runs of {name}, not {experiment}: use another output directory")
        records.setdefault((record.seed, record.planner), record)
    return records


def _write_scenarios(experiment: Experiment, seeds: Sequence[int], out: Path,
                     done: dict[Pair, RunRecord]) -> dict[Pair, Path]:
    """Draw and write every run's scenario file; the files by (seed, planner) in run order."""
    files: dict[Pair, Path] = {}
    (out / "scenarios").mkdir(parents=True, exist_ok=True)
    for seed in seeds:
        for planner in experiment.planners:
            path = scenario_file(out, experiment.name, seed, planner)
            text = (f"# {experiment.name}, seed {seed}, {planner}: replay with `dynfab run {path.name}`\n"
                    + yaml.safe_dump(experiment.sampler(seed, planner), sort_keys=False, default_flow_style=None))
            existing = path.read_text(encoding="utf-8") if path.exists() else None
            if existing != text:
                if existing is not None and (seed, planner) in done:
                    raise SeriesError(f"{path} differs from the scenario seed {seed} draws now, and its run is "
                                      f"recorded: use another output directory")
                path.write_text(text, encoding="utf-8")
            files[(seed, planner)] = path
    return files


def _execute(experiment: str, pending: list[Pair], files: dict[Pair, Path], jobs: int, log: Path,
             bar: _Progress | None, recordings: Path | None) -> Iterator[RunRecord]:
    """Run the pending pairs over ``jobs`` processes; append and yield each as it finishes
    (writing its recording into ``recordings`` if given)."""
    if not pending:
        return
    executor = ProcessPoolExecutor(max_workers=min(jobs, len(pending)),
                                   mp_context=multiprocessing.get_context("spawn"))
    try:
        futures: dict[Future[tuple[dict[str, MetricValue], float]], Pair] = {
            executor.submit(_run_file, str(files[pair]),
                            None if recordings is None else str(recordings / (files[pair].stem + ".npz"))): pair
            for pair in pending}
        remaining = set(futures)
        with log.open("a", encoding="utf-8") as file:
            while remaining:
                finished, remaining = wait(remaining, return_when=FIRST_COMPLETED)
                for future in sorted(finished, key=lambda f: pending.index(futures[f])):
                    seed, planner = futures[future]
                    try:
                        metrics, wall_time = future.result()
                    except Exception as error:
                        raise RunError(f"{files[(seed, planner)]}: {type(error).__name__}: {error}") from error
                    record = RunRecord(seed, planner, metrics, wall_time)
                    file.write(json.dumps({"experiment": experiment, **dataclasses.asdict(record)}) + "\n")
                    file.flush()
                    os.fsync(file.fileno())
                    if bar is not None:
                        bar.advance()
                    yield record
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


def _run_file(path: str, recording: str | None) -> tuple[dict[str, MetricValue], float]:
    """Worker: run one scenario file (recording it to ``recording`` if given); its metrics
    and wall time [s]."""
    start = time.perf_counter()
    result = run_scenario(load_scenario(path))
    if recording is not None:
        save_recording(recording, run_recording(result.robot, result.record, result.scenario.dt))
    return result.metrics.to_dict(), time.perf_counter() - start


class _Progress:
    """A progress bar on a stream: done/total runs, rate and ETA (over this session's
    runs). Redrawn in place on a terminal; otherwise one line per tenth of the series."""

    def __init__(self, stream: IO[str], label: str, total: int, done: int) -> None:
        self._stream = stream
        self._label = label
        self._total = total
        self._initial = done
        self._done = done
        self._start = time.perf_counter()
        self._tty = stream.isatty()
        self._last_tenth = 10 * done // total
        resumed = f" ({done} already done)" if done else ""
        print(f"{label}: {total} runs{resumed}", file=stream, flush=True)

    def advance(self) -> None:
        self._done += 1
        tenth = 10 * self._done // self._total
        if not self._tty and tenth == self._last_tenth and self._done < self._total:
            return
        self._last_tenth = tenth
        elapsed = time.perf_counter() - self._start
        rate = (self._done - self._initial) / elapsed
        eta = (self._total - self._done) / rate
        bar = "#" * (25 * self._done // self._total)
        line = (f"  {self._label} [{bar:<25}] {self._done}/{self._total} runs, {60 * rate:.1f} runs/min, "
                f"elapsed {_duration(elapsed)}, ETA {_duration(eta)}")
        end = "\n" if self._done == self._total or not self._tty else ""
        print(("\r" if self._tty else "") + line, end=end, file=self._stream, flush=True)


def _duration(seconds: float) -> str:
    minutes, seconds = divmod(round(seconds), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}h{minutes:02d}m{seconds:02d}s" if hours else f"{minutes}m{seconds:02d}s"


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
        )
        for planner, own in by_planner.items())
    means = {(s.planner, m): stat.mean for s in planners for m, stat in s.metrics.items() if stat is not None}
    ratios = []
    for ratio in experiment.ratios:
        top, bottom = means.get((ratio.numerator, ratio.quantity)), means.get((ratio.denominator, ratio.quantity))
        ours = top / bottom if top is not None and bottom else None
        ratios.append(RatioSummary(ratio, ours))
    return SeriesSummary(experiment, seeds, common, planners, tuple(ratios))


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
    for metric, label in METRICS.items():
        rows.append([label, *(cell for p in planners
                              for cell in (_shown(p.metrics[metric]), _paper(experiment, metric, p.planner)))])
    rows.append(["wall time per run [s]", *(cell for p in planners for cell in (f"{p.wall_time_s:.3g}", ""))])
    lines = [f"# {experiment.name}: {experiment.description}", "",
             f"Seeds {summary.seeds[0]}..{summary.seeds[-1]} ({len(summary.seeds)} runs per planner). Outcomes "
             f"over all runs; metrics (mean ± std) over the {len(summary.common_seeds)} runs where every planner "
             "succeeded, as the paper compares them; wall time over all runs.", "", *_table(rows)]
    if any(p.outcomes["success"] != len(summary.common_seeds) for p in planners):
        own = [["", *(f"{p.planner} ({p.outcomes['success']} runs)" for p in planners)]]
        own += [[label, *(_shown(p.own_metrics[metric]) for p in planners)] for metric, label in METRICS.items()]
        lines += ["", "The same metrics over each planner's own successful runs:", "", *_table(own)]
    if summary.ratios:
        lines += ["", "Ratios of the means (runs where every planner succeeded):", ""]
        lines += [f"- {METRICS[r.paper.quantity]} {r.paper.numerator} / {r.paper.denominator}: ours "
                  f"{'–' if r.ours is None else f'{r.ours:.3g}'}, paper {r.paper.text}" for r in summary.ratios]
    if experiment.notes:
        lines += ["", experiment.notes]
    return "\n".join(lines) + "\n"


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


def _statistics_dict(statistics: dict[str, Statistic | None]) -> dict[str, dict[str, float] | None]:
    return {m: None if s is None else dataclasses.asdict(s) for m, s in statistics.items()}


def summary_dict(summary: SeriesSummary) -> dict[str, Any]:
    """The summary as a JSON-ready mapping."""
    experiment = summary.experiment
    return {
        "experiment": experiment.name,
        "description": experiment.description,
        "seeds": list(summary.seeds),
        "common_success_seeds": list(summary.common_seeds),
        "planners": {p.planner: {"runs": p.runs, **p.outcomes, "success_rate": p.outcomes["success"] / p.runs,
                                 "metrics": _statistics_dict(p.metrics),
                                 "own_success_metrics": _statistics_dict(p.own_metrics),
                                 "wall_time_s": p.wall_time_s}
                     for p in summary.planners},
        "paper": [dataclasses.asdict(f) for f in experiment.figures],
        "ratios": [{**dataclasses.asdict(r.paper), "ours": r.ours} for r in summary.ratios],
        "notes": experiment.notes,
    }


def _write_csv(path: Path, records: Sequence[RunRecord], experiment: str) -> None:
    with path.open("w", encoding="utf-8", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(["experiment", "seed", "planner", *METRIC_KEYS, "wall_time_s"])
        for r in records:
            values = ("" if r.metrics[k] is None else r.metrics[k] for k in METRIC_KEYS)
            writer.writerow([experiment, r.seed, r.planner, *values, r.wall_time_s])


def _write_plots(directory: Path, summary: SeriesSummary, records: Sequence[RunRecord], example: RunRecord,
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
    """The replayed example run: the goal link's path, goal, obstacles and clearance."""
    goal = result.scenario.goals[0]
    target = result.goal_reference if goal.type == "path" else goal.position
    obstacles = result.scenario.obstacles
    spheres = [k for k, o in enumerate(obstacles) if o.type == "sphere"]
    shapes = [(o.shape, o.orientation, result.obstacle_centers[:, k]) for k, o in enumerate(obstacles)
              if o.type != "sphere"]
    metrics = result.metrics
    outcome = "success" if metrics.success else "collision" if metrics.collision else "deadlock"
    plot_run(path, result.goal_positions, [(target, goal.tolerance)], result.obstacle_centers[:, spheres],
             [obstacles[k].radius for k in spheres], result.robot.planar,
             clearance_over_time=result.clearance if obstacles else None, times=result.record.t,
             title=f"{title}: {outcome}", base_path=None if result.robot.base is None else result.record.q[:, :2],
             shapes=shapes)
