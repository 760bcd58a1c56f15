"""Run the reference implementation (PyPI `fabrics` 0.10.0) from our own environment.

The reference pins numpy<2 and lives in its own virtualenv, ``<repo>/.venv-reference``
(created by ``bench/setup_reference.sh``).  This module never imports it: it runs
``bench/reference_fabrics.py`` with that interpreter as a subprocess and parses the
one JSON object the script prints.

    from reference import run_reference, REFERENCE_MISSING_MESSAGE
    result = run_reference(spheres=5, steps=1000, urdf=Path("dynfab/robots/data/panda.urdf"))
    if result is None:
        print(REFERENCE_MISSING_MESSAGE)

The interpreter is the one named by the environment variable DYNFAB_REFERENCE_PYTHON,
else ``<repo>/.venv-reference/bin/python``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

BENCH_DIR = Path(__file__).resolve().parent
REPO_ROOT = BENCH_DIR.parent
SCRIPT = BENCH_DIR / "reference_fabrics.py"
ENV_VAR = "DYNFAB_REFERENCE_PYTHON"
REFERENCE_MISSING_MESSAGE = "reference not installed: run bench/setup_reference.sh"

# Keys every successful result carries (more may be present).
RESULT_KEYS = ("build_s", "step_ms_median", "step_ms_mean", "n_instructions", "spheres", "nan_fraction")


class ReferenceError(RuntimeError):
    """The reference interpreter exists but the benchmark script failed."""


def reference_python() -> Path | None:
    """The reference interpreter, or None if it is not installed."""
    named = os.environ.get(ENV_VAR)
    if named:
        path = Path(named).expanduser()
        return path if path.is_file() and os.access(path, os.X_OK) else None
    for candidate in (REPO_ROOT / ".venv-reference" / "bin" / "python",
                      REPO_ROOT / ".venv-reference" / "Scripts" / "python.exe"):
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    return None


def _parse_json(stdout: str) -> dict:
    for line in reversed(stdout.strip().splitlines()):
        line = line.strip()
        if line.startswith("{"):
            return json.loads(line)
    raise ValueError("no JSON object in the output")


def run_reference(spheres: int, steps: int, urdf: Path, *, timeout: float | None = 600.0,
                  scene: dict | None = None, model: dict | None = None) -> dict | None:
    """Benchmark the reference planner with `spheres` static obstacles.

    ``scene`` (goal and obstacles) and ``model`` (another collision model) are the JSON
    objects of reference_fabrics.py's ``--scene`` and ``--model``.

    Returns the parsed JSON (keys ``RESULT_KEYS`` at least), or None when the
    reference interpreter is absent.  Raises ReferenceError if it is present but
    the script fails, times out or prints no JSON.
    """
    python = reference_python()
    if python is None:
        return None
    cmd = [str(python), str(SCRIPT), "--spheres", str(int(spheres)), "--steps", str(int(steps)),
           "--urdf", str(Path(urdf).resolve()), "--json"]
    with tempfile.TemporaryDirectory(prefix="dynfab-reference-") as folder:
        for name, value in (("scene", scene), ("model", model)):
            if value is not None:
                path = Path(folder) / f"{name}.json"
                path.write_text(json.dumps(value))
                cmd += [f"--{name}", str(path)]
        return _run(cmd, timeout)


def _run(cmd: list[str], timeout: float | None) -> dict:
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)  # our environment's packages must not leak into the reference's
    env.pop("PYTHONHOME", None)
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env,
                              cwd=str(REPO_ROOT), stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired as exc:
        raise ReferenceError(f"reference benchmark timed out after {timeout} s: {' '.join(cmd)}") from exc
    if proc.returncode != 0:
        tail = "\n".join(proc.stderr.strip().splitlines()[-20:])
        raise ReferenceError(f"reference benchmark failed (exit {proc.returncode}): {' '.join(cmd)}\n{tail}")
    try:
        result = _parse_json(proc.stdout)
    except ValueError as exc:
        raise ReferenceError(f"reference benchmark printed no JSON: {proc.stdout[-500:]!r}") from exc
    missing = [k for k in RESULT_KEYS if k not in result]
    if missing:
        raise ReferenceError(f"reference result lacks keys {missing}: {result}")
    return result


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description="Run the reference fabrics benchmark.")
    parser.add_argument("--spheres", type=int, nargs="+", default=[1, 5, 10])
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--urdf", type=Path, default=REPO_ROOT / "dynfab" / "robots" / "data" / "panda.urdf")
    args = parser.parse_args(argv)
    for n in args.spheres:
        result = run_reference(n, args.steps, args.urdf)
        if result is None:
            print(REFERENCE_MISSING_MESSAGE, file=sys.stderr)
            return 1
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
