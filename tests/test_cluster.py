"""Experiment series on Dask: a real scheduler and two workers started as separate
processes on localhost, the embedded LocalCluster, identical results to a serial run,
resuming, and a one-line error for an unreachable scheduler."""

from __future__ import annotations

import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from dynfab.cli import main
from dynfab.experiments import exp1
from dynfab.experiments.cluster import Cluster
from dynfab.experiments.registry import SF, Experiment
from dynfab.experiments.series import SeriesResult, run_series

SEEDS = 3
TIMING_KEYS = {"solver_time_ms", "plan_time_ms"}   # wall times: they differ between executions


def _short_exp1(seed: int, planner: str) -> dict:
    """Experiment 1's scenario of ``seed``, simulated for 3 s only (a test budget)."""
    return {**exp1.scenario(seed, planner), "duration": 3.0}


SMALL = Experiment(name="exp1", description="Experiment 1, 3 s runs", sampler=_short_exp1, planners=(SF,))


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture(scope="module")
def scheduler() -> Iterator[str]:
    """``tcp://127.0.0.1:PORT`` of a scheduler with two single-thread workers, each its own process."""
    address = f"tcp://127.0.0.1:{_free_port()}"
    port = address.rsplit(":", 1)[1]
    processes = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                   "--port", port, "--no-dashboard"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        from distributed import Client

        for _ in range(2):
            processes.append(subprocess.Popen(
                [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1", "--nworkers", "1",
                 "--no-dashboard", "--no-nanny"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        with Client(address, timeout=30) as client:
            client.wait_for_workers(2, timeout=60)
            assert len(client.scheduler_info()["workers"]) == 2
        yield address
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:  # a worker still trying to say goodbye
                process.kill()
                process.wait()


def _metrics(result: SeriesResult) -> list[tuple[int, str, dict]]:
    return [(r.seed, r.planner, {k: v for k, v in r.metrics.items() if k not in TIMING_KEYS}) for r in result.records]


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> SeriesResult:
    return run_series(SMALL, SEEDS, 0, tmp_path_factory.mktemp("serial"), jobs=1)


def test_series_on_an_existing_cluster_equals_the_serial_run_and_resumes(
        scheduler: str, serial: SeriesResult, tmp_path: Path) -> None:
    distributed = run_series(SMALL, SEEDS, 0, tmp_path, cluster=Cluster(scheduler=scheduler))
    assert distributed.executed == SEEDS
    assert _metrics(distributed) == _metrics(serial)
    log = tmp_path / "runs.jsonl"
    log.write_text("".join(log.read_text().splitlines(keepends=True)[:-1]))  # lose the last run
    resumed = run_series(SMALL, SEEDS, 0, tmp_path, cluster=Cluster(scheduler=scheduler))
    assert resumed.executed == 1
    assert _metrics(resumed) == _metrics(serial)


def test_embedded_local_cluster_gives_the_same_results_with_one_progress_bar(
        serial: SeriesResult, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import io

    progress = io.StringIO()
    local = run_series(SMALL, SEEDS, 0, tmp_path, cluster=Cluster(workers=2), progress=progress)
    assert _metrics(local) == _metrics(serial)
    text = progress.getvalue()
    assert text.count("exp1: 3 runs") == 1 and f"{SEEDS}/{SEEDS} runs" in text
    assert capsys.readouterr().err == ""  # dask's own logging stays quiet


def test_unreachable_scheduler_is_one_line_naming_the_connect_timeout(tmp_path: Path,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    """Dask gives up after CONNECT_TIMEOUT_S (5 s), which the error names; no wall-clock
    assertion (bench/ holds those)."""
    from dynfab.experiments.cluster import CONNECT_TIMEOUT_S

    code = main(["experiment", "exp1", "--runs", "1", "--out", str(tmp_path),
                 "--scheduler", f"tcp://127.0.0.1:{_free_port()}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and CONNECT_TIMEOUT_S == 5.0
    assert len(err) == 1 and err[0].startswith("dynfab: error: --scheduler: cannot reach tcp://127.0.0.1:"), err
    assert f"within {CONNECT_TIMEOUT_S:g} s" in err[0]
