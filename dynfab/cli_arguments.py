"""Types of command-line arguments shared by the ``dynfab`` subcommands, what the
shared ``--workers`` / ``--scheduler`` options ask for, and how a long batch of runs
(experiments, benchmarks, tuning) ends: its result, or an exit status."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    from dynfab.experiments.cluster import Cluster


def at_least_one(text: str) -> int:
    """An integer >= 1 from the command line."""
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return int(text)


def positive_number(text: str) -> float:
    """A positive finite number from the command line."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def requested_cluster(workers: int | None, scheduler: str | None) -> Cluster | None:
    """The Dask cluster ``--workers`` / ``--scheduler`` ask for, or ``None`` (local processes)."""
    if workers is None and scheduler is None:
        return None
    from dynfab.experiments.cluster import Cluster

    return Cluster(workers=workers or 1, scheduler=scheduler)


Result = TypeVar("Result")


@dataclass(frozen=True)
class ExitStatus:
    """A batch of runs that ended without a result: 2 for bad input (a usage error), 1 for
    a run that failed, 130 when interrupted."""

    code: int


def reported(work: Callable[[], Result], usage_errors: tuple[type[Exception], ...],
             resume: str) -> Result | ExitStatus:
    """``work()``, or the exit status of its failure with the reason on stderr:
    ``usage_errors`` are bad input (2), a failed run (``RunError``) is 1, an interrupt 130
    (``resume`` says where the finished work is and how to go on)."""
    from dynfab.experiments.series import RunError

    try:
        return work()
    except usage_errors as error:
        print(f"dynfab: error: {error}", file=sys.stderr)
        return ExitStatus(2)
    except RunError as error:
        print(f"dynfab: run failed: {error}", file=sys.stderr)
        return ExitStatus(1)
    except KeyboardInterrupt:
        print(f"\ndynfab: interrupted; {resume}", file=sys.stderr)
        return ExitStatus(130)
