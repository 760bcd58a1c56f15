"""Benchmark of the planner, side by side with the reference package ``fabrics`` 0.10.0 in
the same run when it is installed in ``.venv-reference`` (``bash bench/setup_reference.sh``):

1. issue 21 (bench/bench_same_model.py): the planner ``dynfab run`` builds for an
   experiment-1 scene, against the reference on the SAME robot model, both ways: the
   reference's model (5 spheres at link origins, 2 pairs) given to ours, and our built-in
   model (75 spheres, 268 pairs) given to the reference;
2. the Panda static fabric with 1, 5 and 10 sphere obstacles, self-collision and joint
   limits, ours (default backend) and the reference's, both on the reference's model;
3. ours only: dynamic fabrics, a scene with boxes and a pose goal, the two sphere models
   of issue 9, and the backends of issue 12 (bench/bench_speed.py): VM, C, exported C,
   batched, cold starts.

    .venv/bin/python bench/bench_planner.py [--spheres 1 5 10] [--steps 2000] [--json]

Each build is a cold start in a fresh process (the VM builds cache nothing; the C
measurements of sections 1 and 2 and of the backends use a fresh cache folder, first cold,
then warm). Times are wall-clock medians of ``FabricPlanner.compute`` from Python,
including input checks. The machine's load average is printed with the numbers: they
belong to this machine at this moment.
"""

from __future__ import annotations

import argparse
import json
import statistics
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

BENCH_DIR = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCH_DIR))

from bench_same_model import reference_model_robot, same_model_measurements, summary  # noqa: E402
from bench_speed import speed_measurements  # noqa: E402
from reference import REFERENCE_MISSING_MESSAGE, run_reference  # noqa: E402

PANDA_URDF = BENCH_DIR.parent / "dynfab" / "robots" / "data" / "panda.urdf"
Q0 = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])


def measure_ours(spheres: int, steps: int, dynamic: bool = False, scene: bool = False,
                 sphere_model: str = "fitted") -> dict:
    """Build the planner and time ``compute`` (run in a fresh interpreter by :func:`main`).
    ``dynamic``: the dynamic-fabric planner (goal and obstacles with velocities and
    accelerations), with moving obstacles. ``scene``: also 2 box slots and a pose goal (the
    hand's position and all three of its axes). ``sphere_model``: the Panda's collision
    spheres, ``"fitted"`` (the default ``panda``), ``"hand-written"`` (the default before
    issue 9) or ``"reference"`` (the reference's model, bench/bench_same_model.py)."""
    from dynfab.fabric.leaves.orientation import OrientationGoalConfig
    from dynfab.fabric.parameters import ShapeSlots
    from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
    from dynfab.robots.builtin import panda_robot

    start = time.perf_counter()
    robot = panda_robot(sphere_model) if sphere_model != "reference" else reference_model_robot(panda_robot("fitted"))
    goals = (GoalConfig(link="panda_hand"),) + ((OrientationGoalConfig(link="panda_hand"),) if scene else ())
    planner = FabricPlanner(robot, PlannerConfig(goals=goals, obstacle_slots=spheres, dynamic=dynamic,
                                                 shape_slots=ShapeSlots(box=2 if scene else 0)))
    build_s = time.perf_counter() - start
    rng = np.random.default_rng(0)
    planner.parameters.goal_position[0][:] = [0.5, -0.4, 0.3]
    if scene:
        planner.parameters.goal_position[1][:] = goals[1].target(np.diag([1.0, -1.0, -1.0]))
        boxes = planner.parameters.boxes
        boxes.position[:] = [[0.5, 0.3, 0.2], [0.3, -0.5, 0.6]]
        boxes.orientation[:] = [1.0, 0.0, 0.0, 0.0]
        boxes.dimensions[:] = [0.2, 0.3, 0.4]
    planner.parameters.obstacle_position[:] = rng.uniform([-0.6, -0.8, 0.05], [0.8, 0.8, 1.0], size=(spheres, 3))
    planner.parameters.obstacle_radius[:] = 0.15
    if dynamic:
        planner.parameters.obstacle_velocity[:] = rng.normal(0, 0.2, size=(spheres, 3))
        planner.parameters.goal_velocity[0][:] = [0.05, 0.0, 0.0]
    states = [(Q0 + rng.normal(0, 0.01, 7), rng.normal(0, 0.1, 7)) for _ in range(steps)]
    for q, qdot in states[:20]:
        planner.compute(q, qdot)
    times, non_finite = [], 0
    for q, qdot in states:
        t0 = time.perf_counter()
        out = planner.compute(q, qdot)
        times.append(time.perf_counter() - t0)
        non_finite += not np.isfinite(out).all()
    return {"spheres": spheres, "backend": planner.backend, "build_s": build_s, "step_ms_median": 1e3 * statistics.median(times),
            "step_ms_mean": 1e3 * statistics.fmean(times), "n_instructions": planner.n_instructions,
            "nan_fraction": non_finite / steps, "robot_spheres": len(robot.collision_spheres),
            "robot_pairs": len(robot.self_collision_pairs)}


