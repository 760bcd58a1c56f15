"""A series killed with SIGKILL mid-run and started again loses no finished run, re-runs
none, and ends with the same results as an uninterrupted series (issue 11 item 6).

The summaries (summary.md, summary.json) must be byte-identical; timings (solver and wall
time) differ between any two executions and live in timings.md / timings.json.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ARGS = ["experiment", "exp2a", "--runs", "3", "--jobs", "1"]


def _dynfab(out: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "dynfab.cli", *ARGS, "--out", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _runs(out: Path) -> list[str]:
    log = out / "runs.jsonl"
    return log.read_text(encoding="utf-8").splitlines() if log.exists() else []


def _results(lines: list[str]) -> dict[tuple[int, str], dict]:
    results = {}
    for line in lines:
        record = json.loads(line)
        metrics = {k: v for k, v in record["metrics"].items() if k not in ("solver_time_ms", "plan_time_ms")}
        results[(record["seed"], record["planner"])] = metrics
    return results


def test_a_killed_series_resumes_without_losing_or_repeating_runs(tmp_path: Path) -> None:
    killed, clean = tmp_path / "killed", tmp_path / "clean"
    process = _dynfab(killed)
    deadline = time.monotonic() + 300
    while len(_runs(killed)) < 2 and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert process.poll() is None, "the series ended before it could be killed"
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    before = _runs(killed)
    assert 2 <= len(before) < 6
    assert subprocess.run([sys.executable, "-m", "dynfab.cli", *ARGS, "--out", str(killed)],
                          capture_output=True).returncode == 0
    after = _runs(killed)
    assert after[:len(before)] == before                       # no finished run lost or rewritten
    assert len(after) == 6 and len(_results(after)) == 6       # every run once, none repeated
    assert _dynfab(clean).wait() == 0
    assert _results(after) == _results(_runs(clean))           # the same results as uninterrupted
    for name in ("summary.md", "summary.json"):
        assert (killed / name).read_bytes() == (clean / name).read_bytes(), f"{name} differs"
    assert "solver time" in (killed / "timings.md").read_text(encoding="utf-8")
