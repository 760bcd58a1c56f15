"""Stress benchmark: 10⁵ seeded adversarial planner calls (dynfab/experiments/adversarial.py)
over Panda, Boxer and Boxer+Panda, static and dynamic; every command must be finite and
within the robot's acceleration limits.

    .venv/bin/python bench/bench_bounded_output.py [--calls 100000] [--seed 0] [--json]

Prints one row per case and exits 1 if any command was non-finite or beyond a limit.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time

from dynfab.experiments.adversarial import CASES, run_case


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=100_000, help="calls in total, split over the cases")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args()
    per_case = max(1, -(-args.calls // len(CASES)))  # at least --calls in total
    rows = []
    for index, (robot, dynamic) in enumerate(CASES):
        start = time.perf_counter()
        statistics = run_case(robot, dynamic, per_case, seed=args.seed + index)
        rows.append({**dataclasses.asdict(statistics), "wall_s": time.perf_counter() - start})
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        print(f"{'case':<22}{'calls':>8}{'non-finite':>12}{'beyond':>8}{'max |a|/a_max':>15}{'fallbacks':>11}")
        for row in rows:
            print(f"{row['case']:<22}{row['calls']:>8}{row['non_finite']:>12}{row['beyond_limits']:>8}"
                  f"{row['max_acceleration_ratio']:>15.6f}{row['fallbacks']:>11}")
    return 0 if all(row["non_finite"] == 0 and row["beyond_limits"] == 0 for row in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
