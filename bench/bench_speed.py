"""Measurements of issue 12 ("fast at every scale"), each in a fresh interpreter so that
build and cold-start times are real: step times of the VM, the C backend, the exported C
and batched evaluation; compile time with a cold cache; cold start with a warm cache.

Used by ``bench/bench_planner.py`` (``./run bench``); every function returns a dict of
plain numbers.
"""

from __future__ import annotations

import dataclasses
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

BENCH_DIR = Path(__file__).resolve().parent
Q0 = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])


def _planner(robot_name: str, spheres: int, dynamic: bool, backend: str):
    """The benchmark planner: goal at the hand, ``spheres`` seeded obstacles (moving ones
    for a dynamic planner), self-collision and joint limits (the defaults)."""
    from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
    from dynfab.robots import load_robot

    robot = load_robot(robot_name)
    config = PlannerConfig.for_robot(robot, (GoalConfig(link="panda_hand"),), obstacle_slots=spheres, dynamic=dynamic)
    planner = FabricPlanner(robot, dataclasses.replace(config, backend=backend))
    rng = np.random.default_rng(0)
    planner.parameters.goal_position[0][:] = [0.5, -0.4, 0.3]
    planner.parameters.obstacle_position[:] = rng.uniform([-0.6, -0.8, 0.05], [0.8, 0.8, 1.0], size=(spheres, 3))
    planner.parameters.obstacle_radius[:] = 0.15
    if dynamic:
        planner.parameters.obstacle_velocity[:] = rng.normal(0, 0.2, size=(spheres, 3))
        planner.parameters.goal_velocity[0][:] = [0.05, 0.0, 0.0]
    return planner


def _states(planner, count: int, rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray]]:
    q0, nv = planner.robot.default_q.copy(), len(planner.config.limits.names)
    if planner.robot.base is None:
        q0 = Q0
    return [(q0 + rng.normal(0, 0.01, q0.size), rng.normal(0, 0.1, nv)) for _ in range(count)]


def measure_step(robot_name: str, spheres: int, dynamic: bool, backend: str, steps: int) -> dict:
    """Build (timed from before the first dynfab import) and the median ``compute`` time."""
    start = time.perf_counter()
    from dynfab.fabric.planner import FabricPlanner  # noqa: F401  (the import is part of a cold start)

    imported = time.perf_counter()
    planner = _planner(robot_name, spheres, dynamic, backend)
    states = _states(planner, steps, np.random.default_rng(1))
    planner.compute(*states[0])
    first_action = time.perf_counter()
    for q, qdot in states[:50]:
        planner.compute(q, qdot)
    times = []
    for q, qdot in states:
        t0 = time.perf_counter()
        planner.compute(q, qdot)
        times.append(time.perf_counter() - t0)
    return {"backend": planner.backend, "import_s": imported - start, "build_s": planner.build_time_s,
            "first_action_s": first_action - imported, "step_us_median": 1e6 * statistics.median(times),
            "n_instructions": planner.n_instructions}


def measure_batch(rows: int, threads: int, repeats: int) -> dict:
    """Panda, 5 spheres, C backend: env-steps per second of ``compute_batch`` (median call)."""
    planner = _planner("panda", 5, False, "c")
    states = _states(planner, rows, np.random.default_rng(2))
    q, qdot = np.array([s[0] for s in states]), np.array([s[1] for s in states])
    planner.compute_batch(q, qdot, threads=threads)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        planner.compute_batch(q, qdot, threads=threads)
        times.append(time.perf_counter() - t0)
    median = statistics.median(times)
    return {"rows": rows, "threads": threads, "env_steps_per_s": rows / median, "us_per_env_step": 1e6 * median / rows}


def measure_export(folder: str) -> dict:
    """Panda, 5 spheres: export, build the example with its Makefile, run it (its own timing)."""
    from dynfab.fabric.c_export import export_planner

    planner = _planner("panda", 5, False, "vm")
    export_planner(planner, Path(folder), "panda_bench", "bench", Q0, np.zeros(7))
    subprocess.run(["make", "-s", "-C", folder], check=True, capture_output=True)
    out = subprocess.run([str(Path(folder) / "example")], check=True, capture_output=True, text=True).stdout
    values = dict(line.split(" ", 1) for line in out.splitlines())
    return {"step_us": float(values["step_us"])}


def in_fresh_process(function: str, *args: object, cache: str | None = None) -> dict:
    """Run ``function(*args)`` of this module in a new interpreter; its dict. ``cache``:
    the ``DYNFAB_CACHE_DIR`` of that process."""
    code = (f"import json, sys; sys.path.insert(0, {str(BENCH_DIR)!r}); import bench_speed; "
            f"print(json.dumps(bench_speed.{function}(*{args!r})))")
    env = dict(os.environ) if cache is None else {**os.environ, "DYNFAB_CACHE_DIR": cache}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    return json.loads(out.stdout.strip().splitlines()[-1])


def speed_measurements(steps: int) -> dict:
    """Everything ``./run bench`` reports for issue 12, with the machine's load around it."""
    with tempfile.TemporaryDirectory(prefix="dynfab-bench-") as work:
        cache = str(Path(work) / "cache")
        results = {"cpus": os.cpu_count(), "load_before": os.getloadavg()}
        results["vm"] = in_fresh_process("measure_step", "panda", 5, False, "vm", steps, cache=cache)
        results["c_cold_cache"] = in_fresh_process("measure_step", "panda", 5, False, "c", steps, cache=cache)
        results["c"] = in_fresh_process("measure_step", "panda", 5, False, "c", steps, cache=cache)
        results["c_dynamic"] = in_fresh_process("measure_step", "panda", 5, True, "c", steps, cache=cache)
        results["c_boxer_panda_8"] = in_fresh_process("measure_step", "boxer-panda", 8, False, "c", steps, cache=cache)
        results["batch_1000_1"] = in_fresh_process("measure_batch", 1000, 1, 20, cache=cache)
        results["batch_1000_cpus"] = in_fresh_process("measure_batch", 1000, os.cpu_count() or 1, 20, cache=cache)
        results["exported"] = in_fresh_process("measure_export", str(Path(work) / "export"), cache=cache)
        results["load_after"] = os.getloadavg()
    return results
