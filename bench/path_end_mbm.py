"""Issue 19, item 1: the end of a path goal, guided, on MotionBenchMaker scenes (one JSON
line per run on stdout, a summary on stderr):

    .venv/bin/python bench/path_end_mbm.py --skip 16 --per-type 2

Each problem (``object-removed``, the valid ones; ``--skip`` problems of each type skipped,
then ``--per-type`` taken) becomes a path goal: the built-in Panda's hand follows a
straight spline from where it is at the problem's start to where it is at the problem's
goal configuration, at 0.25 m/s (at least 2 s), and the run lasts 12 s more. Such a line
mostly cuts through a shelf board or a box wall. Each scene is run twice: guidance on (the
default: the fabric follows the line, guidance plans to its end once its time is over) and
``guidance: false`` (the fabric alone). A run *ends* when the hand is within
:data:`TOLERANCE` of the path's end at the end of the run (``final_distance``) and the
recording is clear on Franka's meshes (``dynfab check``: no collision, no self-collision, no
joint outside its limits). No constant here was chosen by looking at results.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import numpy as np

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.problem_run import run_case
from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES, load_problems
from dynfab.benchmarks.mbm.variants import Case, prepare_case
from dynfab.robots import load_robot

#: the hand's speed along the line [m/s], the shortest path time [s], the time after it [s]
SPEED, SHORTEST, AFTER = 0.25, 2.0, 12.0
#: reached: the hand this close to the path's end at the end of the run [m]
TOLERANCE = 0.02


def path_mapping(case: Case, guidance: bool) -> dict[str, Any]:
    """``case``'s scenario with its joint goal replaced by the straight path of the hand
    from its start position to its goal position (module docstring)."""
    kinematics = load_robot("panda").kinematics
    mapping = case.mapping
    start = np.asarray(kinematics.position(np.asarray(mapping["initial_state"]["q"]), "panda_hand")).ravel()
    end = np.asarray(kinematics.position(np.asarray(mapping["goal"][0]["position"]), "panda_hand")).ravel()
    duration = round(max(SHORTEST, float(np.linalg.norm(end - start)) / SPEED), 2)
    path = {"type": "path", "link": "panda_hand", "tolerance": TOLERANCE,
            "trajectory": {"type": "spline", "waypoints": [start.round(4).tolist(), end.round(4).tolist()],
                           "duration": duration}}
    return {**mapping, "goal": [path], "duration": duration + AFTER, "guidance": guidance}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip", type=int, default=16, help="problems of each type skipped (default 16)")
    parser.add_argument("--per-type", type=int, default=2, help="problems of each type run (default 2)")
    args = parser.parse_args()
    robot = franka()
    counts: dict[bool, list[int]] = {True: [0, 0, 0], False: [0, 0, 0]}   # ended, mesh contacts, runs
    for problem in load_problems(PROBLEM_TYPES, per_type=args.per_type, skip=args.skip):
        case = prepare_case(problem, "object-removed", robot)
        if case.invalid is not None:
            print(json.dumps({"problem": f"{problem.type}/{problem.number:04d}", "invalid": case.invalid}), flush=True)
            continue
        for guidance in (True, False):
            outcome = run_case(path_mapping(case, guidance))
            metrics, check = outcome["metrics"] or {}, outcome["check"] or {}
            clear = bool(check.get("ok"))
            ended = clear and metrics.get("final_distance", np.inf) < TOLERANCE
            counts[guidance][0] += ended
            counts[guidance][1] += bool(check) and not clear   # a collision, self-collision or limit
            counts[guidance][2] += 1
            print(json.dumps({"problem": f"{problem.type}/{problem.number:04d}", "guidance": guidance,
                              "ended": ended, "clear_on_meshes": clear, "refused": outcome["refused"],
                              **{key: metrics.get(key) for key in ("final_distance", "guided", "plans", "fallbacks",
                                                                   "plan_time_ms")},
                              "wall_time_s": round(outcome["wall_time_s"], 1)}), flush=True)
    for guidance, (ended, contacts, runs) in counts.items():
        print(f"guidance {'on ' if guidance else 'off'}: path end reached {ended}/{runs}, "
              f"runs not clear on the meshes {contacts}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
