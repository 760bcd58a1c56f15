"""What the Panda's self-collision pairs cost per fabric step (issue 19).

The static fabric of ``bench_planner.py``'s scene (5 sphere obstacles, 2 boxes, a pose
goal) is built for the built-in Panda with its pairs, with no pairs (the baseline), and,
with ``--previous FILE``, with the pairs of another ``panda_spheres.py`` (e.g. the table
before a change: ``git show REV:dynfab/robots/panda_spheres.py > old.py``). The planners
are timed in interleaved rounds on the same states, so that the machine's load, which
changes while the benchmark runs, weighs on all of them alike; the result is the median
step time of each and its ratio to the baseline's.

    DYNFAB_BACKEND=vm .venv/bin/python bench/bench_self_pairs.py [--previous old.py] [--steps 2000]
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import os
import statistics
import time
from pathlib import Path

import numpy as np

from dynfab.fabric.leaves.orientation import OrientationGoalConfig
from dynfab.fabric.parameters import ShapeSlots
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots.builtin import panda_robot
from dynfab.robots.robot import Robot

Q0 = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])
ROUND = 50


def scene_planner(robot: Robot) -> FabricPlanner:
    """The static fabric of bench_planner.py's scene for ``robot``, its parameters set."""
    goals = (GoalConfig(link="panda_hand"), OrientationGoalConfig(link="panda_hand"))
    planner = FabricPlanner(robot, PlannerConfig(goals=goals, obstacle_slots=5, shape_slots=ShapeSlots(box=2)))
    parameters = planner.parameters
    parameters.goal_position[0][:] = [0.5, -0.4, 0.3]
    parameters.goal_position[1][:] = goals[1].target(np.diag([1.0, -1.0, -1.0]))
    parameters.boxes.position[:] = [[0.5, 0.3, 0.2], [0.3, -0.5, 0.6]]
    parameters.boxes.orientation[:] = [1.0, 0.0, 0.0, 0.0]
    parameters.boxes.dimensions[:] = [0.2, 0.3, 0.4]
    parameters.obstacle_position[:] = np.random.default_rng(0).uniform([-0.6, -0.8, 0.05], [0.8, 0.8, 1.0], (5, 3))
    parameters.obstacle_radius[:] = 0.15
    return planner


def previous_pairs(path: Path) -> tuple[tuple[int, int], ...]:
    """``PANDA_FITTED_PAIRS`` of another ``panda_spheres.py`` (same spheres expected)."""
    spec = importlib.util.spec_from_file_location("previous_panda_spheres", path)
    if spec is None or spec.loader is None:
        raise ValueError(f"--previous: cannot load {path}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return tuple(module.PANDA_FITTED_PAIRS)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--previous", type=Path, help="another panda_spheres.py whose pairs to time too")
    parser.add_argument("--steps", type=int, default=2000)
    args = parser.parse_args()
    robot = panda_robot("fitted")
    variants = {f"built-in ({len(robot.self_collision_pairs)} pairs)": robot,
                "no pairs (baseline)": dataclasses.replace(robot, self_collision_pairs=())}
    if args.previous is not None:
        pairs = previous_pairs(args.previous)
        variants[f"previous ({len(pairs)} pairs)"] = dataclasses.replace(robot, self_collision_pairs=pairs)
    planners = {name: scene_planner(variant) for name, variant in variants.items()}
    rng = np.random.default_rng(1)
    states = [(Q0 + rng.normal(0, 0.01, 7), rng.normal(0, 0.1, 7)) for _ in range(args.steps)]
    times: dict[str, list[float]] = {name: [] for name in planners}
    for start in range(0, args.steps, ROUND):
        for name, planner in planners.items():
            for q, qdot in states[start:start + ROUND]:
                t0 = time.perf_counter()
                out = planner.compute(q, qdot)
                times[name].append(time.perf_counter() - t0)
                if not np.isfinite(out).all():
                    raise RuntimeError(f"{name}: non-finite command")
    baseline = statistics.median(times["no pairs (baseline)"])
    print(f"backend {next(iter(planners.values())).backend}, {args.steps} steps, load {os.getloadavg()[0]:.1f}")
    for name, series in times.items():
        median = statistics.median(series)
        print(f"{name:<28} {1e3 * median:.3f} ms a step, {median / baseline:.2f}x the baseline")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
