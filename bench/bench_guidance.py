"""Benchmark: global joint-space guidance (issue 19, item 6) on MotionBenchMaker's Panda
problems, side by side in one run with the same checks and plans driven by a plain Python
validity check.

    .venv/bin/python bench/bench_guidance.py [--problems N] [--variant object-removed]
                                             [--cap 20] [--configurations 512] [--json]

``--problems N``: the first N valid problems of each of the 7 types (bundled archive,
prepared as ``dynfab benchmark mbm`` prepares them: the variant's scene, start and goal;
cases invalid on Franka's meshes are skipped and counted). Not part of ``./run bench``
(the Python baseline alone takes minutes); run it on its own.

1. **Check time per configuration**, per scene on the same seeded random configurations
   within the joint limits (planning margins: ``margin`` 0.01 m, ``self_margin`` 0):
   the compiled :class:`ConfigurationChecker` (``free`` per configuration from Python;
   ``first_blocked`` and ``batch`` on segments of 64 free configurations; the kernel alone,
   ``first_blocked`` on all of a scene's free configurations in one call, and so the Python
   overhead of ``free``) against the plain Python check: the checker's own numpy path
   (``load_checker_library`` returning None), which evaluates the CasADi forward
   kinematics of the sphere centres per call, ``placed_distance`` per obstacle and the
   self-collision pairs. Each loop is timed 3 times, its best kept (per configuration);
   the table gives the median over scenes.
2. **Plan time**, "new goal -> full plan": :meth:`JointGuidance.plan` (IK when needed,
   endpoint escape, OMPL RRT-Connect, simplification, TOPP-RA timing), ``Plan.time_s``,
   the compiled checker against the same guidance with the Python checker, same planner,
   resolution, margins and seeds. The baseline gets ``--cap`` seconds of OMPL time per
   problem (split over its attempts); a baseline that fails there is counted as hitting
   the cap and its median and 95th percentile are then lower bounds (marked >=).
   Failures enter the statistics with the wall time they took.

The machine's load average (/proc/loadavg) is printed at start and end: the numbers
belong to this machine at this moment.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from typing import TypeVar
from dataclasses import dataclass, replace

import numpy as np

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.moveit import ProblemError
from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES, load_problems
from dynfab.benchmarks.mbm.variants import Case, prepare_case
from dynfab.geometry.shapes import Box, Cylinder, Placement
from dynfab.motion import configuration_checker
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import GuidanceError, GuidanceSettings, JointGuidance, JointTarget
from dynfab.robots.builtin import load_robot
from dynfab.robots.robot import Robot

SEGMENT = 64
ISSUE_TARGETS = {"check_us": 5.0, "plan_median_ms": 30.0, "plan_p95_ms": 300.0}


@dataclass(frozen=True)
class BenchProblem:
    """One valid MBM case: its name, start, joint goal and static obstacles."""

    name: str
    start: np.ndarray
    goal: np.ndarray
    obstacles: tuple[PlacedObstacle, ...]


def valid_cases(per_type: int, variant: str) -> tuple[list[tuple[str, Case]], list[str]]:
    """The first ``per_type`` valid cases of each type in ``variant`` (name, case), and the
    names of the invalid ones skipped on the way."""
    robot = franka()
    cases, skipped = [], []
    for problem_type in PROBLEM_TYPES:
        kept = 0
        for problem in load_problems([problem_type]):
            if kept == per_type:
                break
            try:
                case = prepare_case(problem, variant, robot)
            except ProblemError:
                skipped.append(problem.name)
                continue
            if case.invalid is not None:
                skipped.append(problem.name)
                continue
            cases.append((problem.name, case))
            kept += 1
    return cases, skipped


def load_cases(per_type: int, variant: str) -> tuple[list[BenchProblem], list[str]]:
    """:func:`valid_cases` as the planner's problems."""
    cases, skipped = valid_cases(per_type, variant)
    problems = [BenchProblem(name, np.array(case.mapping["initial_state"]["q"], dtype=float),
                             np.array(case.mapping["goal"][0]["position"], dtype=float),
                             tuple(_placed(o) for o in case.mapping["obstacles"])) for name, case in cases]
    return problems, skipped


