"""Run one of the paper's experiments as a series of seeded runs: in parallel, resumable,
with a summary beside the paper's figures and plots.

``run_series(experiment, runs, seed, out_dir)`` writes into ``out_dir``:

- ``scenarios/<exp>_<seed>_<planner>.yaml``: every run's scenario file; ``dynfab run
  FILE`` replays it (the same metrics apart from the solver time);
- ``runs.jsonl``: one JSON line per finished run, appended the moment it finishes:
  ``{"experiment", "seed", "planner", "metrics", "wall_time_s", "code"}`` (``code``: the
  digest of dynfab's source, :func:`~dynfab.fabric.fingerprint.package_digest`). On start,
  the (seed, planner) pairs already in it are skipped, so an interrupted series resumes; a
  log written by other code is refused (its runs would not be this code's);
- ``runs.csv``: the same, one row per run of the requested seeds;
- ``summary.md``, ``summary.json``: per planner the success rate, collisions and
  deadlocks (goal not reached, no collision), and mean ± std of the metrics over the runs
  where every planner succeeded (as the paper compares them), beside the paper's figures
  and ratios; the same metrics over each planner's own successful runs. Determined by the
  seeds: byte-identical between executions, also after a kill and a resume;
- ``timings.md``, ``timings.json``: solver time per call and wall time per run, with the
  paper's timing figures and ratios (these differ between executions);
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
import os
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, wait
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import yaml

from dynfab.experiments.cluster import Cluster, series_executor
from dynfab.experiments.registry import Experiment
from dynfab.experiments.series_plots import write_plots
from dynfab.experiments.series_summary import (METRIC_KEYS, MetricValue, RunRecord, SeriesSummary, render_summary,
                                               render_timings, summarize, summary_dict, timings_dict)
from dynfab.fabric.fingerprint import package_digest
from dynfab.scenario.recording import Recording, run_recording, save_recording
from dynfab.fabric.backends import series_backend
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import scenario_from_dict


Pair = tuple[int, str]


class SeriesError(ValueError):
    """``out_dir`` holds results that do not belong to this series."""


class RunError(RuntimeError):
    """A run of the series raised; the message names its scenario file."""


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
               progress: IO[str] | None = None, record: bool = False, cluster: Cluster | None = None) -> SeriesResult:
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
        cluster: run on Dask instead of ``jobs`` local processes
            (:mod:`dynfab.experiments.cluster`); the results are the same.

    Raises:
        ValueError: ``runs`` or ``jobs`` < 1.
        SeriesError: ``out_dir`` holds runs of another experiment or of another dynfab
            version, a recorded run's scenario file no longer matches what its seed draws,
            or another series is running in it.
        RunError: a run raised (the finished ones stay recorded).
        ClusterError: the Dask cluster cannot be used.
    """
    jobs = (os.cpu_count() or 1) if jobs is None else jobs
    if runs < 1 or jobs < 1:
        raise ValueError(f"runs and jobs must be >= 1, got {runs} and {jobs}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with exclusive(out):
        seeds = tuple(range(seed, seed + runs))
        log = out / "runs.jsonl"
        done = load_records(log, experiment.name)
        files = _write_scenarios(experiment, seeds, out, done)
        pending = sorted((pair for pair in files if pair not in done), key=_slow_first)
        bar = None if progress is None else Progress(progress, experiment.name, len(files), len(files) - len(pending))
        recordings = out / "recordings" if record else None
        if recordings is not None:
            recordings.mkdir(exist_ok=True)
        for entry in _execute(experiment.name, pending, files, min(jobs, max(len(pending), 1)), cluster, log, bar,
                              recordings):
            done[(entry.seed, entry.planner)] = entry
        records = tuple(done[pair] for pair in files)
        summary = summarize(experiment, records)
        _write_csv(out / "runs.csv", records, experiment.name)
        (out / "summary.md").write_text(render_summary(summary), encoding="utf-8")
        (out / "summary.json").write_text(json.dumps(summary_dict(summary), indent=2) + "\n", encoding="utf-8")
        (out / "timings.md").write_text(render_timings(summary), encoding="utf-8")
        (out / "timings.json").write_text(json.dumps(timings_dict(summary), indent=2) + "\n", encoding="utf-8")
        baseline = [r for r in records if r.planner == experiment.planners[0]]
        example = next((r for r in baseline if not r.metrics["success"]), baseline[0])
        write_plots(out / "plots", summary, records, example, files[(example.seed, example.planner)])
    return SeriesResult(out, records, len(pending), summary, example)


@contextmanager
def exclusive(out: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``out/.lock`` (two series, or benchmarks, must not append
    to one log).

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
        SeriesError: a line is not a run record, or belongs to another experiment, or was
            recorded by other code than this process runs (another ``code`` digest).
    """
    records: dict[Pair, RunRecord] = {}
    code = package_digest()
    for number, line in enumerate(log_lines(log), 1):
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
        if data.get("code") != code:
            raise SeriesError(f"{log}:{number}: recorded by another dynfab version (code digest "
                              f"{str(data.get('code'))[:12]}, this one {code[:12]}): use another output directory")
        records.setdefault((record.seed, record.planner), record)
    return records


def log_lines(log: Path) -> list[str]:
    """The complete lines of an append-only log (none if it does not exist); a last line
    without its newline (a write cut short) is removed from the file."""
    if not log.exists():
        return []
    text = log.read_text(encoding="utf-8")
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
        with log.open("r+", encoding="utf-8") as file:
            file.truncate(len(text.encode("utf-8")))
    return text.splitlines()


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


#: Planners whose runs take far longer than a fabric's: the MPC solves a nonlinear program
#: per step (IPOPT), 10-30x a fabric run.
SLOW_PLANNERS = ("mpc",)


def _slow_first(pair: Pair) -> tuple[bool, int]:
    """Submission order: slow planners' runs first, then by seed (longest processing time
    first keeps every worker busy to the end instead of leaving one MPC run alone at the
    tail; the results do not depend on the order)."""
    seed, planner = pair
    return planner not in SLOW_PLANNERS, seed


def _execute(experiment: str, pending: list[Pair], files: dict[Pair, Path], jobs: int, cluster: Cluster | None,
             log: Path, bar: Progress | None, recordings: Path | None) -> Iterator[RunRecord]:
    """Run the pending pairs over ``jobs`` processes or the cluster; append and yield each
    as it finishes (writing its recording into ``recordings`` if given)."""
    if not pending:
        if bar is not None:
            bar.start()
        return
    with series_executor(jobs, cluster) as executor:
        if bar is not None:
            bar.start()
        futures: dict[Future[RunOutcome], Pair] = {
            executor.submit(run_scenario_text, files[pair].read_text(encoding="utf-8"), str(files[pair].parent),
                            recordings is not None): pair
            for pair in pending}
        remaining = set(futures)
        with log.open("a", encoding="utf-8") as file:
            while remaining:
                finished, remaining = wait(remaining, return_when=FIRST_COMPLETED)
                for future in sorted(finished, key=lambda f: pending.index(futures[f])):
                    seed, planner = futures[future]
                    try:
                        metrics, wall_time, recording = future.result()
                    except Exception as error:
                        raise RunError(f"{files[(seed, planner)]}: {type(error).__name__}: {error}") from error
                    if recordings is not None and recording is not None:
                        save_recording(recordings / (files[(seed, planner)].stem + ".npz"),
                                       dataclasses.replace(recording, scenario=str(files[(seed, planner)].resolve())))
                    record = RunRecord(seed, planner, metrics, wall_time)
                    file.write(json.dumps({"experiment": experiment, **dataclasses.asdict(record), "code": package_digest()})
                               + "\n")
                    file.flush()
                    os.fsync(file.fileno())
                    if bar is not None:
                        bar.advance()
                    yield record


RunOutcome = tuple[dict[str, MetricValue], float, Recording | None]


def run_scenario_text(text: str, base_dir: str, record: bool) -> RunOutcome:
    """Worker: run one scenario given as YAML text (a relative URDF path resolves against
    ``base_dir``) on :func:`~dynfab.fabric.backends.series_backend` unless it chooses a backend;
    its metrics, wall time [s] and, if asked, its recording."""
    start = time.perf_counter()
    mapping = yaml.safe_load(text)
    if isinstance(mapping, dict):
        mapping.setdefault("backend", series_backend())
    result = run_scenario(scenario_from_dict(mapping, base_dir))
    recording = run_recording(result.robot, result.record, result.scenario.dt) if record else None
    return result.metrics.to_dict(), time.perf_counter() - start, recording


class Progress:
    """A progress bar on a stream (shared with ``dynfab benchmark``): done/total runs, rate
    and ETA (over this session's runs). Redrawn in place on a terminal; otherwise one line
    per tenth of the series."""

    def __init__(self, stream: IO[str], label: str, total: int, done: int) -> None:
        self._stream = stream
        self._label = label
        self._total = total
        self._initial = done
        self._done = done
        self._start = time.perf_counter()
        self._tty = stream.isatty()
        self._last_tenth = 10 * done // total

    def start(self) -> None:
        """Print the header (once the runs can start: a cluster that cannot be reached
        prints only its error)."""
        resumed = f" ({self._done} already done)" if self._done else ""
        print(f"{self._label}: {self._total} runs{resumed}", file=self._stream, flush=True)
        self._start = time.perf_counter()

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


def _write_csv(path: Path, records: Sequence[RunRecord], experiment: str) -> None:
    with path.open("w", encoding="utf-8", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(["experiment", "seed", "planner", *METRIC_KEYS, "wall_time_s"])
        for r in records:
            values = ("" if r.metrics[k] is None else r.metrics[k] for k in METRIC_KEYS)
            writer.writerow([experiment, r.seed, r.planner, *values, r.wall_time_s])