def _ours_in_fresh_process(spheres: int, steps: int, dynamic: bool = False, scene: bool = False,
                           sphere_model: str = "fitted", cache: str | None = None) -> dict:
    code = ("import json, sys; sys.path.insert(0, %r); from bench_planner import measure_ours; "
            "print(json.dumps(measure_ours(%d, %d, %r, %r, %r)))"
            % (str(BENCH_DIR), spheres, steps, dynamic, scene, sphere_model))
    env = dict(os.environ) if cache is None else {**os.environ, "DYNFAB_CACHE_DIR": cache}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spheres", type=int, nargs="+", default=[1, 5, 10])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--json", action="store_true", help="print one JSON object with every measurement")
    args = parser.parse_args(argv)
    if args.json:
        print(json.dumps(_all_measurements(args.spheres, args.steps)))
        return 0
    same = same_model_measurements(args.steps)
    if same.get("missing"):
        print(REFERENCE_MISSING_MESSAGE + " (the comparisons with it are left out)")
    else:
        print("\n".join(summary(same)))
        print()
        _print_sweep(args.spheres, args.steps)
        print()
    print("ours only from here on, the built-in Panda (75 spheres, 268 pairs), default backend, cache "
          f"{os.environ.get('DYNFAB_CACHE_DIR', '~/.cache/dynfab')} (build = load when it holds the library).")
    print("dynamic fabrics (moving goal and obstacles):")
    for n in args.spheres:
        dyn = _ours_in_fresh_process(n, args.steps, dynamic=True)
        print(f"{n:>7} spheres | build {dyn['build_s']:.2f} s | step median {dyn['step_ms_median']:.4f} ms | "
              f"{dyn['n_instructions']} SX instructions")
    print()
    print("a real scene: 5 spheres + 2 boxes + pose goal vs 5 spheres + position goal (static, same run):")
    plain = _ours_in_fresh_process(5, args.steps)
    scene = _ours_in_fresh_process(5, args.steps, scene=True)
    print(f"  step median {scene['step_ms_median']:.4f} vs {plain['step_ms_median']:.4f} ms "
          f"({scene['step_ms_median'] / plain['step_ms_median']:.2f}x) | {scene['n_instructions']} vs "
          f"{plain['n_instructions']} SX instructions | build {scene['build_s']:.2f} vs {plain['build_s']:.2f} s")
    print()
    _print_sphere_models(_sphere_models(args.steps))
    print()
    _print_speed(speed_measurements(args.steps))
    return 0


def _print_sweep(spheres: list[int], steps: int) -> None:
    """Static fabric, 1/5/10 seeded spheres, ours and the reference on the reference's model."""
    print(f"static fabric, position goal, {'/'.join(map(str, spheres))} seeded spheres, both on the reference's model (5 spheres of 0.08 m "
          "at link origins, 2 pairs); ours: default backend, fresh cache (build = symbolic build + compile); "
          f"load average {os.getloadavg()[0]:.2f}:")
    header = f"{'spheres':>7} | {'build [s]':>17} | {'step median [ms]':>21} | {'SX instructions':>19} | step ratio ref/ours"
    print(header)
    print("-" * len(header))
    with tempfile.TemporaryDirectory(prefix="dynfab-bench-sweep-") as cache:
        for n in spheres:
            ours = _ours_in_fresh_process(n, steps, sphere_model="reference", cache=cache)
            ref = run_reference(n, min(steps, 1000), PANDA_URDF)
            ratio = ref["step_ms_median"] / ours["step_ms_median"]
            print(f"{n:>7} | {ours['build_s']:>7.2f} vs {ref['setup_s'] + ref['build_s']:>6.2f} | "
                  f"{ours['step_ms_median']:>9.4f} vs {ref['step_ms_median']:>8.4f} | {ours['n_instructions']:>8} vs "
                  f"{ref['n_instructions']:>7} | {ratio:>6.1f}x")
    print("(ours vs reference fabrics 0.10.0; NaN fraction ours 0 by construction)")


