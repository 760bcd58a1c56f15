"""Where the runs of a series execute: local worker processes, or a Dask cluster.

:func:`series_executor` gives a ``concurrent.futures.Executor``:

- without a cluster, a ``ProcessPoolExecutor`` of ``jobs`` spawned processes;
- ``Cluster(workers=K)``: an embedded ``dask.distributed.LocalCluster`` of K worker
  processes with one thread each, started for the series and closed after it;
- ``Cluster(scheduler="tcp://HOST:8786")``: an existing Dask cluster (its workers must be
  able to import dynfab). Runs travel as scenario text, results as values, so workers
  need no shared file system.

Every run is a pure function of its scenario file, so where it runs does not change its
metrics (only its wall and solver times).
"""

from __future__ import annotations

import logging
import multiprocessing
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass

#: seconds to wait for an existing scheduler before giving up
CONNECT_TIMEOUT_S = 5.0


class ClusterError(RuntimeError):
    """The cluster cannot be used (dask missing, scheduler unreachable)."""


@dataclass(frozen=True)
class Cluster:
    """A Dask cluster to run a series on.

    Attributes:
        workers: worker processes of an embedded ``LocalCluster`` (>= 1); ignored with
            ``scheduler``.
        scheduler: address of an existing scheduler, e.g. ``tcp://10.0.0.5:8786``;
            ``None`` starts the embedded cluster.
    """

    workers: int = 1
    scheduler: str | None = None

    def __post_init__(self) -> None:
        if self.workers < 1:
            raise ValueError(f"Cluster.workers must be >= 1, got {self.workers}")


@contextmanager
def series_executor(jobs: int, cluster: Cluster | None) -> Iterator[Executor]:
    """An executor for the runs (see module docstring); shut down on exit, cancelling
    what has not started.

    Raises:
        ClusterError: dask.distributed is not installed, or the scheduler does not answer
            within :data:`CONNECT_TIMEOUT_S`.
    """
    if cluster is None:
        executor = ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"))
        try:
            yield executor
        finally:
            executor.shutdown(wait=True, cancel_futures=True)
        return
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ClusterError("--workers and --scheduler need dask.distributed: "
                           "pip install 'dynfab[cluster]'") from None
    local = None
    if cluster.scheduler is None:
        local = LocalCluster(n_workers=cluster.workers, threads_per_worker=1, processes=True,
                             dashboard_address=":0", silence_logs=logging.ERROR)
        address = local.scheduler_address
    else:
        address = cluster.scheduler
        logging.getLogger("distributed").setLevel(logging.CRITICAL)  # the one-line error says it
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError, ValueError) as error:
        if local is not None:
            local.close()
        reason = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ClusterError(f"--scheduler: cannot reach {address} within {CONNECT_TIMEOUT_S:g} s ({reason})") from None
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()
        if local is not None:
            local.close()