def _placed(obstacle: dict) -> PlacedObstacle:
    """A scenario obstacle mapping of an MBM scene (box or cylinder) as a placed obstacle."""
    shape = (Box(tuple(obstacle["size"])) if obstacle["type"] == "box"
             else Cylinder(obstacle["radius"], obstacle["length"]))
    return PlacedObstacle(shape, Placement(tuple(obstacle["position"]), tuple(obstacle["orientation"])))


T = TypeVar("T")


def python_checker(robot: Robot) -> ConfigurationChecker:
    """The checker on its numpy path (as without a C compiler): the plain Python baseline."""
    checker = _without_compiler(lambda: ConfigurationChecker(robot))
    assert not checker.compiled
    return checker


def python_guidance(robot: Robot, settings: GuidanceSettings) -> JointGuidance:
    """Guidance whose checkers (planning, coarse, allowances, ahead) all take the numpy path."""
    guidance = _without_compiler(lambda: JointGuidance(robot, settings))
    assert not guidance.checker.compiled
    return guidance


def _without_compiler(make: Callable[[], T]) -> T:
    """``make()`` with the compiled checker library unavailable."""
    load = configuration_checker.load_checker_library
    configuration_checker.load_checker_library = lambda _robot: None
    try:
        return make()
    finally:
        configuration_checker.load_checker_library = load


def _best_per_item(run: Callable[[], object], items: int, repeats: int = 3) -> float:
    """Best of ``repeats`` wall times of ``run()``, per item [us]."""
    best = math.inf
    for _ in range(repeats):
        began = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - began)
    return 1e6 * best / items


def measure_checks(robot: Robot, problems: Sequence[BenchProblem], margin: float, self_margin: float,
                   configurations: int, baseline_configurations: int, seed: int) -> list[dict]:
    """Per scene: check times per configuration [us] of the compiled checker and the Python one."""
    compiled = ConfigurationChecker(robot)
    assert compiled.compiled, "no C compiler: the compiled checker is not available"
    python = python_checker(robot)
    lower, upper = robot.kinematics.lower, robot.kinematics.upper
    rows = []
    for index, problem in enumerate(problems):
        rng = np.random.default_rng([seed, index])
        qs = rng.uniform(lower, upper, size=(configurations, robot.dof))
        compiled.set_obstacles(problem.obstacles)
        python.set_obstacles(problem.obstacles)
        free = np.array([compiled.free(q, margin, self_margin) for q in qs])
        free_qs = np.ascontiguousarray(qs[free])
        segments = [free_qs[k:k + SEGMENT] for k in range(0, len(free_qs) - SEGMENT + 1, SEGMENT)]
        segmented = SEGMENT * len(segments)
        row = {
            "problem": problem.name, "obstacles": len(problem.obstacles), "configurations": configurations,
            "free_fraction": float(free.mean()),
            "free_us": _best_per_item(lambda: [compiled.free(q, margin, self_margin) for q in qs], len(qs)),
            "free_on_free_us": _best_per_item(lambda: [compiled.free(q, margin, self_margin) for q in free_qs],
                                              len(free_qs)),
            "kernel_us": _best_per_item(lambda: compiled.first_blocked(free_qs, margin, self_margin), len(free_qs)),
        }
        if segments:
            row["segment_first_blocked_us"] = _best_per_item(
                lambda: [compiled.first_blocked(s, margin, self_margin) for s in segments], segmented)
            row["segment_batch_us"] = _best_per_item(lambda: [compiled.batch(s) for s in segments], segmented)
        row["python_overhead_us"] = row["free_on_free_us"] - row["kernel_us"]
        sample = qs[:baseline_configurations]
        baseline = [python.free(q, margin, self_margin) for q in sample]
        row["agree"] = bool(np.array_equal(baseline, free[:len(sample)]))
        row["python_free_us"] = _best_per_item(lambda: [python.free(q, margin, self_margin) for q in sample],
                                               len(sample), repeats=1)
        rows.append(row)
    return rows


def measure_plans(robot: Robot, problems: Sequence[BenchProblem], cap: float, seed: int) -> list[dict]:
    """Per problem: the compiled guidance's plan and the Python-checked one, interleaved."""
    settings = GuidanceSettings()
    guidance = JointGuidance(robot, settings)
    baseline_settings = replace(settings, path=replace(settings.path, time_limit=cap / settings.attempts))
    baseline = python_guidance(robot, baseline_settings)
    if problems:  # warm-up: imports, toppra and OMPL first calls; not counted
        _plan(guidance, problems[0], seed)
    rows = []
    for problem in problems:
        ours = _plan(guidance, problem, seed)
        theirs = _plan(baseline, problem, seed)
        theirs["hit_cap"] = theirs["failure"] == "no_path"
        rows.append({"problem": problem.name, "obstacles": len(problem.obstacles), "compiled": ours,
                     "python": theirs})
    return rows