def _all_measurements(spheres: list[int], steps: int) -> dict:
    """Every number of the printed report, for machines."""
    same = same_model_measurements(steps)
    sweep = []
    with tempfile.TemporaryDirectory(prefix="dynfab-bench-sweep-") as cache:
        for n in spheres:
            sweep.append({"spheres": n, "model": "reference",
                          "ours": _ours_in_fresh_process(n, steps, sphere_model="reference", cache=cache),
                          "reference": run_reference(n, min(steps, 1000), PANDA_URDF)})
    return {"same_model": same, "sweep": sweep, "sphere_models": _sphere_models(steps),
            "speed": speed_measurements(steps)}


def _sphere_models(steps: int, rounds: int = 3) -> dict:
    """Issue 9: the scene (5 spheres, 2 boxes, pose goal; static) with the Panda's fitted
    spheres and with the hand-written ones, alternating in fresh processes; the ratio of
    the medians of each model's per-round medians."""
    runs: dict[str, list[dict]] = {"fitted": [], "hand-written": []}
    for _ in range(rounds):
        for model in runs:
            runs[model].append(_ours_in_fresh_process(5, steps, scene=True, sphere_model=model))
    result = {model: {**measured[0], "step_ms_median": statistics.median(m["step_ms_median"] for m in measured),
                      "step_ms_rounds": [m["step_ms_median"] for m in measured]}
              for model, measured in runs.items()}
    result["ratio"] = result["fitted"]["step_ms_median"] / result["hand-written"]["step_ms_median"]
    return result


def _print_sphere_models(models: dict) -> None:
    fitted, written = models["fitted"], models["hand-written"]
    print("issue 9, the Panda's collision spheres: the scene above with the fitted spheres (default) vs the "
          "hand-written ones (before), same run, 3 alternating rounds:")
    for name, m in (("fitted", fitted), ("hand-written", written)):
        rounds = ", ".join(f"{t:.4f}" for t in m["step_ms_rounds"])
        print(f"  {name:<13} {m['robot_spheres']:>2} spheres, {m['robot_pairs']:>2} pairs | step median "
              f"{m['step_ms_median']:.4f} ms (rounds {rounds}) | {m['n_instructions']} SX instructions")
    print(f"  fitted / hand-written = {models['ratio']:.2f}x (target <= 1.5x)")


def _print_speed(speed: dict) -> None:
    """The issue-12 report: backends side by side, with the targets (ours only: the
    comparison with the reference on the same robot model is the first section)."""
    c_us = speed["c"]["step_us_median"]
    print(f"backends (issue 12), ours only, the built-in Panda (75 spheres, 268 pairs), 5 spheres, self-collision, "
          f"joint limits, static unless said; {speed['cpus']} CPUs, load average {speed['load_before'][0]:.2f} "
          f"before, {speed['load_after'][0]:.2f} after:")
    rows = [("VM step from Python", speed["vm"]["step_us_median"], None),
            ("C step from Python", c_us, "<= 10 us"),
            ("exported C step", speed["exported"]["step_us"], "<= 5 us"),
            ("C dynamic step", speed["c_dynamic"]["step_us_median"], "<= 1.3x static"),
            ("C Boxer+Panda 8 spheres", speed["c_boxer_panda_8"]["step_us_median"], "<= 20 us"),
            ("batch, 1 thread, per env-step", speed["batch_1000_1"]["us_per_env_step"], None),
            (f"batch, {speed['batch_1000_cpus']['threads']} threads, per env-step",
             speed["batch_1000_cpus"]["us_per_env_step"], ">= 100000 env-steps/s")]
    for label, value, target in rows:
        print(f"  {label:<36} {value:9.2f} us{'  target ' + target if target else ''}")
    print(f"  C dynamic / static = {speed['c_dynamic']['step_us_median'] / c_us:.2f}; "
          f"batch {speed['batch_1000_cpus']['env_steps_per_s']:.0f} env-steps/s "
          f"({speed['batch_1000_1']['env_steps_per_s']:.0f} on 1 thread)")
    cold, warm = speed["c_cold_cache"], speed["c"]
    print(f"  build: VM {speed['vm']['build_s']:.2f} s; C with a cold cache {cold['build_s']:.2f} s "
          f"(symbolic build + compile, target < 60 s); C cold start with a warm cache (new process, build to "
          f"first action) {warm['first_action_s']:.3f} s (target < 0.3 s), after importing dynfab in "
          f"{warm['import_s']:.2f} s")


if __name__ == "__main__":
    sys.exit(main())
