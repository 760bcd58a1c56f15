"""``dynfab tune EXPERIMENT --trials N``: search the ``fabric:`` parameters of an experiment
with Optuna (:mod:`dynfab.experiments.tuning`), print the tuned block against the defaults
on training and held-out scenarios, and write the best block as a scenario YAML fragment
(``fabric: ...``) to ``--out``.

Exit codes: 0 done, 2 invalid input (unknown experiment, overlapping seeds, a study of
another setup, optuna or the Dask cluster unavailable, ``--out`` not writable), 1 a run
failed, 130 on Ctrl-C (rerun the same command to resume).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import yaml

from dynfab.cli_arguments import ExitStatus, at_least_one, requested_cluster, reported
from dynfab.experiments.tuning_objective import Evaluation

__all__ = ["add_tune_parser", "comparison_table", "tune_command"]


def add_tune_parser(commands: Any) -> None:
    """Register ``tune`` on the ``dynfab`` subparsers."""
    tune = commands.add_parser("tune", help="search the fabric: parameters of an experiment with Optuna "
                                            "(resumable) and write the best block")
    tune.add_argument("name", metavar="EXPERIMENT", help="exp1, exp2a, exp2b, exp3, exp4, exp5, exp6 or arms")
    tune.add_argument("--trials", type=at_least_one, default=30, help="finished trials the study should hold (default 30)")
    tune.add_argument("--out", type=Path, help="YAML file of the best block (default dynfab-tuning/NAME-fabric.yaml)")
    tune.add_argument("--study", type=Path, help="SQLite file of the Optuna study; rerunning continues it "
                                                 "(default dynfab-tuning/NAME.db)")
    tune.add_argument("--planner", help="the fabric planner tuned (default: the experiment's first)")
    tune.add_argument("--train", type=at_least_one, default=40, help="training scenarios (default 40)")
    tune.add_argument("--train-seed", type=int, default=100_000, help="first training seed (default 100000)")
    tune.add_argument("--held-out", type=at_least_one, default=100, help="held-out scenarios (default 100)")
    tune.add_argument("--held-out-seed", type=int, default=0,
                      help="first held-out seed (default 0: the seeds of dynfab experiment)")
    tune.add_argument("--duration", type=float, help="simulated time of every run [s] (default: the experiment's)")
    tune.add_argument("--seed", type=int, default=0, help="seed of the TPE sampler (default 0)")
    tune.add_argument("--jobs", type=at_least_one, default=2, help="worker processes for the runs (default 2)")
    tune.add_argument("--workers", type=at_least_one, help="run on Dask: an embedded LocalCluster of this many workers")
    tune.add_argument("--scheduler", metavar="tcp://HOST:8786", help="run on the existing Dask cluster of this "
                                                                     "scheduler")


def tune_command(args: argparse.Namespace) -> int:
    """Run ``dynfab tune`` (module docstring for the exit codes)."""
    from dynfab.experiments.cluster import ClusterError
    from dynfab.experiments.registry import EXPERIMENTS
    from dynfab.experiments.tuning import TuningError, TuningResult, TuningSetup, tune

    if args.name not in EXPERIMENTS:
        return _error(f"unknown experiment {args.name!r} (expected one of {', '.join(EXPERIMENTS)})")
    experiment = EXPERIMENTS[args.name]
    fabric = [planner for planner in experiment.planners if planner != "mpc"]
    study = args.study or Path("dynfab-tuning") / f"{args.name}.db"
    out = args.out or Path("dynfab-tuning") / f"{args.name}-fabric.yaml"
    if args.duration is not None and not 0 < args.duration <= 1e4:
        return _error(f"--duration: expected a number of seconds in (0, 10000], got {args.duration:g}")
    if args.out is not None and not out.parent.is_dir():
        return _error(f"--out: folder {out.parent} does not exist")
    cluster = requested_cluster(args.workers, args.scheduler)
    def run() -> tuple[TuningSetup, TuningResult]:
        setup = TuningSetup(experiment, args.planner or fabric[0], args.train, args.train_seed, args.held_out,
                            args.held_out_seed, args.duration, args.seed)
        return setup, tune(setup, args.trials, study, args.jobs, cluster,
                           progress=lambda line: print(f"dynfab: {line}", file=sys.stderr, flush=True))

    outcome = reported(run, (TuningError, ClusterError),
                       f"the finished trials are in {study}, rerun the same command to resume")
    if isinstance(outcome, ExitStatus):
        return outcome.code
    setup, result = outcome
    print(f"{args.name}, {setup.planner}: best of {result.trials} trials is trial {result.best_trial}")
    print(comparison_table(result.training, result.held_out, setup.train, setup.held_out))
    header = (f"# dynfab tune {args.name} --trials {result.trials}: trial {result.best_trial}, planner {setup.planner}, "
              f"{setup.train} training scenarios (seeds {setup.train_seed}..)\n"
              f"# held-out ({setup.held_out}, seeds {setup.held_out_seed}..): defaults "
              f"{_line(result.held_out[0])}; tuned {_line(result.held_out[1])}\n")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(header + yaml.safe_dump({"fabric": result.best_block}, sort_keys=False), encoding="utf-8")
    except OSError as error:
        return _error(f"--out: cannot write {out} ({error.strerror})")
    print(f"dynfab: {result.executed} trials run; best block written to {out}", file=sys.stderr)
    return 0


def comparison_table(training: tuple[Evaluation, Evaluation], held_out: tuple[Evaluation, Evaluation],
                     train: int, held: int) -> str:
    """A Markdown table of (defaults, tuned) on training and held-out scenarios."""
    columns = (*training, *held_out)
    rows = [
        ("success", [f"{e.successes}/{e.runs}" for e in columns]),
        ("collisions", [str(e.collisions) for e in columns]),
        ("deadlocks", [str(e.deadlocks) for e in columns]),
        ("time to goal [s]", [f"{e.time_to_goal:.2f}" for e in columns]),
        ("clearance [m]", [f"{e.clearance:.3f}" for e in columns]),
        ("score", [f"{e.score:.4f}" for e in columns]),
    ]
    lines = [f"| | training ({train}): defaults | tuned | held-out ({held}): defaults | tuned |",
             "|---|---|---|---|---|"]
    lines += [f"| {name} | " + " | ".join(values) + " |" for name, values in rows]
    return "\n".join(lines)


def _line(evaluation: Evaluation) -> str:
    return (f"{evaluation.successes}/{evaluation.runs} succeeded, time to goal {evaluation.time_to_goal:.2f} s, "
            f"clearance {evaluation.clearance:.3f} m")


def _error(message: str) -> int:
    print(f"dynfab: error: {message}", file=sys.stderr)
    return 2
