"""Benchmark: the control loop while a plan is made (issue 19, item 1: the robot never waits
for a plan), on MotionBenchMaker's Panda problems.

    .venv/bin/python bench/bench_async_plans.py [--problems 2] [--switch-interval S] [--json]

For each problem (the first ``--problems`` valid ones of each of the 7 types, object
removed, prepared as ``dynfab benchmark mbm`` prepares them, its fabric on the same
backend) the scenario's guided
controller runs in real time: called every ``dt`` (10 ms, paced by the wall clock; the
robot integrated as a double integrator) from the new goal until its first plan has
arrived, the plan made on the worker thread (``plan_latency=None``). Beside it, in the
same run, the synchronous way (the plan made inside the first call, as before issue 19's
item 1), on the same problem. Reported, over problems:

- the first call's wall time after the new goal: background against synchronous (the
  ratio is the time the robot no longer waits);
- the longest call while the plan is being made, and the median and the longest call
  after it arrived (the control thread waits for the interpreter while the planner's
  Python validity callbacks hold it: at most about ``sys.getswitchinterval()``; after the
  plan arrived no plan is made, so the longest call then is what the machine's load alone
  costs the loop);
- the plan's wall time made in the background against made in the call (the planner
  shares the interpreter with the control loop);
- ticks commanded before the plan arrived.

The loop waits one ``dt`` before its first call, as a loop waits for each tick's state.
``--switch-interval`` sets ``sys.setswitchinterval`` first (Python's default is 5 ms).
The machine's load average is printed at start and end.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import dataclass

import numpy as np

from dynfab.fabric.backends import series_backend
from dynfab.scenario.guided_controller import GuidedController, make_scenario_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import Scenario, scenario_from_dict, validate_for_robot

from bench_guidance import valid_cases  # noqa: E402  (bench/ is the script's folder)

#: longest a loop waits for a plan [s]
PATIENCE = 15.0


@dataclass(frozen=True)
class LoopTimes:
    """One control loop from a new goal until its plan arrived (wall times [ms])."""

    first_call_ms: float
    longest_call_while_planning_ms: float
    median_call_after_ms: float
    longest_call_after_ms: float
    plan_ms: float
    ticks_before_plan: int


def load_scenarios(per_type: int) -> list[tuple[str, Scenario]]:
    """The first ``per_type`` valid object-removed cases of each type, as scenarios (on the
    benchmark's backend: no compile per scene)."""
    cases, _ = valid_cases(per_type, "object-removed")
    return [(name, scenario_from_dict({"backend": series_backend(), **case.mapping})) for name, case in cases]


def control_loop(scenario: Scenario, plan_latency: float | None, after_ticks: int = 50) -> LoopTimes:
    """Call the guided controller every ``dt`` of wall time from the new goal until its plan
    arrived, then ``after_ticks`` more."""
    robot = robot_for(scenario)
    scenario = validate_for_robot(scenario, robot)
    controller = make_scenario_controller(scenario, robot, scenario_references(scenario, robot), plan_latency=plan_latency)
    assert isinstance(controller, GuidedController)
    guided = controller.guided
    dt = scenario.dt
    q, qdot = np.array(scenario.initial_state.q, dtype=float), np.zeros(robot.dof)
    calls: list[float] = []
    arrived_at: int | None = None
    time.sleep(dt)   # a loop waits for each tick's state, its first one too (module docstring)
    began = time.perf_counter()
    tick = 0
    while time.perf_counter() - began < PATIENCE:
        start = time.perf_counter()
        qddot = controller(tick * dt, q, qdot)
        calls.append(1e3 * (time.perf_counter() - start))
        if arrived_at is None and not guided.planning:
            arrived_at = tick
        if arrived_at is not None and tick >= arrived_at + after_ticks:
            break
        q, qdot = q + dt * qdot + 0.5 * dt**2 * qddot, qdot + dt * qddot
        tick += 1
        time.sleep(max(0.0, began + tick * dt - time.perf_counter()))
    guided.close()
    if arrived_at is None:
        raise RuntimeError(f"no plan within {PATIENCE} s")
    during, after = calls[1:arrived_at + 1] or [0.0], calls[arrived_at + 1:] or [0.0]
    return LoopTimes(calls[0], max(during), statistics.median(after), max(after), guided.status.plan_time_ms or 0.0,
                     arrived_at)


def _loadavg() -> list[float]:
    with open("/proc/loadavg", encoding="ascii") as handle:
        return [float(v) for v in handle.read().split()[:3]]


def _summary(rows: list[LoopTimes]) -> dict[str, float]:
    def stat(values: list[float]) -> dict[str, float]:
        return {"median": statistics.median(values), "p95": float(np.percentile(values, 95)), "max": max(values)}
    return {key: stat([float(getattr(row, key)) for row in rows]) for key in LoopTimes.__dataclass_fields__}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", type=int, default=2, help="valid problems per type (7 types)")
    parser.add_argument("--switch-interval", type=float, default=None, help="sys.setswitchinterval [s]")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if args.switch_interval is not None:
        sys.setswitchinterval(args.switch_interval)
    load_start = _loadavg()
    scenarios = load_scenarios(args.problems)
    control_loop(scenarios[0][1], 0.0, after_ticks=1)   # warm-up: imports, compiled models
    background, synchronous = [], []
    for _, scenario in scenarios:
        background.append(control_loop(scenario, None))
        synchronous.append(control_loop(scenario, 0.0))
    result = {"problems": [name for name, _ in scenarios], "switch_interval_s": sys.getswitchinterval(),
              "load_start": load_start, "load_end": _loadavg(),
              "background": _summary(background), "synchronous": _summary(synchronous)}
    if args.json:
        print(json.dumps(result))
        return 0
    b, s = result["background"], result["synchronous"]
    print(f"Control loop during a new goal's plan: {len(scenarios)} MBM Panda problems (object removed), "
          f"dt 10 ms, switch interval {1e3 * result['switch_interval_s']:.1f} ms, load average "
          f"{load_start[0]:.2f} at start, {result['load_end'][0]:.2f} at end")
    print()
    print("| wall time [ms] (median / p95 / max over problems) | plan on a worker thread | plan in the first call "
          "| synchronous / background |")
    print("|---|---|---|---|")
    for key, label in (("first_call_ms", "first call after the new goal"),
                       ("longest_call_while_planning_ms", "longest call while the plan is made"),
                       ("median_call_after_ms", "median call once the plan is followed"),
                       ("longest_call_after_ms", "longest call once the plan is followed (no plan made)"),
                       ("plan_ms", "the plan (IK, path, timing)"),
                       ("ticks_before_plan", "ticks commanded before the plan arrived")):
        ratio = f"{s[key]['median'] / b[key]['median']:.1f}×" if key in ("first_call_ms", "plan_ms") else ""
        print(f"| {label} | {b[key]['median']:.2f} / {b[key]['p95']:.2f} / {b[key]['max']:.2f} | "
              f"{s[key]['median']:.2f} / {s[key]['p95']:.2f} / {s[key]['max']:.2f} | {ratio} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