def _plan(guidance: JointGuidance, problem: BenchProblem, seed: int) -> dict:
    began = time.perf_counter()
    try:
        plan = guidance.plan(problem.start, JointTarget(tuple(problem.goal)), problem.obstacles, seed)
    except GuidanceError as error:
        return {"ok": False, "time_ms": 1e3 * (time.perf_counter() - began), "failure": error.reason,
                "checks": None}
    return {"ok": True, "time_ms": 1e3 * plan.time_s, "failure": None, "checks": plan.checks,
            "duration_s": plan.trajectory.duration, "waypoints": int(len(plan.trajectory.waypoints))}


def _percentile(values: Sequence[float], q: float) -> float:
    return float(np.percentile(np.asarray(values, dtype=float), q)) if len(values) else math.nan


def summarize_checks(checks: Sequence[dict]) -> dict:
    """Medians over scenes, and the ratios."""
    def median(key: str) -> float:
        values = [row[key] for row in checks if key in row]
        return statistics.median(values) if values else math.nan

    check = {key: median(key) for key in ("free_us", "free_on_free_us", "segment_first_blocked_us",
                                          "segment_batch_us", "kernel_us", "python_overhead_us",
                                          "python_free_us")}
    check["ratio_python_over_free"] = check["python_free_us"] / check["free_us"]
    check["ratio_python_over_segment"] = check["python_free_us"] / check["segment_first_blocked_us"]
    check["agree"] = all(row["agree"] for row in checks)
    check["obstacles_min"] = min((row["obstacles"] for row in checks), default=0)
    check["obstacles_max"] = max((row["obstacles"] for row in checks), default=0)
    return check


def summarize_plans(plans: Sequence[dict]) -> dict:
    """Medians and 95th percentiles over problems, and the ratios."""
    plan: dict = {}
    for side in ("compiled", "python"):
        times = [row[side]["time_ms"] for row in plans]
        plan[side] = {"median_ms": statistics.median(times) if times else math.nan,
                      "p95_ms": _percentile(times, 95), "solved": sum(row[side]["ok"] for row in plans),
                      "problems": len(plans)}
    plan["python"]["hit_cap"] = sum(row["python"]["hit_cap"] for row in plans)
    plan["ratio_median"] = plan["python"]["median_ms"] / plan["compiled"]["median_ms"]
    plan["ratio_p95"] = plan["python"]["p95_ms"] / plan["compiled"]["p95_ms"]
    both = [row for row in plans if row["compiled"]["ok"] and row["python"]["ok"]]
    plan["same_checks"] = sum(row["compiled"]["checks"] == row["python"]["checks"] for row in both)
    plan["both_solved"] = len(both)
    plan["median_per_problem_ratio"] = (statistics.median(row["python"]["time_ms"] / row["compiled"]["time_ms"]
                                                          for row in both) if both else math.nan)
    return plan


def _loadavg() -> list[float]:
    with open("/proc/loadavg", encoding="ascii") as handle:
        return [float(v) for v in handle.read().split()[:3]]


def print_report(result: dict) -> None:
    c, p = result["summary"]["checks"], result["summary"]["plans"]
    conditions = result["conditions"]
    print(f"Guidance benchmark (issue 19, item 6): {conditions['problems']} MBM Panda problems "
          f"({conditions['per_type']} per type, variant {conditions['variant']}; {len(conditions['skipped'])} "
          f"invalid skipped), {c['obstacles_min']}-{c['obstacles_max']} boxes and cylinders per scene, "
          f"built-in Panda ({conditions['spheres']} spheres, {conditions['pairs']} self pairs); "
          f"{conditions['cpus']} CPUs, load average {conditions['load_start'][0]:.2f} at start, "
          f"{conditions['load_end'][0]:.2f} at end; seed {conditions['seed']}, baseline cap {conditions['cap_s']} s")
    print()
    print("| check, per configuration (median over scenes) | compiled | plain Python | Python / compiled | target |")
    print("|---|---|---|---|---|")
    py = c["python_free_us"]
    print(f"| `free`, one call per configuration | {c['free_us']:.2f} µs | {py:.0f} µs | "
          f"{c['ratio_python_over_free']:.0f}× | ≤ {ISSUE_TARGETS['check_us']:.0f} µs |")
    print(f"| `first_blocked`, segments of {SEGMENT} free configurations | {c['segment_first_blocked_us']:.2f} µs | "
          f"{py:.0f} µs | {c['ratio_python_over_segment']:.0f}× | < `free` |")
    print(f"| `batch` (all clearances), segments of {SEGMENT} | {c['segment_batch_us']:.2f} µs | | | |")
    print(f"| kernel alone (validity, free configurations) | {c['kernel_us']:.2f} µs | | | |")
    print(f"| Python call overhead of `free` | {c['python_overhead_us']:.2f} µs | | | |")
    print(f"Checks agree (compiled vs Python, same configurations): {c['agree']}.")
    if p is not None:
        _print_plans(p, result["plans"])


