"""Static vs dynamic fabrics on seeded scenarios of the paper's Experiments 1-5.

    .venv/bin/python bench/compare_planners.py [--runs 50] [--experiments 1 2a 2b 3]

Runs each scenario (``dynfab.experiments``) with every planner the experiment compares,
sequentially in one process, and prints success, collisions, and the means of clearance,
summed error, time to goal and solver time. Clearance, summed error and time to goal are
averaged over the runs that all planners completed successfully (as in the paper). This is
the quick check behind the README's table; the full experiment runner (parallel, resumable,
with plots) is separate work.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from dynfab.experiments import exp1, exp2, exp3, exp4, exp5
from dynfab.metrics import Metrics
from dynfab.runner import run_scenario
from dynfab.scenario import scenario_from_dict

EXPERIMENTS: dict[str, tuple[Callable[[int, str], dict[str, Any]], tuple[str, ...]]] = {
    "1": (exp1.scenario, ("static-fabric",)),
    "2a": (exp2.analytic_scenario, ("static-fabric", "dynamic-fabric")),
    "2b": (exp2.rrt_scenario, ("static-fabric", "dynamic-fabric")),
    "3": (exp3.scenario, ("static-fabric", "dynamic-fabric")),
    "4": (exp4.scenario, ("static-fabric",)),
    "5": (exp5.scenario, ("static-fabric",)),
}


def _mean(values: list[float | None]) -> str:
    kept = [v for v in values if v is not None]
    return f"{np.mean(kept):.4f}" if kept else "-"


def compare(name: str, runs: int) -> None:
    make, planners = EXPERIMENTS[name]
    results: dict[str, list[Metrics]] = {p: [] for p in planners}
    start = time.perf_counter()
    for seed in range(runs):
        for planner in planners:
            results[planner].append(run_scenario(scenario_from_dict(make(seed, planner))).metrics)
        print(f"\r  experiment {name}: {seed + 1}/{runs}", end="", file=sys.stderr)
    print(file=sys.stderr)
    both = [i for i in range(runs) if all(results[p][i].success for p in planners)]
    print(f"Experiment {name} ({runs} runs, {time.perf_counter() - start:.0f} s)")
    print(f"  {'planner':<15} {'success':>8} {'collisions':>10} {'clearance':>10} {'summed err':>10} "
          f"{'t goal':>8} {'solver ms':>10}")
    for planner, metrics in results.items():
        print(f"  {planner:<15} {sum(m.success for m in metrics):>8} {sum(m.collision for m in metrics):>10} "
              f"{_mean([metrics[i].clearance for i in both]):>10} {_mean([metrics[i].summed_error for i in both]):>10} "
              f"{_mean([metrics[i].time_to_goal for i in both]):>8} {_mean([m.solver_time_ms for m in metrics]):>10}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--experiments", nargs="+", choices=sorted(EXPERIMENTS), default=sorted(EXPERIMENTS))
    args = parser.parse_args(argv)
    for name in args.experiments:
        compare(name, args.runs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
