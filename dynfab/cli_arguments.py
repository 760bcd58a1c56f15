"""Types of command-line arguments shared by the ``dynfab`` subcommands, and what the
shared ``--workers`` / ``--scheduler`` options ask for."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

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