def _print_plans(p: dict, plans: Sequence[dict]) -> None:
    lower_bound = ">= " if p["python"]["hit_cap"] else ""
    print()
    print("| new goal → full plan (`JointGuidance.plan`) | compiled | plain Python | Python / compiled | target |")
    print("|---|---|---|---|---|")
    co, pp = p["compiled"], p["python"]
    print(f"| median | {co['median_ms']:.1f} ms | {lower_bound}{pp['median_ms']:.0f} ms | "
          f"{lower_bound}{p['ratio_median']:.0f}× | ≤ {ISSUE_TARGETS['plan_median_ms']:.0f} ms |")
    print(f"| 95th percentile | {co['p95_ms']:.1f} ms | {lower_bound}{pp['p95_ms']:.0f} ms | "
          f"{lower_bound}{p['ratio_p95']:.0f}× | ≤ {ISSUE_TARGETS['plan_p95_ms']:.0f} ms |")
    print(f"| solved | {co['solved']}/{co['problems']} | {pp['solved']}/{pp['problems']} "
          f"({pp['hit_cap']} hit the cap) | | |")
    print()
    print(f"Solved by both: {p['both_solved']}, of them with the same number of checks (same path): {p['same_checks']}; "
          f"median per-problem ratio {p['median_per_problem_ratio']:.0f}×.")
    slow = sorted(plans, key=lambda row: -row["compiled"]["time_ms"])[:5]
    print("Slowest compiled plans: " + ", ".join(
        f"{row['problem']} {row['compiled']['time_ms']:.0f} ms"
        f"{'' if row['compiled']['ok'] else ' (' + str(row['compiled']['failure']) + ')'}" for row in slow))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", type=int, default=3, help="valid problems per type (7 types)")
    parser.add_argument("--variant", choices=("as-posed", "object-removed"), default="object-removed")
    parser.add_argument("--cap", type=float, default=20.0, help="baseline OMPL time per problem [s]")
    parser.add_argument("--configurations", type=int, default=512, help="random configurations per scene")
    parser.add_argument("--baseline-configurations", type=int, default=64,
                        help="of those, checked by the Python baseline")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--skip-plans", action="store_true", help="check times only")
    parser.add_argument("--json", action="store_true", help="print one JSON object with every measurement")
    args = parser.parse_args(argv)
    load_start = _loadavg()
    robot = load_robot("panda")
    problems, skipped = load_cases(args.problems, args.variant)
    path = GuidanceSettings().path
    planning = robot.planning_robot   # the spheres guidance checks on among shapes
    checks = measure_checks(planning, problems, path.margin, path.self_margin, args.configurations,
                            args.baseline_configurations, args.seed)
    plans = [] if args.skip_plans else measure_plans(robot, problems, args.cap, args.seed)
    conditions = {"problems": len(problems), "per_type": args.problems, "variant": args.variant,
                  "skipped": skipped, "spheres": len(planning.collision_spheres),
                  "pairs": len(planning.self_collision_pairs), "cpus": os.cpu_count(), "seed": args.seed,
                  "cap_s": args.cap, "margin": path.margin, "self_margin": path.self_margin,
                  "resolution": path.resolution, "planner": path.planner, "load_start": load_start,
                  "load_end": _loadavg()}
    summary = {"checks": summarize_checks(checks), "plans": summarize_plans(plans) if plans else None}
    result = {"conditions": conditions, "summary": summary, "checks": checks, "plans": plans}
    if args.json:
        print(json.dumps(result))
    else:
        print_report(result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
